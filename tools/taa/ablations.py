"""Thesis 5.6 ablations at reduced scale: trains each variant with train.py from scratch (or,
--init, from given weights of its width) for each seed (same data, steps, batch, patch,
burn-in), evaluates it in PyTorch on the validation sequences, and prints a markdown table with the per-seed and mean scores, the
parameter count and FLOP/px; nominates the smallest variant (FLOP/px, then parameters) whose
mean score is within 1% of the best (a nomination only: README "Size rule"). The score of a run is the geometric mean of its
validation RMSEs (the sequences' error scales differ by 3x between 1 and 8 spp, so an
arithmetic mean would only rank the noisiest one).

  /usr/bin/python3 -m tools.taa.ablations --data D1,D2 --scenes ... --val ... --out DIR [--steps 1000] [--batch 4]
               [--patch 32] [--burn 16] [--seeds 1,2,3] [--jobs 2]
               [--variants h5,h0,h0-in,h0-reset,...] [--cache DIR] [--lr 1e-3]
               [--init 12=W12.ttw,6=W6.ttw]

Runs already in DIR (their .train.json) are kept: the command resumes."""
import argparse
import json
import math
import os
import subprocess
import sys
import time

from tools.taa import taa_model

# name: (width, hidden, body, jitter layers, kernel-layer size, rejection)
VARIANTS = {
    "h5": (12, 5, "3,3,5", "b2 b3 k", 5, "none"),      # the earlier shipped shape (2-3-K)
    "h0": (12, 0, "3,3,5", "b2 b3 k", 5, "none"),
    "h3": (12, 3, "3,3,5", "b2 b3 k", 5, "none"),
    "h0-in": (12, 0, "3,3,5", "b2 b3 k", 5, "input"),  # + the rejection input
    "h0-reset": (12, 0, "3,3,5", "b2 b3 k", 5, "reset"),  # + history reset
    "h5-reset": (12, 5, "3,3,5", "b2 b3 k", 5, "reset"),
    "nojit": (12, 5, "3,3,5", "", 5, "none"),
    "kh": (12, 5, "3,3,5", "b2 b3 k h", 5, "none"),
    "l2": (12, 5, "3,5", "b1 b2 k", 5, "none"),
    "l4": (12, 5, "3,3,3,5", "b3 b4 k", 5, "none"),
}
for w in (12, 6):   # width x kernel-layer size, with hidden 0 and the history reset
    for k in (5, 3, 1):
        VARIANTS[f"w{w}k{k}"] = (w, 0, "3,3,5", "b2 b3 k", k, "reset")
        VARIANTS[f"w{w}k{k}-in"] = (w, 0, "3,3,5", "b2 b3 k", k, "input")
        VARIANTS[f"w{w}k{k}-h5"] = (w, 5, "3,3,5", "b2 b3 k", k, "none")


def shape(v):
    width, hidden, body, jit, k, rej = VARIANTS[v]
    flags = {"none": 0, "input": taa_model.FLAG_REJECT,
             "reset": taa_model.FLAG_REJECT | taa_model.FLAG_RESET}[rej]
    m = taa_model.TAANet(width, hidden, tuple(int(x) for x in body.split(",")), jit, flags=flags,
                         kernel=k)
    return sum(p.numel() for p in m.parameters()), sum(r[-1] for r in m.flops_per_pixel())


