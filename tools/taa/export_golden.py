#!/usr/bin/python3
"""Writes the golden fixture the C test (tests/taa_net.c) checks the plugin's inference
against: small random inputs, run through the PyTorch model loaded from a weights file.

  export_golden.py WEIGHTS.ttw OUT.bin

OUT.bin (little-endian): "TTAAGLD1", u32 fnv1a(weights file), u32 width, height, frames,
state channels; per frame: u32 jitter index, u32 fresh, then float32 colour (H*W*3, HWC),
depth (H*W), motion (H*W*2), expected state (H*W*S, tonemapped rgb + hidden) and expected
linear output (H*W*3)."""
import struct
import sys

import numpy as np
import torch

import taa_model


def main():
    wpath, out = sys.argv[1], sys.argv[2]
    torch.manual_seed(0)
    rng = np.random.default_rng(7)
    model = taa_model.load_weights(wpath)
    w, h, frames = 20, 14, 4
    jit = [6, 7, 0, 1]
    s_ch = 3 + model.hidden
    blob = [struct.pack("<8sIIIII", b"TTAAGLD1", taa_model.fnv1a(open(wpath, "rb").read()),
                        w, h, frames, s_ch)]
    state = None
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    for f in range(frames):
        color = rng.uniform(0, 1.5, (h, w, 3)).astype(np.float32)
        color[rng.uniform(size=(h, w)) < 0.1] *= 6.0       # a few bright pixels
        depth = rng.uniform(1.0, 10.0, (h, w)).astype(np.float32)
        motion = np.stack([1.7 * np.sin(0.3 * yy + f) - 0.4,
                           1.1 * np.cos(0.2 * xx - f) + 0.3], -1).astype(np.float32)
        t = lambda a: torch.from_numpy(np.ascontiguousarray(a.transpose(2, 0, 1)))[None]
        dn = depth / depth.max()
        with torch.no_grad():
            o, state = model.step(t(color), t(dn[..., None]), t(motion), state, jit[f], f == 0)
            lin = taa_model.untonemap(o)
        st = state[0].numpy().transpose(1, 2, 0)
        blob.append(struct.pack("<II", jit[f], 1 if f == 0 else 0))
        for a in (color, depth, motion, st, lin[0].numpy().transpose(1, 2, 0)):
            blob.append(np.ascontiguousarray(a, dtype="<f4").tobytes())
    open(out, "wb").write(b"".join(blob))


if __name__ == "__main__":
    main()
