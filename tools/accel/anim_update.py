"""Per-frame acceleration-structure update + render time along an animated sequence, per
update method of accel_embree: build from scratch every frame (rebuild), refit every frame,
refit with a rebuild every N frames; each for the native and the custom backend.

Every measurement is one `host --sequence` process over the scene (the frames' manifest
records each frame's `update_ms` and `render_ms`); `--rounds` rounds run every
configuration once, the order rotated per round, so drift in the machine's load hits every
configuration alike. Printed per configuration: the medians over all frames of all rounds of
update ms, render ms and their sum, how many frames were built from scratch, and the
median over rounds of (rebuild's summed frame time / this configuration's), the speed-up
against rebuilding every frame with the same backend. The load average is printed at the
start and at the end; --out keeps the raw per-frame figures as JSON.

  /usr/bin/python3 -m tools.accel.anim_update --rounds 5 --frames 0:47
  /usr/bin/python3 -m tools.accel.anim_update --scene scenes/animated-cornell/scene.json \\
      --res 128x128 --spp 1 --threads 2 --out /tmp/anim_update.json
"""
import json
import os
import statistics
import sys
import tempfile

from tools.tttools import cli, host

ROOT = host.ROOT
# label -> accel_embree settings; the first of each backend is its reference (rebuild)
CONFIGS = {
    "native rebuild": [],
    "native refit": ["updateMethod=refit"],
    "native refit, rebuild every 8": ["updateMethod=refit", "refitInterval=8"],
    "custom rebuild": ["backend=custom"],
    "custom refit": ["backend=custom", "updateMethod=refit"],
    "custom refit, rebuild every 8": ["backend=custom", "updateMethod=refit", "refitInterval=8"],
    "custom refit, rebuild at SAH x1.2": ["backend=custom", "updateMethod=refit", "refitSahGrowth=1.2"],
}


def run_sequence(exe, scene, sets, args, folder):
    """The manifest's frames of one `host --sequence` run."""
    cmd = ["--quiet", "--sequence", args.frames, "--spp", str(args.spp), "--res", args.res,
           "--threads", str(args.threads), "--out-dir", folder]
    for s in sets:
        cmd += ["--set", "accel_embree." + s]
    host.run(exe, cmd + [scene], nice=args.nice, log=os.path.join(folder, "host.log"))
    with open(os.path.join(folder, "manifest.json")) as f:
        return json.load(f)["frames"]


def main(argv=None):
    p = cli.parser(__doc__)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "animated-cornell", "scene.json"))
    p.add_argument("--frames", default="0:47", help="frames A:B of the sequence (default 0:47)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--res", default="128x128")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--nice", type=int, default=None, help="run the host under nice -n NICE")
    p.add_argument("--out", help="raw per-frame figures as JSON")
    args = p.parse_args(argv)
    exe = host.find(args.host)
    labels = list(CONFIGS)
    print(f"load average at start: {os.getloadavg()}")
    frames = {k: [] for k in labels}       # per config: per round, the manifest's frames
    with tempfile.TemporaryDirectory(prefix="tt_anim_update.") as tmp:
        for r in range(args.rounds):
            order = labels[r % len(labels):] + labels[:r % len(labels)]
            for k in order:
                folder = os.path.join(tmp, f"r{r}_{labels.index(k)}")
                os.makedirs(folder)
                frames[k].append(run_sequence(exe, args.scene, CONFIGS[k], args, folder))
    print(f"load average at end: {os.getloadavg()}")
    print(f"{args.scene}: frames {args.frames}, {args.res}, {args.spp} spp, {args.threads} threads, "
          f"{args.rounds} rounds (medians over every frame of every round; wall time)")
    print(f"{'configuration':36s} {'update ms':>10s} {'render ms':>10s} {'sum ms':>9s} "
          f"{'rebuilt':>8s} {'x rebuild':>10s}")
    for k in labels:
        every = [f for run in frames[k] for f in run]
        upd = [f.get("update_ms", 0.0) for f in every]
        ren = [f["render_ms"] for f in every]
        tot = [u + v for u, v in zip(upd, ren)]
        rebuilt = sum(f.get("update") == "rebuild" for f in every)
        ref = "native rebuild" if k.startswith("native") else "custom rebuild"
        speed = statistics.median(
            sum(f.get("update_ms", 0.0) + f["render_ms"] for f in a) /
            sum(f.get("update_ms", 0.0) + f["render_ms"] for f in b)
            for a, b in zip(frames[ref], frames[k]))
        print(f"{k:36s} {statistics.median(upd):10.3f} {statistics.median(ren):10.2f} "
              f"{statistics.median(tot):9.2f} {rebuilt:4d}/{len(every):<3d} {speed:10.3f}")
    if args.out:
        tmp_out = args.out + ".tmp"
        with open(tmp_out, "w") as f:
            json.dump({"scene": args.scene, "frames": args.frames, "res": args.res, "spp": args.spp,
                       "threads": args.threads, "configs": CONFIGS, "runs": frames}, f, indent=1)
        os.replace(tmp_out, args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
