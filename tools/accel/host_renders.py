"""End-to-end accel comparison through the host program itself (issue 16): what a user runs.

Every measurement is one whole `host` process rendering a scene (load, build, render,
write the EXR), so nothing is shared between configurations: per scene, per thread count
and integrator_pt maxDepth, `--rounds` rounds each run every configuration once, the order
rotated per round (drift in this shared machine's load hits every configuration alike).
The figure is the host's `render_ms` from --stats with `--clock cpu` (the process's CPU
time of the render: time preempted by other jobs is not counted), `build_ms` beside it.
A ratio to the first configuration is the median over rounds of first / this within the
round. Results go to --out as JSON (rewritten atomically after every finished block, and
reused on a rerun, so an interrupted run keeps what it measured); the tables are printed
at the end, with the load average at the start and at the end.

  H="/usr/bin/python3 -m tools.accel.host_renders"       # from the repository root
  $H --rounds 5 --out /tmp/acc_host.json
  $H --summarize /tmp/acc_host.json
  $H --scene living-room --threads 1 --depths 3 --rounds 3 \\
      --config "bf8=backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=8"

Configurations are "label=name=value,..." of accel_embree's parameters (the first is the
reference; default: native default, custom default, bf4/bf8 with sahBlockSize 4 and
maxLeafSize 8, the rows of plugins/accel_embree/tests/accel_embree_render_bench).
"""
import json
import math
import os
import statistics
import sys
import tempfile
import time

from tools.scenes import generate
from tools.tttools import cli, host

ROOT = host.ROOT
SHARED = os.path.abspath(os.path.join(ROOT, "..", "shared", "scenes"))
SCENES = {
    "living-room": os.path.join(SHARED, "living-room", "living-room.pbrt"),
    "bmw-m6": os.path.join(SHARED, "bmw-m6", "bmw-m6.pbrt"),
    "staircase": os.path.join(SHARED, "staircase", "staircase.pbrt"),
    "bathroom": os.path.join(SHARED, "bathroom", "bathroom.pbrt"),
    "killeroos": os.path.join(SHARED, "killeroos", "killeroo-simple.pbrt"),
    "voxel-world": None,  # tools/scenes/generate.py voxel, generated once into --voxel-dir
}
CONFIGS = [
    "native default=backend=native",
    "custom default (bf2)=backend=custom",
    "custom bf4 blk4 leaf8=backend=custom,branchingFactor=4,sahBlockSize=4,maxLeafSize=8",
    "custom bf8 blk4 leaf8=backend=custom,branchingFactor=8,sahBlockSize=4,maxLeafSize=8",
]


def parse_config(text):
    label, sep, settings = text.partition("=")
    if not sep or not label:
        sys.exit(f"host_renders: --config '{text}': expected LABEL=name=value,...")
    pairs = []
    for tok in filter(None, settings.split(",")):
        name, eq, value = tok.partition("=")
        if not eq:
            sys.exit(f"host_renders: --config '{text}': '{tok}' is not name=value")
        pairs.append((name, value))
    return label, pairs


def scene_path(name, a):
    if name not in SCENES:
        sys.exit(f"host_renders: unknown scene '{name}' (known: {', '.join(SCENES)})")
    if SCENES[name]:
        return SCENES[name]
    path = os.path.join(a.voxel_dir, "scene.json")
    if not os.path.exists(path):
        print(f"note: generating the voxel world into {a.voxel_dir}", flush=True)
        generate.main(["voxel", a.voxel_dir])
    return path


def write_atomic(path, data):
    d = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".accel_host_renders.", dir=d)
    with os.fdopen(fd, "w") as f:
        json.dump(data, f, indent=1)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def one_render(a, scene, settings, threads, depth, work):
    args = ["--quiet", "--threads", str(threads), "--spp", str(a.spp), "--res", a.res,
            "--clock", "cpu", "--seed", "1", "--set", f"integrator_pt.maxDepth={depth}"]
    for name, value in settings:
        args += ["--set", f"accel_embree.{name}={value}"]
    r = host.run(a.host, args + ["--out", os.path.join(work, "out.exr"), scene],
                 stats=os.path.join(work, "stats.json"), capture=True)
    s = r.stats
    mem = (s.get("accel") or {}).get("memory_bytes", 0)
    return {"render_ms": s["render_ms"], "build_ms": s["build_ms"], "rays": s["rays"],
            "process_wall_s": r.wall_s, "memory_bytes": mem}


