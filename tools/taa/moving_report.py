"""TAA on sequences with moving objects: the goals (network RMSE <= 0.8 x VCTAA's, temporal
error <= VCTAA's, whole frames) per sequence from evaluate.py's eval.json, and the same two
errors inside the disocclusion regions, where a filter has no valid history: the pixels that
rejection.py's test marks (history disoccluded, e.g. uncovered behind a moving object, or
off-screen), grown by one pixel (the neighbourhood a 5 x 5 kernel mixes them into). The
masks come from the sequence's own depth, prevdepth and motion AOVs, which follow moving
objects as well as the camera. Frames from --skip (8) on, tonemapped space (eval.py's).

  /usr/bin/python3 -m tools.taa.moving_report EVAL_OUT/eval.json --nets c6,c12 [--json OUT.json]

prints a markdown table and writes the JSON (the committed tools/taa/figures/moving_objects.json)."""
import argparse
import json
import os
import sys

import numpy as np

from tools.common import images
from tools.taa import eval as ev
from tools.taa import rejection

GOAL_RMSE = 0.8


def fail(msg):
    sys.exit(f"moving_report: {msg}")


def region_masks(folder):
    """Per frame, bool (T, H, W): rejection.py's raw mask (disoccluded or off-screen), grown
    by one pixel; frames that start fresh (0 and cuts) are all False (nothing to reject)."""
    man = ev.manifest(folder)
    fr = man["frames"]
    for i, f in enumerate(fr):
        for k in ("depth", "motion", "prev_depth"):
            if k not in f:
                fail(f"{os.path.join(folder, 'manifest.json')}: frames[{i}] has no \"{k}\" "
                     "file; expected a sequence rendered with the depth, motion and prevdepth "
                     "AOVs (tools/taa/render_noisy.sh)")
    def aov(key, ch):  # AOVs have 1 (depth) or 2-3 (motion) channels: not eval.frames' RGB
        out = []
        for f in fr:
            try:
                out.append(images.read_exr(os.path.join(folder, f[key]))[..., ch])
            except IOError as e:
                fail(str(e))
        return np.stack(out)
    depth, zprev, motion = aov("depth", 0), aov("prev_depth", 0), aov("motion", slice(0, 2))
    jit = np.array([f.get("jitter", [0.0, 0.0]) for f in fr], np.float32)
    reset = np.array([bool(f.get("reset", False)) for f in fr])
    raw, _ = rejection.sequence_masks(depth, zprev, motion, jit, reset)
    m = raw > 0
    m[0] = False
    m[reset] = False
    return np.stack([rejection._morph(x, False) for x in m])


def region_errors(outs, ref, mask, skip):
    """RMSE and temporal error (eval.py's definitions) over the masked pixels of frames
    skip..; the temporal term of frame t counts the pixels masked in frame t."""
    o = np.stack([ev.tm(x) for x in outs])
    r = np.stack([ev.tm(x) for x in ref])
    se = ((o - r) ** 2).mean(-1)
    rm = [np.sqrt(se[t][mask[t]].mean()) for t in range(skip, len(o)) if mask[t].any()]
    td = np.abs((o[1:] - o[:-1]) - (r[1:] - r[:-1])).mean(-1)
    tp = [td[t - 1][mask[t]].mean() for t in range(max(skip, 1), len(o)) if mask[t].any()]
    return (float(np.mean(rm)) if rm else float("nan"),
            float(np.mean(tp)) if tp else float("nan"))


def ratio(a, b):
    """a / b rounded, None where b is 0 (nothing to compare with)."""
    return round(a / b, 4) if b > 0 else None


def fmt(v, d=3):
    return "-" if v is None else f"{v:.{d}f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("eval_json", help="evaluate.py's OUT/eval.json")
    ap.add_argument("--nets", default="c6,c12", help="network labels to check (c6: the default, c12)")
    ap.add_argument("--skip", type=int, default=8, help="warm-up frames left out (8)")
    ap.add_argument("--json", default=None, help="write the per-sequence figures here")
    a = ap.parse_args()
    try:
        results = json.load(open(a.eval_json))
    except (OSError, ValueError) as e:
        fail(f"{a.eval_json}: {e}")
    if not isinstance(results, list) or not results:
        fail(f"{a.eval_json}: expected evaluate.py's list of sequence results")
    eval_dir = os.path.dirname(os.path.abspath(a.eval_json))
    nets = a.nets.split(",")
    out = {"goals": {"rmse_vs_vctaa": GOAL_RMSE, "temporal_vs_vctaa": 1.0},
           "region": "disocclusion (rejection.py raw mask, grown by 1 px)", "skip": a.skip,
           "sequences": []}
    print("| sequence | spp | method | RMSE | x VCTAA | temporal | x VCTAA | disocclusion RMSE "
          "| x VCTAA | disocclusion temporal | x VCTAA | goals met |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for res in results:
        by = {r["method"]: r for r in res["methods"]}
        for m in ["vctaa"] + nets:
            if m not in by:
                fail(f"{a.eval_json}: {res['sequence']} has no {m!r} row")
        mask = region_masks(res["folder"])
        ref = ev.frames(res["folder"], "reference")
        frac = float(mask[a.skip:].mean())
        seq = {"sequence": res["sequence"], "spp": res["spp"], "frames": res["frames"],
               "region_fraction": round(frac, 5), "methods": {}}
        reg = {}
        for m in ["input", "vctaa"] + nets:
            if m not in by:
                continue
            outs = ev.frames(os.path.join(eval_dir, res["sequence"], m), "post")
            reg[m] = region_errors(outs, ref, mask, a.skip)
        vc, vr = by["vctaa"], reg["vctaa"]
        for m in reg:
            r = by[m]
            row = {"rmse": round(r["rmse"], 6), "temporal": round(r["temporal"], 6),
                   "rmse_vs_vctaa": round(r["rmse"] / vc["rmse"], 4),
                   "temporal_vs_vctaa": round(r["temporal"] / vc["temporal"], 4),
                   "region_rmse": round(reg[m][0], 6), "region_temporal": round(reg[m][1], 6),
                   "region_rmse_vs_vctaa": ratio(reg[m][0], vr[0]),
                   "region_temporal_vs_vctaa": ratio(reg[m][1], vr[1])}
            met = ""
            if m in nets:
                row["met"] = {"rmse": row["rmse_vs_vctaa"] <= GOAL_RMSE,
                              "temporal": row["temporal_vs_vctaa"] <= 1.0}
                met = ", ".join(k + (" yes" if v else " NO") for k, v in row["met"].items())
            seq["methods"][m] = row
            print(f"| {res['sequence']} | {res['spp']} | {m} | {row['rmse']:.4f} | "
                  f"{row['rmse_vs_vctaa']:.3f} | {row['temporal']:.4f} | "
                  f"{row['temporal_vs_vctaa']:.3f} | {row['region_rmse']:.4f} | "
                  f"{fmt(row['region_rmse_vs_vctaa'])} | {row['region_temporal']:.4f} | "
                  f"{fmt(row['region_temporal_vs_vctaa'])} | {met} |")
        print(f"({res['sequence']}: disocclusion region {100 * frac:.2f}% of the pixels of "
              f"frames {a.skip}..)")
        out["sequences"].append(seq)
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(out, f, indent=1)
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
