"""Evaluates a weights file in PyTorch on whole sequences (as the C plugin runs them:
frame 0 and every reset start fresh, the state carries over otherwise) with eval.py's
metrics (tonemapped RMSE and temporal error, frames --skip.. ).

  /usr/bin/python3 -m tools.taa.eval_torch W.ttw DATA_DIR SEQ[,SEQ...] [--threads 1] [--cache DIR] [--json OUT]
  /usr/bin/python3 -m tools.taa.eval_torch --nets L=W.ttw,... DATA_DIR SEQ[,SEQ...] --eval-json OUT

The second form scores several networks on the sequences (decoded once) beside VCTAA (the
"post" frames the sequence was rendered with) and writes evaluate.py's eval.json format
(method rows with rmse, temporal, brightness = mean linear luminance / the reference's), the
input of select_val.py: a validation choice in minutes instead of one host run per network
and sequence."""
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


def luma_mean(x):
    return float((x[..., 0] * 0.2126 + x[..., 1] * 0.7152 + x[..., 2] * 0.0722).mean())


def eval_json(nets, seqs, skip):
    """evaluate.py-style results: per sequence, rows for vctaa (the stored post frames) and
    each network {label: weights file}."""
    models = {label: taa_model.load_weights(w) for label, w in nets.items()}
    results = []
    for name, s in seqs.items():
        if s.post is None or s.ref is None:
            raise SystemExit(f"eval_torch: {s.folder}: expected a sequence with \"post\" (VCTAA) "
                             "and \"reference\" frames (tools/taa/render_noisy.sh)")
        ref_l = [luma_mean(r) for r in s.ref]
        outs = {"vctaa": list(s.post), "input": list(s.color)}
        outs.update({label: list(run_sequence(m, s)) for label, m in models.items()})
        rows = []
        for label, out in outs.items():
            rmse, tmp, per = ev.metrics(out, list(s.ref), skip)
            br = [luma_mean(o) / max(r, 1e-12) for o, r in zip(out, ref_l)]
            rows.append({"method": label, "rmse": rmse, "temporal": tmp,
                         "rmse_per_frame": [float(v) for v in per],
                         "brightness": float(np.mean(br[skip:]))})
            print(f"{name:22s} {label:16s} RMSE {rmse:.5f} temporal {tmp:.5f} "
                  f"brightness {rows[-1]['brightness']:.3f}", flush=True)
        results.append({"sequence": name, "folder": os.path.abspath(s.folder), "frames": len(s.ref),
                        "spp": s.manifest.get("spp"), "methods": rows})
    return results


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("weights", nargs="?", default=None)
    ap.add_argument("data")
    ap.add_argument("seqs")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--cache", default=None)
    ap.add_argument("--skip", type=int, default=8)
    ap.add_argument("--json", default=None)
    ap.add_argument("--nets", default=None, help="LABEL=W.ttw,... (with --eval-json)")
    ap.add_argument("--eval-json", default=None, help="write evaluate.py's eval.json format")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    seqs = {s: dataset.Sequence(os.path.join(a.data, s), cache_dir=a.cache)
            for s in a.seqs.split(",")}
    if a.nets or a.eval_json:
        if not (a.nets and a.eval_json) or a.weights:
            raise SystemExit("eval_torch: --nets and --eval-json go together, without W.ttw")
        nets = dict(spec.split("=", 1) for spec in a.nets.split(","))
        res = eval_json(nets, seqs, a.skip)
        tmp = a.eval_json + ".tmp"
        json.dump(res, open(tmp, "w"), indent=1)
        os.replace(tmp, a.eval_json)
        return
    model = taa_model.load_weights(a.weights)
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
