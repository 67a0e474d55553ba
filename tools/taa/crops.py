"""Side-by-side PNG of evaluate.py outputs for looking at ghosting / blur: one row per
frame, columns input | reference | each method | 4x |method - reference| for each method
(tonemapped c / (1 + max c), gamma 2.2, pixels repeated SCALE times); prints the per-frame
RMSE of each.

  /usr/bin/python3 -m tools.taa.crops SEQ EVAL_OUT/SEQ OUT.png SCALE F1,F2,... [X0:X1,Y0:Y1] [--methods vctaa,c12,...]
e.g. crops.py /tmp/taa/data/d1/pillars /tmp/ev/pillars /tmp/p.png 3 79,80,81 10:110,50:82
SEQ: the dataset sequence (its manifest names the references); EVAL_OUT/SEQ/METHOD: the
folders evaluate.py rendered (input = mode none)."""
import argparse
import json
import os
import sys

import numpy as np

from tools.common import images


def tm(a):
    a = np.maximum(a[..., :3], 0)
    return a / (1 + a.max(axis=2, keepdims=True))   # the tonemap of eval.py / training


def disp(a):
    return np.clip(a, 0, 1) ** (1 / 2.2)


def frame(folder, key, f):
    man = json.load(open(os.path.join(folder, "manifest.json")))
    for e in man["frames"]:
        if e["index"] == f:
            return tm(images.read_exr(os.path.join(folder, e[key])))
    sys.exit(f"crops.py: {folder}: no frame {f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("seq")
    ap.add_argument("ev")
    ap.add_argument("out")
    ap.add_argument("scale", type=int)
    ap.add_argument("frames")
    ap.add_argument("crop", nargs="?", default=None)
    ap.add_argument("--methods", default=None, help="comma-separated (default: every folder "
                    "of EVAL_OUT/SEQ but input)")
    a = ap.parse_args()
    methods = (a.methods.split(",") if a.methods else
               sorted(m for m in os.listdir(a.ev) if os.path.isdir(os.path.join(a.ev, m)) and m != "input"))
    crop = None
    if a.crop:
        xs, ys = a.crop.split(",")
        crop = tuple(int(v) for v in xs.split(":")) + tuple(int(v) for v in ys.split(":"))
    rows = []
    print("columns: input, reference, " + ", ".join(methods) + ", then 4x error of each")
    for f in (int(x) for x in a.frames.split(",")):
        r = frame(a.seq, "reference", f)
        inp = frame(os.path.join(a.ev, "input"), "post", f)
        outs = [frame(os.path.join(a.ev, m), "post", f) for m in methods]
        cols = [inp, r] + outs + [np.abs(o - r) * 4 for o in outs]
        print(f, "rmse " + " ".join(f"{m} {float(np.sqrt(((o - r) ** 2).mean())):.4f}"
                                   for m, o in zip(["input"] + methods, [inp] + outs)))
        if crop:
            cols = [c[crop[2]:crop[3], crop[0]:crop[1]] for c in cols]
        sep = np.ones((cols[0].shape[0], 2, 3), np.float32)
        row = np.concatenate(sum([[disp(c), sep] for c in cols], [])[:-1], axis=1)
        rows += [row, np.ones((2, row.shape[1], 3), np.float32)]
    img = np.concatenate(rows[:-1], axis=0)
    img = np.repeat(np.repeat(img, a.scale, 0), a.scale, 1)
    import OpenImageIO as oiio
    o = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    o.set_pixels(oiio.ROI(0, img.shape[1], 0, img.shape[0]), (img * 255 + 0.5).astype(np.uint8))
    tmp = a.out + ".tmp.png"
    if not o.write(tmp):
        sys.exit(f"crops.py: cannot write {a.out}: {o.geterror()}")
    os.replace(tmp, a.out)


if __name__ == "__main__":
    main()
