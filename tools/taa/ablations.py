#!/usr/bin/python3
"""Thesis 5.6 ablations at reduced scale: trains each variant with train.py from scratch
(same data, seed, steps, batch and patch) and evaluates it in PyTorch on the held-back
sequences; prints a markdown table and picks the smallest variant within 1% of the best
held-back RMSE (mean over the held-back sequences).

  ablations.py --data D1,D2 --scenes ... --val ... --out DIR [--steps 600] [--batch 4]
               [--patch 32] [--variants base,nojit,kh,h0,h3,h8,l2,l4] [--cache DIR]"""
import argparse
import json
import os
import subprocess
import sys

import taa_model

VARIANTS = {   # name: (hidden, body, jitter layers)
    "base": (5, "3,3,5", "b2 b3 k"),       # shipped architecture (2-3-K)
    "nojit": (5, "3,3,5", ""),             # one weight set everywhere
    "kh": (5, "3,3,5", "b2 b3 k h"),       # 2-3-K-H: jitter sets in the hidden layer too
    "h0": (0, "3,3,5", "b2 b3 k"),
    "h3": (3, "3,3,5", "b2 b3 k"),
    "h8": (8, "3,3,5", "b2 b3 k"),
    "l2": (5, "3,5", "b1 b2 k"),            # 2 body layers, jitter sets in the last 3 layers
    "l4": (5, "3,3,3,5", "b3 b4 k"),        # 4 body layers, jitter sets in the last 3 layers
}


def params(hidden, body, jit, width):
    m = taa_model.TAANet(width, hidden, tuple(int(k) for k in body.split(",")), jit)
    n_par = sum(p.numel() for p in m.parameters())
    flops = sum(r[-1] for r in m.flops_per_pixel())
    return n_par, flops


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--scenes", required=True)
    ap.add_argument("--val", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--batch", type=int, default=4)
    ap.add_argument("--patch", type=int, default=32)
    ap.add_argument("--width", type=int, default=12)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--cache", default=None)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    here = os.path.dirname(os.path.abspath(__file__))
    rows = []
    for v in a.variants.split(","):
        hidden, body, jit = VARIANTS[v]
        w = os.path.join(a.out, f"{v}.ttw")
        if not os.path.exists(w + ".train.json"):
            cmd = [sys.executable, os.path.join(here, "train.py"), "--data", a.data,
                   "--scenes", a.scenes, "--val", a.val, "--out", w, "--width", str(a.width),
                   "--hidden", str(hidden), "--body", body, "--jitter-layers", jit,
                   "--steps", str(a.steps), "--minutes", "1000", "--batch", str(a.batch),
                   "--patch", str(a.patch), "--threads", "1", "--seed", str(a.seed)]
            if a.cache:
                cmd += ["--cache", a.cache]
            print(" ".join(cmd), flush=True)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
        meta = json.load(open(w + ".train.json"))
        ev = meta["evals"][-1]
        n_par, flops = params(hidden, body, jit, a.width)
        vals = [k for k in ev if isinstance(ev[k], dict)]
        rows.append({"variant": v, "hidden": hidden, "body": body, "jitter": jit or "-",
                     "params": n_par, "flops": flops, "steps": meta["steps"],
                     "minutes": meta["elapsed_s"] / 60.0,
                     **{f"{k}_rmse": ev[k]["rmse"] for k in vals},
                     **{f"{k}_tmp": ev[k]["temporal"] for k in vals},
                     "mean_rmse": sum(ev[k]["rmse"] for k in vals) / len(vals)})
        json.dump(rows, open(os.path.join(a.out, "ablations.json"), "w"), indent=1)
        print(rows[-1], flush=True)
    vals = [k[:-5] for k in rows[0] if k.endswith("_rmse") and k != "mean_rmse"]
    print("| variant | hidden | body | jitter sets | params | FLOP/px | " +
          " | ".join(f"{k} RMSE | {k} temporal" for k in vals) + " | mean RMSE |")
    print("|---" * (7 + 2 * len(vals)) + "|")
    for r in rows:
        print(f"| {r['variant']} | {r['hidden']} | {r['body']} | {r['jitter']} | {r['params']} | "
              f"{r['flops']} | " + " | ".join(f"{r[k + '_rmse']:.5f} | {r[k + '_tmp']:.5f}"
                                               for k in vals) + f" | {r['mean_rmse']:.5f} |")
    best = min(r["mean_rmse"] for r in rows)
    ok = [r for r in rows if r["mean_rmse"] <= 1.01 * best]
    pick = min(ok, key=lambda r: r["flops"])
    print(f"best mean RMSE {best:.5f}; smallest within 1%: {pick['variant']} "
          f"({pick['flops']} FLOP/px)")


if __name__ == "__main__":
    main()
