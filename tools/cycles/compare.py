"""Peer comparison of integrator_pt against Blender 3.4 Cycles (CPU) on the Cornell box and
a glossy/glass variant (benchmark, not CI; issue 4). For each scene:

  1. high-spp references: Cycles (two seeds: their difference is the noise floor of two
     independent references) and ours;
  2. accuracy: mean luminance of ours vs Cycles (relative difference) and tunetrace's rRMSE
     (tools/common/images.py: over luminance, sqrt(mean((L - R)^2 / (R^2 + 1e-3)))) of ours
     vs the Cycles reference, next to Cycles-seed-1 vs Cycles-seed-2 (what pure noise gives);
  3. speed at equal spp and depth, run back to back in this one invocation (--repeat times,
     alternating, best of each kept): wall time and samples/s of ours (host --stats
     render_ms) and of Cycles (time around its render call), plus CPU seconds and samples
     per CPU second (ours: the whole host process, scene load and EXR write included;
     Cycles: its render call). On a shared machine the CPU figures are the steadier ones.
References are reused when their files exist in --out.

Usage (from the repository root, after `ninja -C build`):
  /usr/bin/python3 -m tools.cycles.compare [--host PATH] [--res 128x128]
      [--ref-spp 1024] [--spp 64] [--depth 3] [--threads 2] [--repeat 3]
      [--sampler independent] [--out /tmp/tt_cycles]
Needs: blender (apt-get install blender), python3-openimageio, python3-numpy.
"""
import copy
import json
import os
import subprocess
import sys

from tools.common import images
from tools.tttools import cli, host

ROOT = host.ROOT
CYCLES_SCRIPT = os.path.join(ROOT, "tools", "cycles", "cycles_reference.py")


read_rgb = images.read_rgb
luminance = images.luminance
rrmse = images.rrmse


def run_ours(args, scene, spp, seed, out):
    """Renders with host; returns (render wall s, samples/s, cpu s)."""
    r = host.run(args.host, ["--spp", str(spp), "--threads", str(args.threads), "--res", args.res,
                             "--seed", str(seed), "--set", f"integrator_pt.maxDepth={args.depth}",
                             "--set", f"integrator_pt.sampler={args.sampler}",
                             "--out", out, "--quiet", "--no-db", scene], stats=out + ".json")
    wall = r.stats["render_ms"] / 1000.0
    return wall, r.stats["samples"] / wall, r.cpu_s


def run_cycles(args, scene, spp, seed, out):
    """Renders with Blender Cycles; returns (render wall s, samples/s, cpu s of the render)."""
    cmd = [args.blender, "-b", "--factory-startup", "-P", CYCLES_SCRIPT, "--", "--scene", scene,
           "--spp", str(spp), "--depth", str(args.depth), "--threads", str(args.threads),
           "--res", args.res, "--seed", str(seed), "--out", out]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    st = json.load(open(out + ".json"))
    return st["wall_s"], st["samples_per_s"], st.get("cpu_s", float("nan"))