def measure(a, configs):
    data = {"settings": {"rounds": a.rounds, "res": a.res, "spp": a.spp, "clock": "cpu",
                         "configs": [[lab, dict(p)] for lab, p in configs]},
            "blocks": {}}
    if os.path.exists(a.out):
        with open(a.out) as f:
            old = json.load(f)
        if old.get("settings") == data["settings"]:
            data = old
    data["load_start"] = list(os.getloadavg())
    with tempfile.TemporaryDirectory(prefix="accel_host_renders.") as work:
        for name in a.scene:
            scene = scene_path(name, a)
            for threads in a.threads:
                for depth in a.depths:
                    key = f"{name} t{threads} d{depth}"
                    if key in data["blocks"]:
                        continue
                    runs = {lab: [] for lab, _ in configs}
                    t0 = time.time()
                    for r in range(a.rounds):
                        for k in range(len(configs)):
                            lab, settings = configs[(k + r) % len(configs)]
                            runs[lab].append(one_render(a, scene, settings, threads, depth, work))
                    data["blocks"][key] = {"scene": name, "threads": threads, "depth": depth,
                                           "runs": runs, "load": list(os.getloadavg())}
                    data["load_end"] = list(os.getloadavg())
                    write_atomic(a.out, data)
                    print(f"  {key}: {time.time() - t0:.0f} s, load {os.getloadavg()[0]:.1f}",
                          flush=True)
    return data


def summarize(data):
    labels = [lab for lab, _ in data["settings"]["configs"]]
    ref = labels[0]
    st = data["settings"]
    print(f"\nhost renders ({st['res']}, {st['spp']} spp, --clock cpu), {st['rounds']} rounds "
          f"interleaved; ratio = median over rounds of {ref} render_ms / this render_ms; "
          f"load average at start {' '.join('%.1f' % x for x in data.get('load_start', []))}, "
          f"at end {' '.join('%.1f' % x for x in data.get('load_end', []))}")
    ratios = {}  # (label, mode) -> [ratio per scene]
    print(f"{'block':<24} {'configuration':<26} {'render ms':>10} {'build ms':>9} {'MiB':>8} "
          f"{'vs ' + ref:>18}")
    for key, b in data["blocks"].items():
        runs = b["runs"]
        for lab in labels:
            rr = runs[lab]
            med = statistics.median(x["render_ms"] for x in rr)
            bld = statistics.median(x["build_ms"] for x in rr)
            q = statistics.median(runs[ref][i]["render_ms"] / rr[i]["render_ms"]
                                  for i in range(len(rr)))
            mib = rr[0]["memory_bytes"] / 2**20
            print(f"{key if lab == ref else '':<24} {lab:<26} {med:10.1f} {bld:9.1f} {mib:8.1f} "
                  f"{q:17.3f}x")
            ratios.setdefault((lab, f"t{b['threads']} d{b['depth']}"), []).append(q)
    print(f"\ngeometric means over the scenes of the render-time ratios to {ref} (min):")
    for (lab, mode), qs in ratios.items():
        if lab == ref:
            continue
        g = math.exp(sum(map(math.log, qs)) / len(qs))
        print(f"  {lab:<26} {mode:<7} {g:.3f}x (min {min(qs):.3f}x, {len(qs)} scenes)")


def main():
    p = cli.parser(__doc__)
    p.add_argument("--scene", action="append", help="scene name (repeat); default all six")
    p.add_argument("--config", action="append", help="LABEL=name=value,... (repeat)")
    p.add_argument("--threads", default="1,2")
    p.add_argument("--depths", default="3,8")
    p.add_argument("--rounds", type=int, default=5)
    p.add_argument("--res", default="320x240")
    p.add_argument("--spp", type=int, default=8)
    p.add_argument("--voxel-dir", default="/tmp/tt_bench_voxel_world")
    p.add_argument("--out", default="/tmp/accel_host_renders.json")
    p.add_argument("--summarize", metavar="FILE", help="print the tables of a results file")
    a = p.parse_args()
    if a.summarize:
        with open(a.summarize) as f:
            summarize(json.load(f))
        return
    a.host = host.find(a.host)
    a.scene = a.scene or list(SCENES)
    a.threads = [int(x) for x in a.threads.split(",")]
    a.depths = [int(x) for x in a.depths.split(",")]
    configs = [parse_config(c) for c in (a.config or CONFIGS)]
    summarize(measure(a, configs))


if __name__ == "__main__":
    main()
