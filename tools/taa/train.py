#!/usr/bin/python3
"""Trains the TAA network on CPU (thesis 5.5): 8-frame windows of patches starting at every
jitter index, channel swapping, losses L1 reference + gradient + temporal, each split by the
aliasing mask M and (1 - M), computed on the last frame of the window; Adam (lr 1e-3,
eps 1e-7, gradients clipped to norm 1) with exponential decay 0.96 every 1000 steps.
Exports the weights file (and optionally the golden fixture).

  train.py --data DIR --scenes stairs,fence --out w.ttw [--width 12] [--hidden 5]
           [--body 3,3,5] [--jitter-layers "b2 b3 k"] [--minutes 8] [--batch 8] [--patch 64]
"""
import argparse
import json
import os
import time

import numpy as np
import torch
import torch.nn.functional as F

import dataset
import taa_model

# Loss weights (5.5.3): temporal dominant, gradient above reference; aliased regions 1.5x.
W_REF, W_GRAD, W_TMP, ALIAS = 1.0, 1.5, 6.0, 1.5
MASK_SENSITIVITY = 4.0


def aliasing_mask(inp_tm, ref_tm):
    """M: summed channel differences input vs reference, scaled, clipped, 3x3-dilated."""
    m = (inp_tm - ref_tm).abs().sum(1, keepdim=True) * MASK_SENSITIVITY
    return F.max_pool2d(m.clamp(0, 1), 3, stride=1, padding=1)


def grads(x):
    return x[..., :, 1:] - x[..., :, :-1], x[..., 1:, :] - x[..., :-1, :]


def loss_fn(outs, refs, inp_last):
    o, o_prev = outs[-1], outs[-2]
    r, r_prev = refs[-1], refs[-2]
    m = aliasing_mask(inp_last, r)
    parts = {}
    for name, mw in (("alias", m), ("ghost", 1.0 - m)):
        scale = ALIAS if name == "alias" else 1.0
        l_ref = (mw * (o - r).abs()).mean()
        ox, oy = grads(o)
        rx, ry = grads(r)
        l_grad = (mw[..., :, 1:] * (ox - rx).abs()).mean() + (mw[..., 1:, :] * (oy - ry).abs()).mean()
        l_tmp = (mw * ((o - o_prev) - (r - r_prev)).abs()).mean()
        parts[name + "_ref"] = scale * W_REF * l_ref
        parts[name + "_grad"] = scale * W_GRAD * l_grad
        parts[name + "_tmp"] = scale * W_TMP * l_tmp
    return sum(parts.values()), parts


def run_window(model, c, d, mo, j0):
    """Unrolls the recurrent network over the window (first frame starts fresh)."""
    outs, state = [], None
    for t in range(c.shape[1]):
        o, state = model.step(c[:, t], d[:, t], mo[:, t], state, (j0 + t) % 8, t == 0)
        outs.append(o)
    return outs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--scenes", default="stairs,fence")
    ap.add_argument("--out", required=True)
    ap.add_argument("--width", type=int, default=12)
    ap.add_argument("--hidden", type=int, default=5)
    ap.add_argument("--body", default="3,3,5")
    ap.add_argument("--jitter-layers", default="b2 b3 k")
    ap.add_argument("--minutes", type=float, default=8.0)
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--patch", type=int, default=64)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--init", default=None, help="start from this weights file (same shape)")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    seqs = [dataset.Sequence(os.path.join(a.data, s)) for s in a.scenes.split(",")]
    model = taa_model.TAANet(a.width, a.hidden, tuple(int(k) for k in a.body.split(",")),
                             a.jitter_layers)
    if a.init:
        src = taa_model.load_weights(a.init)
        for dst_l, src_l in zip(model.layers(), src.layers()):
            dst_l.weight.data.copy_(src_l.weight.data)
            dst_l.bias.data.copy_(src_l.bias.data)
    opt = torch.optim.Adam(model.parameters(), lr=1e-3, betas=(0.9, 0.999), eps=1e-7)
    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda step: 0.96 ** (step / 1000.0))
    gen = dataset.windows(seqs, a.batch, a.frames, a.patch, rng)
    t_end = time.time() + 60 * a.minutes
    step, log = 0, []
    while time.time() < t_end:
        c, d, mo, r, j0 = (next(gen))
        c, d, mo, r = (torch.from_numpy(x) for x in (c, d, mo, r))
        outs = run_window(model, c, d, mo, j0)
        refs = [taa_model.tonemap(r[:, t]) for t in range(r.shape[1])]
        loss, parts = loss_fn(outs, refs, taa_model.tonemap(c[:, -1]))
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        sched.step()
        step += 1
        if step % 20 == 0:
            log.append({"step": step, "loss": float(loss),
                        **{k: float(v) for k, v in parts.items()}})
            print(f"step {step} loss {float(loss):.5f} " +
                  " ".join(f"{k} {float(v):.4f}" for k, v in parts.items()), flush=True)
    taa_model.save_weights(model, a.out)
    meta = {"steps": step, "init": a.init, "minutes": a.minutes, "batch": a.batch, "patch": a.patch,
            "frames": a.frames, "scenes": a.scenes, "width": a.width, "hidden": a.hidden,
            "body": a.body, "jitter_layers": a.jitter_layers, "threads": a.threads,
            "log": log}
    json.dump(meta, open(a.out + ".train.json", "w"), indent=1)
    print(f"wrote {a.out} after {step} steps")


if __name__ == "__main__":
    main()
