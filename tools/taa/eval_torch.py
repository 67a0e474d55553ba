"""Evaluates a weights file in PyTorch on whole sequences (as the C plugin runs them:
frame 0 and every reset start fresh, the state carries over otherwise) with eval.py's
metrics (tonemapped RMSE and temporal error, frames --skip.. ).

  /usr/bin/python3 -m tools.taa.eval_torch W.ttw DATA_DIR SEQ[,SEQ...] [--threads 1] [--cache DIR] [--json OUT]"""
import argparse
import json
import os

import numpy as np
import torch

from tools.taa import dataset, taa_model
from tools.taa import eval as ev


def run_sequence(model, seq):
    """Returns the linear outputs (T,H,W,3) of the network over the whole sequence."""
    c = torch.from_numpy(np.ascontiguousarray(seq.color.transpose(0, 3, 1, 2)))
    d = torch.from_numpy(np.ascontiguousarray(seq.depth_n[:, None]))
    m = torch.from_numpy(np.ascontiguousarray(seq.motion.transpose(0, 3, 1, 2)))
    rj = torch.from_numpy(np.ascontiguousarray(seq.rej))
    outs, state = [], None
    with torch.no_grad():
        for t in range(c.shape[0]):
            fresh = t == 0 or bool(seq.reset[t])
            o, state = model.step(c[t:t + 1], d[t:t + 1], m[t:t + 1], state,
                                  int(seq.jitter[t]), fresh, rj[t:t + 1])
            outs.append(taa_model.untonemap(o)[0].permute(1, 2, 0).numpy())
    return np.stack(outs)


def evaluate(model, seqs, skip=8):
    """{name: (rmse, temporal)} of the model on preloaded sequences {name: Sequence}."""
    res = {}
    for name, s in seqs.items():
        out = run_sequence(model, s)
        rmse, tmp, _ = ev.metrics(list(out), list(s.ref), skip)
        res[name] = (rmse, tmp)
    return res


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("weights")
    ap.add_argument("data")
    ap.add_argument("seqs")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--cache", default=None)
    ap.add_argument("--skip", type=int, default=8)
    ap.add_argument("--json", default=None)
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    model = taa_model.load_weights(a.weights)
    seqs = {s: dataset.Sequence(os.path.join(a.data, s), cache_dir=a.cache)
            for s in a.seqs.split(",")}
    res = evaluate(model, seqs, a.skip)
    for s, (r, t) in res.items():
        line = f"{s:20s} network RMSE {r:.5f}  temporal {t:.5f}"
        if seqs[s].post is not None:
            vr, vt, _ = ev.metrics(list(seqs[s].post), list(seqs[s].ref), a.skip)
            line += f"   (VCTAA {vr:.5f} / {vt:.5f})"
        print(line)
    if a.json:
        json.dump({s: {"rmse": r, "temporal": t} for s, (r, t) in res.items()},
                  open(a.json, "w"), indent=1)


if __name__ == "__main__":
    main()
