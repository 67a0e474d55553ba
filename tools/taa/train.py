"""Trains the TAA network on CPU (thesis 5.5): 8-frame windows of patches starting at every
jitter index, channel swapping, losses L1 reference + gradient + temporal, each split by the
aliasing mask M and (1 - M), computed on the last frame of the window; Adam (lr 1e-3,
eps 1e-7, gradients clipped to norm 1) with exponential decay 0.96 every 1000 steps.
Exports the weights file (and optionally the golden fixture).

  /usr/bin/python3 -m tools.taa.train --data DIR[,DIR2] --scenes stairs,fence[,DIR2:NAME*W] --out w.ttw [--width 12]
           [--hidden 5] [--body 3,3,5] [--jitter-layers "b2 b3 k"] [--minutes 8] [--steps N]
           [--batch 8] [--patch 64] [--threads 1] [--burn 24] [--ema 0.99] [--lr 1e-3]
           [--val pillars,...] [--ckpt-minutes M] [--cache DIR] [--init W.ttw]
           [--reject none|input|reset] [--w-tmp 6]
"""
import argparse
import json
import os
import time

# Under CPU contention OpenMP's default spin-waiting burns ~10x the CPU time per step with
# 2 threads (a preempted thread stalls the others at every barrier): wait passively.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

import numpy as np
import torch
import torch.nn.functional as F

from tools.taa import dataset, eval_torch, taa_model  # noqa: E402

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


def run_window(model, c, d, mo, j0, burn=0, rej=None):
    """Unrolls the recurrent network over the window (first frame starts fresh). The first
    `burn` frames run without gradients (burn-in): the window's trained frames then start
    from the network's own state, as in a long sequence, instead of a fresh start only
    (trained on fresh 8-frame windows alone, the error grows along a 120-frame sequence)."""
    outs, state = [], None
    for t in range(c.shape[1]):
        with torch.set_grad_enabled(t >= burn and torch.is_grad_enabled()):
            if t == burn and state is not None:
                state = state.detach()
            o, state = model.step(c[:, t], d[:, t], mo[:, t], state, (j0 + t) % 8, t == 0,
                                  None if rej is None else rej[:, t])
        if t >= burn:
            outs.append(o)
    return outs


def init_from(model, src, name):
    """Starts `model` from the weights of `src` (train.py --init): layers in order (body,
    kernel; the hidden layer when both have one). The first layer's input channels are
    matched by meaning ([rgb, motion, depth, state rgb] = 0..8, then the hidden channels
    both have, then the rejection input), new inputs start at zero weight, so the network
    first computes what `src` did; one weight set is copied into all 8 of a jitter layer."""
    pairs = list(zip(model.body, src.body)) + [(model.kernel, src.kernel)]
    if model.hid is not None and src.hid is not None:
        pairs.append((model.hid, src.hid))
    if len(model.body) != len(src.body):
        raise SystemExit(f"train.py: --init {name}: {len(src.body)} body layers, expected "
                         f"{len(model.body)}")
    for i, (d, s) in enumerate(pairs):
        if d.cout != s.cout or d.k != s.k or (i and d.cin != s.cin):
            raise SystemExit(f"train.py: --init {name}: layer {i} is {s.cin}->{s.cout} {s.k}x{s.k}, "
                             f"expected {d.cin}->{d.cout} {d.k}x{d.k}")
        sets = torch.arange(d.sets) % s.sets   # 1 set -> copied into all 8
        w = s.weight.data[sets]
        d.bias.data.copy_(s.bias.data[sets])
        if i == 0:   # input channels by meaning
            d.weight.data.zero_()
            d.weight.data[:, :, :9] = w[:, :, :9]
            h = min(model.hidden, src.hidden)
            d.weight.data[:, :, 9:9 + h] = w[:, :, 9:9 + h]
            if model.flags & taa_model.FLAG_REJECT and src.flags & taa_model.FLAG_REJECT:
                d.weight.data[:, :, -1] = w[:, :, -1]
        else:
            d.weight.data.copy_(w)


