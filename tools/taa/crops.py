#!/usr/bin/python3
"""Side-by-side PNG of evaluate.sh outputs for looking at ghosting / blur: one row per
frame, columns input | reference | VCTAA | network 12 | network 6 | 4x|VCTAA - ref| |
4x|network 12 - ref| (tonemapped c / (1 + max c), gamma 2.2, pixels repeated SCALE times);
prints the per-frame RMSE of each.

  crops.py DATA/SEQ EVAL_OUT/SEQ OUT.png SCALE F1,F2,... [X0:X1,Y0:Y1]
e.g. crops.py /tmp/taa_data/pillars /tmp/taa_eval/pillars /tmp/p.png 3 79,80,81 10:110,50:82"""
import sys

import numpy as np
import OpenImageIO as oiio


def rd(p):
    a = oiio.ImageBuf(p).get_pixels(oiio.FLOAT)[..., :3]
    return a / (1 + a.max(axis=2, keepdims=True))   # the tonemap of eval.py / training


def disp(a):
    return np.clip(a, 0, 1) ** (1 / 2.2)


def main(argv):
    if len(argv) < 5:
        sys.exit(__doc__)
    ref, ev, out, sc = argv[0], argv[1], argv[2], int(argv[3])
    frames = [int(f) for f in argv[4].split(",")]
    crop = None
    if len(argv) > 5:
        xs, ys = argv[5].split(",")
        crop = tuple(int(v) for v in xs.split(":")) + tuple(int(v) for v in ys.split(":"))
    rows = []
    for f in frames:
        r = rd(f"{ref}/reference_{f:04d}.exr")
        cols = [rd(f"{ev}/none/color_{f:04d}.exr"), r]
        outs = [rd(f"{ev}/{m}/post_{f:04d}.exr") for m in ("vctaa", "net12", "net6")]
        cols += outs
        cols += [np.abs(outs[0] - r) * 4, np.abs(outs[1] - r) * 4]
        print(f, "rmse vctaa %.4f net12 %.4f net6 %.4f input %.4f" % tuple(
            float(np.sqrt(((c - r) ** 2).mean())) for c in outs + [cols[0]]))
        if crop:
            cols = [c[crop[2]:crop[3], crop[0]:crop[1]] for c in cols]
        sep = np.ones((cols[0].shape[0], 2, 3), np.float32)
        row = np.concatenate(sum([[disp(c), sep] for c in cols], [])[:-1], axis=1)
        rows += [row, np.ones((2, row.shape[1], 3), np.float32)]
    img = np.concatenate(rows[:-1], axis=0)
    img = np.repeat(np.repeat(img, sc, 0), sc, 1)
    o = oiio.ImageBuf(oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.UINT8))
    o.set_pixels(oiio.ROI(0, img.shape[1], 0, img.shape[0]), (img * 255 + 0.5).astype(np.uint8))
    o.write(out)


if __name__ == "__main__":
    main(sys.argv[1:])