def command(a, v, seed, out):
    width, hidden, body, jit, k, rej = VARIANTS[v]
    cmd = [sys.executable, "-m", "tools.taa.train", "--data", a.data, "--scenes", a.scenes,
           "--val", a.val, "--out", out, "--width", str(width), "--hidden", str(hidden),
           "--body", body, "--jitter-layers", jit, "--kernel", str(k), "--reject", rej,
           "--steps", str(a.steps), "--minutes", "100000", "--batch", str(a.batch),
           "--patch", str(a.patch), "--burn", str(a.burn), "--threads", "1",
           "--seed", str(seed), "--lr", str(a.lr)]
    if a.init:
        inits = dict(x.split("=", 1) for x in a.init.split(","))
        if str(width) in inits:
            cmd += ["--init", inits[str(width)]]
    if a.cache:
        cmd += ["--cache", a.cache]
    return cmd


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", required=True)
    ap.add_argument("--scenes", required=True)
    ap.add_argument("--val", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--steps", type=int, default=1000)
    ap.add_argument("--batch", type=int, default=4)
    ap.add_argument("--patch", type=int, default=32)
    ap.add_argument("--burn", type=int, default=16)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--jobs", type=int, default=1, help="trainings run side by side")
    ap.add_argument("--variants", default="h5,h0,h0-in,h0-reset")
    ap.add_argument("--cache", default=None)
    ap.add_argument("--nice", type=int, default=19)
    ap.add_argument("--lr", type=float, default=1e-3)
    ap.add_argument("--init", default=None,
                    help="WIDTH=W.ttw,...: fine-tune the variants of that width from W.ttw "
                         "(train.py --init: inputs mapped by meaning, 1 set -> 8) instead of "
                         "training them from scratch")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    variants = a.variants.split(",")
    for v in variants:
        if v not in VARIANTS:
            sys.exit(f"ablations.py: unknown variant {v} (known: {', '.join(VARIANTS)})")
    seeds = [int(s) for s in a.seeds.split(",")]
    todo = [(v, s) for s in seeds for v in variants
            if not os.path.exists(os.path.join(a.out, f"{v}_s{s}.ttw.train.json"))]
    running = []
    while todo or running:
        while todo and len(running) < a.jobs:
            v, s = todo.pop(0)
            out = os.path.join(a.out, f"{v}_s{s}.ttw")
            cmd = ["nice", "-n", str(a.nice)] + command(a, v, s, out)
            print(" ".join(cmd), flush=True)
            log = open(out + ".log", "w")
            running.append((subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT), log, v, s))
        time.sleep(5)
        for r in list(running):
            if r[0].poll() is not None:
                r[1].close()
                running.remove(r)
                if r[0].returncode:
                    sys.exit(f"ablations.py: {r[2]} seed {r[3]} failed (log {a.out}/{r[2]}_s{r[3]}.ttw.log)")
                print(f"done {r[2]} seed {r[3]}", flush=True)
    rows = []
    for v in variants:
        runs = []
        for s in seeds:
            meta = json.load(open(os.path.join(a.out, f"{v}_s{s}.ttw.train.json")))
            ev = meta["evals"][-1]
            vals = {k: ev[k] for k in ev if isinstance(ev[k], dict)}
            runs.append({"seed": s, "steps": meta["steps"], "minutes": meta["elapsed_s"] / 60.0,
                         "vals": vals,
                         "score": math.exp(sum(math.log(x["rmse"]) for x in vals.values()) / len(vals))})
        n_par, flops = shape(v)
        seqs = list(runs[0]["vals"])
        mean = {q: {m: sum(r["vals"][q][m] for r in runs) / len(runs) for m in ("rmse", "temporal")}
                for q in seqs}
        rows.append({"variant": v, "shape": VARIANTS[v], "params": n_par, "flops": flops,
                     "runs": runs, "mean": mean,
                     "score": sum(r["score"] for r in runs) / len(runs)})
    json.dump(rows, open(os.path.join(a.out, "ablations.json"), "w"), indent=1)
    seqs = list(rows[0]["mean"])
    print("| variant | width | hidden | kernel | rejection | params | FLOP/px | " +
          " | ".join(f"{q} RMSE / temporal" for q in seqs) + " | score per seed | mean score |")
    print("|---" * (9 + len(seqs)) + "|")
    for r in rows:
        w, h, _, _, k, rej = r["shape"]
        print(f"| {r['variant']} | {w} | {h} | {k}x{k} | {rej} | {r['params']} | {r['flops']} | " +
              " | ".join(f"{r['mean'][q]['rmse']:.5f} / {r['mean'][q]['temporal']:.5f}" for q in seqs) +
              " | " + " / ".join(f"{x['score']:.5f}" for x in r["runs"]) + f" | {r['score']:.5f} |")
    best = min(r["score"] for r in rows)
    ok = [r for r in rows if r["score"] <= 1.01 * best]
    pick = min(ok, key=lambda r: (r["flops"], r["params"]))
    print(f"best mean score {best:.5f}; smallest within 1%: {pick['variant']} "
          f"({pick['flops']} FLOP/px, {pick['params']} parameters)")


if __name__ == "__main__":
    main()
