"""Writes the golden fixture the C test (plugins/post_taa/tests/taa_net.c) checks the plugin's inference
against: small random inputs, run through the PyTorch model loaded from a weights file.

  /usr/bin/python3 -m tools.taa.export_golden WEIGHTS.ttw OUT.bin

OUT.bin (little-endian): "TTAAGLD2", u32 fnv1a(weights file), u32 width, height, frames,
state channels; per frame: u32 jitter index, u32 fresh, float32 jitter offset (2), then
float32 colour (H*W*3, HWC), depth (H*W), motion (H*W*2), prevdepth (H*W), expected state
(H*W*S, tonemapped rgb + hidden) and expected linear output (H*W*3). The rejection masks of
models with the rejection input come from rejection.py, as in training."""
import struct
import sys

import numpy as np
import torch

from tools.taa import rejection, taa_model


def halton(i, b):
    f, r, n = 1.0, 0.0, i
    while n:
        f /= b
        r += f * (n % b)
        n //= b
    return r


def main():
    wpath, out = sys.argv[1], sys.argv[2]
    torch.manual_seed(0)
    rng = np.random.default_rng(7)
    model = taa_model.load_weights(wpath)
    w, h, frames = 20, 14, 4
    jit = [6, 7, 0, 1]
    s_ch = 3 + model.hidden
    blob = [struct.pack("<8sIIIII", b"TTAAGLD2", taa_model.fnv1a(open(wpath, "rb").read()),
                        w, h, frames, s_ch)]
    state, dprev, jprev = None, None, None
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    for f in range(frames):
        jxy = np.array([halton(jit[f] + 1, 2) - 0.5, halton(jit[f] + 1, 3) - 0.5], np.float32)
        color = rng.uniform(0, 1.5, (h, w, 3)).astype(np.float32)
        color[rng.uniform(size=(h, w)) < 0.1] *= 6.0       # a few bright pixels
        # a smooth background with a nearer block that moves: some history disoccluded
        depth = (6.0 + 0.1 * xx + 0.05 * yy).astype(np.float32)
        depth[(xx >= 4 + 2 * f) & (xx < 10 + 2 * f) & (yy >= 3) & (yy < 10)] = 2.5
        motion = np.stack([1.7 * np.sin(0.3 * yy + f) - 0.4,
                           1.1 * np.cos(0.2 * xx - f) + 0.3], -1).astype(np.float32)
        zprev = (depth * rng.uniform(0.97, 1.05, (h, w))).astype(np.float32)
        t = lambda a: torch.from_numpy(np.ascontiguousarray(a.transpose(2, 0, 1)))[None]
        dn = depth / depth.max()
        rej = None
        if f > 0:
            raw, rst = rejection.masks(dprev, zprev, motion, jxy, jprev)
            rej = torch.from_numpy(np.stack([raw, rst]).astype(np.float32))[None]
        with torch.no_grad():
            o, state = model.step(t(color), t(dn[..., None]), t(motion), state, jit[f], f == 0,
                                  rej)
            lin = taa_model.untonemap(o)
        st = state[0].numpy().transpose(1, 2, 0)
        blob.append(struct.pack("<IIff", jit[f], 1 if f == 0 else 0, jxy[0], jxy[1]))
        for a in (color, depth, motion, zprev, st, lin[0].numpy().transpose(1, 2, 0)):
            blob.append(np.ascontiguousarray(a, dtype="<f4").tobytes())
        dprev, jprev = depth, jxy
    open(out, "wb").write(b"".join(blob))


if __name__ == "__main__":
    main()
