"""VCTAA's darkening of noisy input (issue #19), as a figure: the mean luminance of each
method's output over the reference's (frames --skip..), against the input's samples per
pixel, one panel per scene, from evaluate.py's eval.json (sequences NAME-spp1, -spp2, ...).

  /usr/bin/python3 -m tools.taa.darkening EVAL.json [EVAL2.json ...] --out FIG.png [--skip 8]

Prints the table of the ratios too. The tonemapped resolve averages c / (1 + max c): the
inverse of that average lies below the mean of c (the tonemap is concave), the more so the
noisier c; resolve=linear averages c itself."""
import argparse
import json
import os
import re

import numpy as np


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("evals", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--skip", type=int, default=8)
    a = ap.parse_args()
    data = {}   # scene -> method -> {spp: ratio}
    for path in a.evals:
        for res in json.load(open(path)):
            m = re.match(r"(.*)-spp(\d+)$", res["sequence"])
            if not m:
                continue
            scene, spp = m.group(1), int(m.group(2))
            for r in res["methods"]:
                b = float(np.mean(r["brightness_per_frame"][a.skip:]))
                data.setdefault(scene, {}).setdefault(r["method"], {})[spp] = b
    if not data:
        raise SystemExit("darkening.py: no NAME-sppK sequences in the evaluations")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(data), figsize=(5.5 * len(data), 4), squeeze=False)
    print("| scene | method | " + " | ".join(f"{s} spp" for s in sorted(next(iter(next(iter(data.values())).values())))) + " |")
    for ax, (scene, methods) in zip(axes[0], sorted(data.items())):
        for meth, by in methods.items():
            spps = sorted(by)
            ls = "--" if meth.startswith("vctaa") else ":" if meth == "input" else "-"
            ax.plot(spps, [by[s] for s in spps], ls, marker="o", label=meth)
            print(f"| {scene} | {meth} | " + " | ".join(f"{by[s]:.3f}" for s in spps) + " |")
        ax.axhline(1.0, color="grey", lw=0.6)
        ax.set_xscale("log", base=2)
        ax.set_xlabel("input samples per pixel (full path depth)")
        ax.set_ylabel("mean luminance / reference")
        ax.set_title(scene)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(a.out + ".tmp.png", dpi=90)
    os.replace(a.out + ".tmp.png", a.out)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