def variants(base_path, outdir):
    """The Cornell box as is, and a glossy/glass variant: tall block smooth glass (ior 1.5),
    short block a GGX conductor with Fresnel ~1 (eta 1, k 1000: Cycles' Glossy BSDF has no
    Fresnel) tinted 0.8, alpha 0.05."""
    base = json.load(open(base_path))
    glossy = copy.deepcopy(base)
    glossy["materials"]["glass"] = {"type": "dielectric", "ior": 1.5, "alpha": 0.0}
    glossy["materials"]["gloss"] = {"type": "conductor", "eta": [1, 1, 1], "k": [1000, 1000, 1000],
                                    "alpha": 0.05, "specular": [0.8, 0.8, 0.8]}
    for m in glossy["meshes"]:
        if m["name"] == "tall_block":
            m["material"] = "glass"
        elif m["name"] == "short_block":
            m["material"] = "gloss"
    path = os.path.join(outdir, "cornell-glossy.json")
    json.dump(glossy, open(path, "w"), indent=1)
    return [("cornell", os.path.abspath(base_path)), ("cornell-glossy", path)]


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--blender", default="blender")
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes", "cornell-box", "scene.json"))
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--spp", type=int, default=64, help="equal-spp timing run")
    ap.add_argument("--depth", type=int, default=3, help="tunetrace maxDepth (Cycles bounces = depth - 1)")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default="/tmp/tt_cycles")
    ap.add_argument("--only", default=None, help="run one variant (cornell or cornell-glossy)")
    ap.add_argument("--repeat", type=int, default=3, help="equal-spp timing runs per renderer")
    ap.add_argument("--sampler", default="independent", help="integrator_pt.sampler")
    args = ap.parse_args()
    args.host = host.find(args.host)
    os.makedirs(args.out, exist_ok=True)
    w, h = (int(x) for x in args.res.split("x"))

    rows = []
    for name, scene in variants(args.scene, args.out):
        if args.only and name != args.only:
            continue
        p = lambda tag: os.path.join(args.out, f"{name}_d{args.depth}_{tag}.exr")
        print(f"[{name}] references at {args.ref_spp} spp, {args.res}, depth {args.depth} ...", flush=True)
        for tag, seed in (("cycles_ref1", 1), ("cycles_ref2", 2)):
            if not os.path.exists(p(tag)):
                run_cycles(args, scene, args.ref_spp, seed, p(tag))
        if not os.path.exists(p("ours_ref")):
            run_ours(args, scene, args.ref_spp, 1, p("ours_ref"))
        print(f"[{name}] equal-spp timing at {args.spp} spp, {args.repeat} runs each ...", flush=True)
        best = lambda runs: min(runs, key=lambda r: r[0])
        ours_runs, cyc_runs = [], []
        for _ in range(args.repeat):
            ours_runs.append(run_ours(args, scene, args.spp, 7, p("ours_eq")))
            cyc_runs.append(run_cycles(args, scene, args.spp, 7, p("cycles_eq")))
        ow, osps, ocpu = best(ours_runs)
        cw, csps, ccpu = best(cyc_runs)
        ocpu, ccpu = min(r[2] for r in ours_runs), min(r[2] for r in cyc_runs)
        c1, c2, ours = read_rgb(p("cycles_ref1")), read_rgb(p("cycles_ref2")), read_rgb(p("ours_ref"))
        oeq, ceq = read_rgb(p("ours_eq")), read_rgb(p("cycles_eq"))
        lc, lo = luminance(c1).mean(), luminance(ours).mean()
        rows.append({
            "scene": name, "depth": args.depth, "res": args.res, "ref_spp": args.ref_spp,
            "mean_lum_cycles": lc, "mean_lum_ours": lo, "mean_lum_rel_diff": (lo - lc) / lc,
            "rrmse_ours_ref_vs_cycles_ref": rrmse(ours, c1),
            "rrmse_cycles_ref2_vs_ref1": rrmse(c2, c1),
            "spp": args.spp, "rrmse_ours_eq": rrmse(oeq, c1), "rrmse_cycles_eq": rrmse(ceq, c1),
            "ours_wall_s": ow, "ours_samples_per_s": osps, "ours_cpu_s": ocpu,
            "cycles_wall_s": cw, "cycles_samples_per_s": csps, "cycles_cpu_s": ccpu,
            "speed_ratio": osps / csps,
            "ours_samples_per_cpu_s": w * h * args.spp / ocpu,
            "cycles_samples_per_cpu_s": w * h * args.spp / ccpu,
            "sampler": args.sampler, "repeat": args.repeat,
        })
    # numpy scalars (the image means and errors are float32) as plain floats; written atomically
    path = os.path.join(args.out, f"compare_d{args.depth}.json")
    with open(path + ".tmp", "w") as f:
        json.dump(rows, f, indent=1, default=float)
    os.replace(path + ".tmp", path)

    print(f"\nours (integrator_pt) vs Blender Cycles 3.4 CPU, {args.res}, maxDepth {args.depth} "
          f"(Cycles bounces {args.depth - 1}), {args.threads} threads, our sampler {args.sampler}")
    print("| scene | mean lum Cycles | mean lum ours | diff | rRMSE ours vs Cycles ref "
          f"({args.ref_spp} spp) | rRMSE Cycles seed 2 vs 1 (noise floor) |")
    print("|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scene']} | {r['mean_lum_cycles']:.4f} | {r['mean_lum_ours']:.4f} | "
              f"{100 * r['mean_lum_rel_diff']:+.2f}% | {r['rrmse_ours_ref_vs_cycles_ref']:.4f} | "
              f"{r['rrmse_cycles_ref2_vs_ref1']:.4f} |")
    print(f"\n| scene | spp | ours wall s | ours samples/s | Cycles wall s | Cycles samples/s "
          "| ours/Cycles (wall) | ours samples/CPU-s | Cycles samples/CPU-s | ours/Cycles (CPU) "
          "| rRMSE ours | rRMSE Cycles |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['scene']} | {r['spp']} | {r['ours_wall_s']:.2f} | {r['ours_samples_per_s']:.0f} | "
              f"{r['cycles_wall_s']:.2f} | {r['cycles_samples_per_s']:.0f} | {r['speed_ratio']:.2f}x | "
              f"{r['ours_samples_per_cpu_s']:.0f} | {r['cycles_samples_per_cpu_s']:.0f} | "
              f"{r['ours_samples_per_cpu_s'] / r['cycles_samples_per_cpu_s']:.2f}x | "
              f"{r['rrmse_ours_eq']:.4f} | {r['rrmse_cycles_eq']:.4f} |")


if __name__ == "__main__":
    sys.exit(main())
