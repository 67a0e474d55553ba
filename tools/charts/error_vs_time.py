"""Speed-vs-accuracy chart for integrator_pt (issue 4): relative RMSE against a high-spp
reference versus render time, on the Cornell box, for maxDepth 1, 2, 3, 5, 8.

The reference is our own converged render with a deep path (default maxDepth 32, Russian
roulette from bounce 3), so a shallow maxDepth shows its bias as a floor that more samples
cannot lower; pass --reference REF.exr to use another one (e.g. a Cycles reference from
tools/cycles/compare.py, rendered at the same resolution and a large depth).
rRMSE = tunetrace's one definition (tools/common/images.py, tt_rrmse in C): over the
Rec. 709 luminance, sqrt(mean((L - R)^2 / (R^2 + 1e-3))); time = the host's render_ms (no
scene load / accel build / output).

Usage (from the repository root):
  /usr/bin/python3 -m tools.charts.error_vs_time [--host PATH] [--res 128x128]
      [--ref-spp 2048] [--max-spp 256] [--threads 2] [--out /tmp/tt_chart]
Writes OUT/error_vs_time.png and OUT/error_vs_time.json and prints a table.
Needs: python3-matplotlib, python3-numpy, python3-openimageio (Debian 12 packages).
"""
import json
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from tools.common import images  # noqa: E402
from tools.tttools import cli, host  # noqa: E402

ROOT = host.ROOT


def render(args, depth, spp, seed, out):
    """One host render; returns render seconds."""
    st = host.run(args.host, ["--spp", str(spp), "--threads", str(args.threads), "--res", args.res,
                              "--seed", str(seed), "--set", f"integrator_pt.maxDepth={depth}",
                              "--out", out, "--quiet", "--no-db", args.scene],
                  stats=out + ".json").stats
    return st["render_ms"] / 1000.0


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--scene", default=os.path.join(ROOT, "scenes", "cornell-box", "scene.json"))
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--depths", default="1,2,3,5,8")
    ap.add_argument("--ref-depth", type=int, default=32)
    ap.add_argument("--ref-spp", type=int, default=2048)
    ap.add_argument("--reference", default=None, help="use this EXR as the reference")
    ap.add_argument("--max-spp", type=int, default=256)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default="/tmp/tt_chart")
    args = ap.parse_args()
    args.host = host.find(args.host)
    os.makedirs(args.out, exist_ok=True)

    ref_path = args.reference
    if not ref_path:
        ref_path = os.path.join(args.out, f"ref_d{args.ref_depth}_{args.ref_spp}spp.exr")
        if not os.path.exists(ref_path):
            print(f"reference: maxDepth {args.ref_depth}, {args.ref_spp} spp, {args.res} ...", flush=True)
            t = render(args, args.ref_depth, args.ref_spp, 1000, ref_path)
            print(f"reference: {t:.1f} s", flush=True)
    ref = images.read_rgb(ref_path)

    depths = [int(d) for d in args.depths.split(",")]
    spps = []
    s = 1
    while s <= args.max_spp:
        spps.append(s)
        s *= 2
    results = {}
    for d in depths:
        pts = []
        for spp in spps:
            out = os.path.join(args.out, f"d{d}_{spp}spp.exr")
            t = render(args, d, spp, 7 + spp, out)
            e = images.rrmse(images.read_rgb(out), ref)
            pts.append({"spp": spp, "time_s": t, "rrmse": e})
            print(f"maxDepth {d:2d} spp {spp:4d}: {t:8.3f} s  rRMSE {e:.4f}", flush=True)
        results[d] = pts

    json.dump({"reference": ref_path, "res": args.res, "threads": args.threads,
               "results": {str(k): v for k, v in results.items()}},
              open(os.path.join(args.out, "error_vs_time.json"), "w"), indent=1)
    fig, ax = plt.subplots(figsize=(7, 5))
    for d, pts in results.items():
        ax.loglog([p["time_s"] for p in pts], [p["rrmse"] for p in pts], "o-", label=f"maxDepth {d}")
    ax.set_xlabel("render time [s] (%s threads, %s)" % (args.threads, args.res))
    ax.set_ylabel("rRMSE vs reference")
    ax.set_title("integrator_pt on the Cornell box: error vs time\n(reference: %s)"
                 % os.path.basename(ref_path))
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    png = os.path.join(args.out, "error_vs_time.png")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print(f"\nchart: {png}")
    print("| maxDepth | " + " | ".join(f"{s} spp" for s in spps) + " |")
    print("|---|" + "---|" * len(spps))
    for d, pts in results.items():
        print(f"| {d} | " + " | ".join(f"{p['rrmse']:.4f} ({p['time_s']:.2f} s)" for p in pts) + " |")


if __name__ == "__main__":
    main()