def main():
    global W_TMP
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True, help="dataset folder(s), comma-separated")
    ap.add_argument("--scenes", default="stairs,fence",
                    help="training sequences: NAME (first --data folder) or DATA:NAME, "
                         "optionally NAME*W for sampling weight W")
    ap.add_argument("--out", required=True)
    ap.add_argument("--width", type=int, default=12)
    ap.add_argument("--hidden", type=int, default=5)
    ap.add_argument("--body", default="3,3,5")
    ap.add_argument("--jitter-layers", default="b2 b3 k")
    ap.add_argument("--kernel", type=int, default=5, help="kernel-prediction layer size "
                    "(thesis: 5; it outputs the 2 x 25 colour-mix weights either way)")
    ap.add_argument("--minutes", type=float, default=8.0)
    ap.add_argument("--steps", type=int, default=0, help="stop after this many steps (0: none)")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--patch", type=int, default=64)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--burn", type=int, default=0,
                    help="burn-in: each batch runs a random 0..BURN frames (multiple of 8) "
                         "without gradients before its FRAMES trained frames")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--init", default=None, help="start from this weights file (same shape)")
    ap.add_argument("--cache", default=None, help="folder for decoded-sequence .npz caches")
    ap.add_argument("--ckpt-minutes", type=float, default=0.0,
                    help="write OUT.stepN.ttw every this many minutes (0: none)")
    ap.add_argument("--val", default="", help="validation sequences (DATA:NAME or NAME) "
                    "evaluated in PyTorch at each checkpoint and at the end")
    ap.add_argument("--ema", type=float, default=0.0,
                    help="save/evaluate an exponential moving average of the weights with "
                         "this decay (e.g. 0.99; 0: the raw weights)")
    ap.add_argument("--reject", choices=("none", "input", "reset"), default="none",
                    help="history rejection (rejection.py): input = the mask as an extra "
                         "input channel; reset = also reset the history where it says so")
    ap.add_argument("--no-channels-last", action="store_true")
    ap.add_argument("--w-tmp", type=float, default=W_TMP,
                    help=f"weight of the temporal loss terms (thesis 5.5.3: {W_TMP})")
    a = ap.parse_args()
    W_TMP = a.w_tmp
    flags = {"none": 0, "input": taa_model.FLAG_REJECT,
             "reset": taa_model.FLAG_REJECT | taa_model.FLAG_RESET}[a.reject]
    torch.set_num_threads(a.threads)
    torch.set_flush_denormal(True)
    torch.manual_seed(a.seed)
    rng = np.random.default_rng(a.seed)
    datas = a.data.split(",")

    def resolve(spec):
        w = 1.0
        if "*" in spec:
            spec, w = spec.split("*")
            w = float(w)
        d, n = (spec.rsplit(":", 1) if ":" in spec else (datas[0], spec))
        return os.path.join(d, n), n, w

    t_load = time.time()
    specs = [resolve(s) for s in a.scenes.split(",")]
    seqs = [dataset.Sequence(p, with_post=False, cache_dir=a.cache) for p, _, _ in specs]
    vals = {}
    for s in filter(None, a.val.split(",")):
        p, n, _ = resolve(s)
        vals[n] = dataset.Sequence(p, cache_dir=a.cache)
    print(f"loaded {len(seqs)} training, {len(vals)} validation sequences in "
          f"{time.time() - t_load:.1f} s", flush=True)
    model = taa_model.TAANet(a.width, a.hidden, tuple(int(k) for k in a.body.split(",")),
                             a.jitter_layers, flags=flags, kernel=a.kernel)
    model.channels_last = not a.no_channels_last
    if a.init:
        init_from(model, taa_model.load_weights(a.init), a.init)
    opt = torch.optim.Adam(model.parameters(), lr=a.lr, betas=(0.9, 0.999), eps=1e-7)
    sched = torch.optim.lr_scheduler.LambdaLR(opt, lambda step: 0.96 ** (step / 1000.0))
    gen = dataset.TensorWindows(seqs, a.batch, a.frames + a.burn, a.patch, rng,
                                [w for _, _, w in specs])
    t_start = time.time()
    t_end = t_start + 60 * a.minutes
    t_ckpt = t_start + 60 * a.ckpt_minutes if a.ckpt_minutes > 0 else float("inf")
    step, log, evals = 0, [], []

    params = list(model.parameters())
    ema = [p.detach().clone() for p in params] if a.ema > 0 else None

    def checkpoint(path):
        model.eval()
        raw = None
        if ema is not None:
            raw = [p.detach().clone() for p in params]
            with torch.no_grad():
                for p, e in zip(params, ema):
                    p.copy_(e)
        taa_model.save_weights(model, path)
        row = {"step": step, "minutes": (time.time() - t_start) / 60.0, "file": path}
        if vals:
            cl = model.channels_last
            model.channels_last = False
            res = eval_torch.evaluate(model, vals)
            model.channels_last = cl
            row.update({n: {"rmse": r, "temporal": t} for n, (r, t) in res.items()})
            print(f"eval step {step}: " + "  ".join(f"{n} {r:.5f}/{t:.5f}"
                                                    for n, (r, t) in res.items()), flush=True)
        evals.append(row)
        if raw is not None:
            with torch.no_grad():
                for p, r in zip(params, raw):
                    p.copy_(r)
        model.train()

    while time.time() < t_end and (a.steps <= 0 or step < a.steps):
        c, d, mo, r, j0, rj = next(gen)
        if a.burn:
            skip = a.burn - 8 * int(rng.integers(0, a.burn // 8 + 1))
            c, d, mo, r, rj = c[:, skip:], d[:, skip:], mo[:, skip:], r[:, skip:], rj[:, skip:]
            j0 = (j0 + skip) % 8
            outs = run_window(model, c, d, mo, j0, c.shape[1] - a.frames, rj)
        else:
            outs = run_window(model, c, d, mo, j0, 0, rj)
        refs = [taa_model.tonemap(r[:, t]) for t in (-2, -1)]
        loss, parts = loss_fn(outs, refs, taa_model.tonemap(c[:, -1]))
        opt.zero_grad()
        loss.backward()
        torch.nn.utils.clip_grad_norm_(model.parameters(), 1.0)
        opt.step()
        sched.step()
        step += 1
        if ema is not None:
            with torch.no_grad():
                for p, e in zip(params, ema):
                    e.mul_(a.ema).add_(p.detach(), alpha=1.0 - a.ema)
        if step % 20 == 0:
            el = time.time() - t_start
            log.append({"step": step, "loss": float(loss), "seconds": round(el, 1),
                        **{k: float(v) for k, v in parts.items()}})
            print(f"step {step} {el:.0f}s {step / el:.3f} steps/s "
                  f"{step * a.batch * a.frames * a.patch ** 2 / el:.0f} px-frames/s "
                  f"loss {float(loss):.5f} " +
                  " ".join(f"{k} {float(v):.4f}" for k, v in parts.items()), flush=True)
        if time.time() >= t_ckpt:
            checkpoint(f"{a.out}.step{step}.ttw")
            t_ckpt += 60 * a.ckpt_minutes
    elapsed = time.time() - t_start
    checkpoint(a.out)
    meta = {"steps": step, "init": a.init, "minutes": a.minutes, "elapsed_s": round(elapsed, 1),
            "steps_per_s": step / elapsed,
            "px_frames_per_s": step * a.batch * a.frames * a.patch ** 2 / elapsed,
            "batch": a.batch, "patch": a.patch, "frames": a.frames, "data": a.data,
            "scenes": a.scenes, "val": a.val, "width": a.width, "hidden": a.hidden,
            "body": a.body, "jitter_layers": a.jitter_layers, "kernel": a.kernel,
            "threads": a.threads,
            "seed": a.seed, "lr": a.lr, "w_tmp": a.w_tmp, "ema": a.ema, "burn": a.burn, "reject": a.reject,
            "channels_last": model.channels_last,
            "evals": evals, "log": log}
    json.dump(meta, open(a.out + ".train.json", "w"), indent=1)
    print(f"wrote {a.out} after {step} steps ({step / elapsed:.3f} steps/s)")


if __name__ == "__main__":
    main()
