"""The TAA test-set report (tools/taa/README, "Three sets"): reads evaluate.py's eval.json
of the test sequences and checks the goals for each network against VCTAA, per sequence:
RMSE <= 0.8 x VCTAA's, temporal error <= VCTAA's, mean luminance within 3% of the
reference's (evaluate.py's "brightness": linear luminance, frames 8..). Beside it, as a
diagnostic only, the same ratio with luminance clamped at 1 (the display range): a few
emitter pixels of radiance up to ~2000 hold most of a scene's linear mean, and a filter
that blends in the tonemapped domain cannot keep them. Prints a markdown table and writes
a small JSON (the committed tools/taa/figures/test_set.json).

  /usr/bin/python3 -m tools.taa.test_report EVAL_OUT/eval.json --nets c6,c12 [--json OUT.json]"""
import argparse
import json
import os
import sys

import numpy as np

from tools.taa import eval as ev

GOAL_RMSE, GOAL_MEAN = 0.8, 0.03
SKIP = 8  # evaluate.py's default --skip


def luma(x):
    return x[..., 0] * 0.2126 + x[..., 1] * 0.7152 + x[..., 2] * 0.0722


def clamped_means(eval_dir, res, methods):
    """Mean luminance clamped at 1, each method's over the reference's (frames SKIP..)."""
    ref = ev.frames(res["folder"], "reference", ev.manifest(res["folder"]))[SKIP:]
    r = np.mean([np.minimum(luma(x), 1.0).mean() for x in ref])
    out = {}
    for m in methods:
        o = ev.frames(os.path.join(eval_dir, res["sequence"], m), "post")[SKIP:]
        out[m] = float(np.mean([np.minimum(luma(x), 1.0).mean() for x in o]) / r)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("eval_json", help="evaluate.py's OUT/eval.json")
    ap.add_argument("--nets", default="c6,c12", help="network labels to check (c6: the default, c12)")
    ap.add_argument("--json", default=None, help="write the per-sequence figures here")
    a = ap.parse_args()
    try:
        ev = json.load(open(a.eval_json))
    except (OSError, ValueError) as e:
        sys.exit(f"test_report: {a.eval_json}: {e}")
    results = ev["results"] if isinstance(ev, dict) and "results" in ev else ev
    nets = a.nets.split(",")
    out = {"goals": {"rmse_vs_vctaa": GOAL_RMSE, "temporal_vs_vctaa": 1.0, "mean_vs_reference": GOAL_MEAN},
           "sequences": []}
    print("| sequence | spp | method | RMSE | x VCTAA | temporal | x VCTAA | mean / ref | "
          "clamped mean / ref | goals met |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for res in results:
        by = {r["method"]: r for r in res["methods"]}
        if "vctaa" not in by:
            sys.exit(f"test_report: {a.eval_json}: {res['sequence']} has no vctaa row")
        vc = by["vctaa"]
        cm = clamped_means(os.path.dirname(os.path.abspath(a.eval_json)), res,
                           ["input", "vctaa"] + nets)
        seq = {"sequence": res["sequence"], "spp": res["spp"], "frames": res["frames"], "methods": {}}
        for m in ["input", "vctaa"] + nets:
            if m not in by:
                sys.exit(f"test_report: {a.eval_json}: {res['sequence']} has no {m!r} row")
            r = by[m]
            rr, tr = r["rmse"] / vc["rmse"], r["temporal"] / vc["temporal"]
            row = {"rmse": round(r["rmse"], 6), "temporal": round(r["temporal"], 6),
                   "rmse_vs_vctaa": round(rr, 4), "temporal_vs_vctaa": round(tr, 4),
                   "mean_vs_reference": round(r["brightness"], 4),
                   "clamped_mean_vs_reference": round(cm[m], 4)}
            if "flip" in r:
                row["flip"] = round(r["flip"], 5)
            met = ""
            if m in nets:
                row["met"] = {"rmse": rr <= GOAL_RMSE, "temporal": tr <= 1.0,
                              "mean": abs(r["brightness"] - 1) <= GOAL_MEAN}
                met = ", ".join(k + (" yes" if v else " NO") for k, v in row["met"].items())
            seq["methods"][m] = row
            print(f"| {res['sequence']} | {res['spp']} | {m} | {r['rmse']:.4f} | {rr:.3f} | "
                  f"{r['temporal']:.4f} | {tr:.3f} | {r['brightness']:.3f} | {cm[m]:.3f} | {met} |")
        out["sequences"].append(seq)
    for m in nets:
        n = sum(all(s["methods"][m]["met"].values()) for s in out["sequences"])
        print(f"\n{m}: all three goals met on {n} of {len(out['sequences'])} test sequences")
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(out, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
