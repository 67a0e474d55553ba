#!/usr/bin/python3
"""Evaluates TAA outputs against references, per sequence (tonemapped c/(1+max c) space,
the space the filters resolve in):
  RMSE       per-frame root-mean-square error vs the reference, averaged over frames
  temporal   mean |(o_t - o_{t-1}) - (r_t - r_{t-1})| over frames t >= 1
Frames before --skip (default 8, one jitter cycle of warm-up) are left out of both.

  eval.py --ref DIR --test DIR [--key post|color]     one sequence (manifest.json in each)
  eval.py --ref DIR --test DIR1 --test DIR2 ...        several methods on one sequence
FLIP is not computed (no Debian package; see README)."""
import argparse
import json
import os

import numpy as np

import dataset


def tm(x):
    x = np.maximum(x, 0)
    return x / (1.0 + x.max(-1, keepdims=True))


def frames(folder, key):
    man = json.load(open(os.path.join(folder, "manifest.json")))
    return [dataset.read_exr(os.path.join(folder, f[key])) for f in man["frames"]]


def metrics(out, ref, skip):
    o = np.stack([tm(x) for x in out])
    r = np.stack([tm(x) for x in ref])
    rmse = np.sqrt(((o - r) ** 2).mean(axis=(1, 2, 3)))
    tmp = np.abs((o[1:] - o[:-1]) - (r[1:] - r[:-1])).mean(axis=(1, 2, 3))
    return float(rmse[skip:].mean()), float(tmp[max(skip - 1, 0):].mean()), rmse


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--ref", required=True)
    ap.add_argument("--test", action="append", required=True)
    ap.add_argument("--key", default=None, help="frame key in the test manifest (default: "
                    "post if present, else color)")
    ap.add_argument("--skip", type=int, default=8)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    ref = frames(a.ref, "reference")
    rows = []
    for t in a.test:
        man = json.load(open(os.path.join(t, "manifest.json")))
        key = a.key or ("post" if "post" in man["frames"][0] else "color")
        label = f"{os.path.basename(os.path.normpath(t))}:{key}"
        if key == "post" and man.get("post"):
            label += f" ({man['post']})"
        out = frames(t, key)
        rmse, tmp, per = metrics(out, ref, a.skip)
        ms = [f.get("post_ms", 0.0) for f in man["frames"]] if key == "post" else []
        rows.append({"test": t, "label": label, "rmse": rmse, "temporal": tmp,
                     "post_ms_mean": float(np.mean(ms)) if ms else None,
                     "rmse_per_frame": [round(float(v), 6) for v in per]})
        print(f"{label:40s} RMSE {rmse:.5f}  temporal {tmp:.5f}" +
              (f"  post {np.mean(ms):.1f} ms/frame" if ms else ""))
    if a.json:
        json.dump(rows, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
