"""Evaluates TAA outputs against references, per sequence (tonemapped c/(1+max c) space,
the space the filters resolve in):
  RMSE       per-frame root-mean-square error vs the reference, averaged over frames
  temporal   mean |(o_t - o_{t-1}) - (r_t - r_{t-1})| over frames t >= 1
  FLIP       per-frame mean LDR-FLIP (flip.py; the tonemapped frames sRGB-encoded, 67 pixels
             per degree), averaged over frames; last column of each line, "--no-flip" skips it
Frames before --skip (default 8, one jitter cycle of warm-up) are left out of all three.

Each --test folder is scored on every image its manifest has: the rendered frames ("color")
and, when a post filter ran, the filtered ones ("post"), one line each, so a filter's line
can be read against its own input's; --key KEY scores that one key only.

  E="/usr/bin/python3 -m tools.taa.eval"   # from the repository root
  $E --ref DIR --test DIR [--key post|color]     one sequence (manifest.json in each)
  $E --ref DIR --test DIR1 --test DIR2 ...        several methods on one sequence
(--json FILE also writes the numbers, per-frame RMSE / FLIP included.)"""
import argparse
import json
import os
import sys

import numpy as np

from tools.common import images  # OpenImageIO only: evaluation must not need torch
from tools.taa import flip as flipmod


def tm(x):
    x = np.maximum(x, 0)
    return x / (1.0 + x.max(-1, keepdims=True))


def fail(msg):
    sys.exit(f"eval.py: {msg}")


def manifest(folder):
    """The folder's manifest.json (host --sequence / --frames with an --out pattern)."""
    path = os.path.join(folder, "manifest.json")
    try:
        man = json.load(open(path))
    except OSError as e:
        fail(f"{path}: cannot read the manifest ({e.strerror}); expected a folder written by "
             "host --sequence ... --out-dir DIR or host --frames A:B --out DIR/frame_%04d.exr")
    except ValueError as e:
        fail(f"{path}: not valid JSON ({e})")
    if not isinstance(man, dict) or not isinstance(man.get("frames"), list) or not man["frames"]:
        fail(f"{path}: field \"frames\": expected a non-empty list")
    return man


def frames(folder, key, man=None):
    man = man or manifest(folder)
    out = []
    for i, f in enumerate(man["frames"]):
        if key not in f:
            fail(f"{os.path.join(folder, 'manifest.json')}: frames[{i}] has no \"{key}\" file "
                 f"(it has: {', '.join(k for k in f if isinstance(f[k], str))})")
        try:
            out.append(images.read_exr(os.path.join(folder, f[key])))
        except IOError as e:
            fail(str(e))
        if out[-1].ndim != 3 or out[-1].shape[-1] < 3 or out[-1].shape != out[0].shape:
            fail(f"{os.path.join(folder, f[key])}: expected an RGB image of shape "
                 f"{out[0].shape}, got {out[-1].shape}")
    return out


def metrics(out, ref, skip):
    o = np.stack([tm(x) for x in out])
    r = np.stack([tm(x) for x in ref])
    rmse = np.sqrt(((o - r) ** 2).mean(axis=(1, 2, 3)))
    tmp = np.abs((o[1:] - o[:-1]) - (r[1:] - r[:-1])).mean(axis=(1, 2, 3))
    return float(rmse[skip:].mean()), float(tmp[max(skip - 1, 0):].mean()), rmse


def flip_frames(out, ref_srgb, skip, ppd):
    """Per-frame mean LDR-FLIP of frames >= skip (ref_srgb: those frames, sRGB-encoded)."""
    return np.array([flipmod.flip_mean(r, flipmod.srgb_encode(tm(x)), ppd)
                     for r, x in zip(ref_srgb, out[skip:])])   # per frame: faster than stacked


def main():
    ap = argparse.ArgumentParser(prog="eval.py", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ref", required=True, metavar="DIR",
                    help="the reference sequence: a folder whose manifest.json lists "
                    "\"reference\" frames (host --supersample K ... --out-dir DIR)")
    ap.add_argument("--test", action="append", required=True, metavar="DIR",
                    help="a sequence to score (repeatable): a folder of host --sequence ... "
                    "--out-dir DIR or host --frames A:B --out DIR/frame_%%04d.exr, of the "
                    "reference's frame count and size")
    ap.add_argument("--key", default=None, metavar="KEY",
                    help="score only this frame key of the test manifests (color, post, "
                    "reference, ...); default: color and post, each that the manifest has")
    ap.add_argument("--skip", type=int, default=8, metavar="N",
                    help="leave out the first N frames, the warm-up (default 8)")
    ap.add_argument("--json", default=None, metavar="FILE",
                    help="also write the numbers to FILE, per-frame RMSE and FLIP included")
    ap.add_argument("--no-flip", action="store_true", help="skip the FLIP column (faster)")
    ap.add_argument("--ppd", type=float, default=67.0, metavar="PPD",
                    help="FLIP pixels per degree (default 67)")
    a = ap.parse_args()
    ref = frames(a.ref, "reference")
    ref_srgb = None if a.no_flip else flipmod.srgb_encode(np.stack([tm(x) for x in ref[a.skip:]]))
    rows = []
    jobs = []
    for t in a.test:
        man = manifest(t)
        keys = [a.key] if a.key else [k for k in ("color", "post") if k in man["frames"][0]]
        if not keys:
            fail(f"{os.path.join(t, 'manifest.json')}: frames[0] has neither \"color\" nor "
                 "\"post\" frames; name the key with --key")
        jobs += [(t, man, k) for k in keys]
    for t, man, key in jobs:
        label = f"{os.path.basename(os.path.normpath(t))}:{key}"
        if key == "post" and man.get("post"):
            label += f" ({man['post']})"
        out = frames(t, key, man)
        if len(out) != len(ref) or out[0].shape != ref[0].shape:
            fail(f"{t}: {len(out)} frames of {out[0].shape[1]}x{out[0].shape[0]}, the reference "
                 f"{a.ref} has {len(ref)} of {ref[0].shape[1]}x{ref[0].shape[0]}")
        if len(out) <= a.skip:
            fail(f"{t}: {len(out)} frames, none left after --skip {a.skip}")
        rmse, tmp, per = metrics(out, ref, a.skip)
        ms = [f.get("post_ms", 0.0) for f in man["frames"]] if key == "post" else []
        fl = None if a.no_flip else flip_frames(out, ref_srgb, a.skip, a.ppd)
        rows.append({"test": t, "label": label, "rmse": rmse, "temporal": tmp,
                     "post_ms_mean": float(np.mean(ms)) if ms else None,
                     "rmse_per_frame": [round(float(v), 6) for v in per]})
        if fl is not None:
            rows[-1]["flip"] = float(fl.mean())
            rows[-1]["flip_per_frame"] = [round(float(v), 6) for v in fl]   # frames skip..
        print(f"{label:40s} RMSE {rmse:.5f}  temporal {tmp:.5f}" +
              (f"  post {np.mean(ms):.1f} ms/frame" if ms else "") +
              (f"  FLIP {fl.mean():.5f}" if fl is not None else ""))
    if a.json:
        json.dump(rows, open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
