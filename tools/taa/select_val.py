"""Chooses a TAA network on the validation sequences only (tools/taa/README, "Three sets"),
by a rule fixed before any result is seen:

  1. per network, the validation sequences on which it meets both quality goals
     (RMSE <= 0.8 x VCTAA's, temporal error <= VCTAA's); most wins;
  2. among those with the most, the geometric mean of the validation RMSEs decides the best;
  3. size rule: the smallest network (FLOP per pixel) among them whose geo-mean RMSE is
     within 1% of that best ships.

Reads evaluate.py's eval.json of the validation sequences; the networks and their weights
files come as LABEL=W.ttw (the files give the size; numpy only, no torch).

  /usr/bin/python3 -m tools.taa.select_val VAL_EVAL/eval.json LABEL=W.ttw... [--json OUT]"""
import argparse
import json
import math
import os
import sys

from tools.taa import ttw

GOAL_RMSE, SIZE_TOL = 0.8, 0.01


def fail(msg):
    sys.exit(f"select_val: {msg}")


def flops(path):
    """FLOP per pixel of one frame (Table 5.1's count: 2 K^2 I O + O per layer)."""
    try:
        return ttw.read(path).flops_per_pixel()
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")


def choose(results, nets):
    """nets: {label: flops}. Returns (rows sorted best first, the chosen label)."""
    rows = []
    for label, fl in nets.items():
        met, logs, seqs = 0, [], {}
        for res in results:
            by = {r["method"]: r for r in res["methods"]}
            if label not in by or "vctaa" not in by:
                fail(f"{res['sequence']}: no {label if label not in by else 'vctaa'!r} row "
                     "in the evaluation")
            r, v = by[label], by["vctaa"]
            rr, tr = r["rmse"] / v["rmse"], r["temporal"] / v["temporal"]
            ok = rr <= GOAL_RMSE and tr <= 1.0
            met += ok
            logs.append(math.log(r["rmse"]))
            seqs[res["sequence"]] = {"rmse_vs_vctaa": round(rr, 4), "temporal_vs_vctaa": round(tr, 4),
                                     "mean_vs_reference": round(r.get("brightness", float("nan")), 4),
                                     "met": bool(ok)}
        rows.append({"net": label, "flops": fl, "met": met, "of": len(results),
                     "geo_rmse": math.exp(sum(logs) / len(logs)), "sequences": seqs})
    rows.sort(key=lambda r: (-r["met"], r["geo_rmse"]))
    top = [r for r in rows if r["met"] == rows[0]["met"]]
    best = top[0]["geo_rmse"]
    near = [r for r in top if r["geo_rmse"] <= best * (1 + SIZE_TOL)]
    chosen = min(near, key=lambda r: (r["flops"], r["geo_rmse"]))["net"]
    return rows, chosen


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("eval_json", help="evaluate.py's OUT/eval.json of the validation sequences")
    ap.add_argument("nets", nargs="+", help="LABEL=W.ttw, each a --net of that evaluation")
    ap.add_argument("--json", default=None, help="write the table and the choice here")
    a = ap.parse_args()
    try:
        results = json.load(open(a.eval_json))
    except (OSError, ValueError) as e:
        fail(f"{a.eval_json}: {e}")
    if not isinstance(results, list) or not results:
        fail(f"{a.eval_json}: expected evaluate.py's list of sequence results")
    nets = {}
    for spec in a.nets:
        if "=" not in spec:
            fail(f"{spec}: expected LABEL=W.ttw")
        label, path = spec.split("=", 1)
        nets[label] = flops(path)
    rows, chosen = choose(results, nets)
    print("| network | FLOP/px | goals met | geo-mean RMSE | " +
          " | ".join(res["sequence"] for res in results) + " |")
    print("|---|---|---|---|" + "---|" * len(results))
    for r in rows:
        cells = [f"{s['rmse_vs_vctaa']:.3f} / {s['temporal_vs_vctaa']:.3f} / {s['mean_vs_reference']:.3f}"
                 for s in r["sequences"].values()]
        print(f"| {r['net']}{' (chosen)' if r['net'] == chosen else ''} | {r['flops']} | "
              f"{r['met']} / {r['of']} | {r['geo_rmse']:.5f} | " + " | ".join(cells) + " |")
    print("\nCells: RMSE x VCTAA / temporal x VCTAA / mean vs reference.")
    print(f"chosen: {chosen}")
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump({"rule": __doc__.split("\n\n")[1], "chosen": chosen, "rows": rows}, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
