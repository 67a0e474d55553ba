"""predict() against one 1-spp frame, on evaluate.py's validation protocol (issue 15's goal:
predict() below 1% of a frame), and whether a changed predictor answers the same.

Prints two tables: per objective and model (against the median frame), and per scene
(against that scene's frame: the goal holds only if it holds on the cheapest scene).

For every protocol of evaluate.py (15 random 80/20 camera splits per scene and
leave-one-scene-out) and objective, each model is trained by `host --predict --warm-start
TRAIN.db --states VAL.json` from the training cameras' rows (evaluate.py's functions, so the
same training databases and states) and predicts every validation camera. The host times
each predict() as the median of 5 calls (CPU time of the thread). The frame is the
validation camera's default configuration rendered at 1 spp, its cost in the baseline
(`hybrid_jobs.default_cost` of the render job: CPU ms of one thread at the baseline's
resolution).

With `--reference-host H` every prediction is made by H too, interleaved protocol by
protocol (so both see the same load), and the answers are compared: the configuration
must be the same, and the reported Q (`value`) is compared in relative terms. This is how a
faster predict() is shown to answer what the earlier one answered.

  /usr/bin/python3 -m tools.hybrid.predict_cost --db /tmp/hybrid/baseline.db --work /tmp/hybrid/pc \\
      --models rbf --reference-host OLD_HOST --out tools/hybrid/figures/predict_cost

The training databases and predictions are cached in --work (per host, not per --set: give
each set of --set its own --work).
"""
import json
import os
import sys

from tools.hybrid import evaluate as ev
from tools.tttools import cli, host


def median(xs):
    xs = sorted(x for x in xs if x is not None)
    return xs[len(xs) // 2] if xs else None


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--db", required=True, help="baseline database (tools/hybrid/baseline.py)")
    ap.add_argument("--work", required=True, help="cache of training DBs and predictions")
    ap.add_argument("--out", default=None, help="folder for predict_cost.json/.md")
    ap.add_argument("--reference-host", default=None, help="a host whose answers must be the same")
    ap.add_argument("--objectives", default="render,build+render")
    ap.add_argument("--models", default="rbf")
    ap.add_argument("--splits", type=int, default=15)
    ap.add_argument("--val", type=float, default=0.2)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--min-cameras", type=int, default=5)
    ap.add_argument("--set", action="append", default=[], metavar="PLUGIN.KEY=VALUE",
                    help="a predictor setting for that predictor's runs (both hosts), e.g. "
                         "predictor_rbf.lhsCandidates=210: an argmax over about 260 candidates "
                         "on a baseline whose pool is not full yet")
    a = ap.parse_args()
    objectives = a.objectives.split(",")
    models = a.models.split(",")
    for m in models:
        if m not in ev.MODELS:
            sys.exit(f"predict_cost: --models: unknown model {m!r} (known: {', '.join(ev.MODELS)})")
    jobs, _ = ev.load_jobs(a.db, objectives)
    cams = ev.cameras(jobs, objectives, a.min_cameras)
    if not cams:
        sys.exit(f"predict_cost: {a.db}: no scene has {a.min_cameras} cameras with every objective done")
    ind = ev.camera_indicators(a.db, jobs, cams)
    args = {m: [x for kv in a.set if kv.split(".")[0] == ev.MODELS[m] for x in ("--set", kv)]
            for m in models}
    for kv in a.set:
        if kv.split(".")[0] not in (ev.MODELS[m] for m in models):
            sys.exit(f"predict_cost: --set {kv}: no model of --models is that plugin")
    a.host = host.find(a.host)
    hosts = [("new", a.host)] + ([("ref", host.find(a.reference_host))] if a.reference_host else [])
    for d in ("train",) + tuple(f"pred_{h}" for h, _ in hosts):
        os.makedirs(os.path.join(a.work, d), exist_ok=True)
    rows = []
    for name, train, val in ev.protocols(cams, a.splits, a.val, True, a.seed):
        for o in objectives:
            job = next(j for (s, c, oo), j in jobs.items() if oo == o)
            tdb = ev.training_db(a, jobs, train, o, os.path.join(a.work, "train", f"{name}_{o}.db"))
            states = [(s, c, ind[(s, c)]) for s in sorted(val) for c in val[s]]
            for m in models:
                got = {}
                for h, path in hosts:  # interleaved: both hosts at the same load
                    a.host = path
                    p = ev.predict(a, job, m, {"args": args[m]}, tdb, states, o,
                                   os.path.join(a.work, f"pred_{h}", f"{name}_{o}_{m}.json"))
                    got[h] = {item["id"]: item for item in p["predictions"]}
                a.host = hosts[0][1]
                for s, c, _ in states:
                    n = got["new"].get(f"{s}:{c}", {})
                    r = got.get("ref", {}).get(f"{s}:{c}", {})
                    row = {"protocol": name, "objective": o, "model": m, "scene": s, "camera": c,
                           "predict_ms": n.get("predict_ms"), "error": n.get("error"),
                           "frame_ms": jobs[(s, c, "render")]["default_cost"] if (s, c, "render") in jobs else None}
                    if "ref" in got:
                        row["ref_predict_ms"] = r.get("predict_ms")
                        # the same configuration, or both refused (no training data)
                        nc, rc = n.get("config"), r.get("config")
                        row["same_config"] = (ev.canon(nc) == ev.canon(rc) if nc is not None and rc is not None
                                              else nc is None and rc is None and "error" in n and "error" in r)
                        nv, rv = n.get("value"), r.get("value")
                        row["value_rel_diff"] = (abs(nv - rv) / abs(rv) if nv is not None and rv else None)
                    rows.append(row)
    summary = {"cameras": {s: len(cs) for s, cs in cams.items()}, "table": {}}
    for o in objectives:
        for m in models:
            sel = [r for r in rows if r["objective"] == o and r["model"] == m]
            refused = sum(1 for r in sel if r["error"])
            t = {"n": len(sel), "refused": refused, "predict_ms_median": median(r["predict_ms"] for r in sel),
                 "frame_ms_median": median(r["frame_ms"] for r in sel),
                 "frame_ms_min": min((r["frame_ms"] for r in sel if r["frame_ms"]), default=None),
                 "predict_ms_max": max((r["predict_ms"] for r in sel if r["predict_ms"]), default=None)}
            t["share_of_frame"] = (t["predict_ms_median"] / t["frame_ms_median"]
                                   if t["predict_ms_median"] and t["frame_ms_median"] else None)
            if a.reference_host:
                t["ref_predict_ms_median"] = median(r["ref_predict_ms"] for r in sel)
                t["same_config"] = sum(1 for r in sel if r["same_config"])
                diffs = [r["value_rel_diff"] for r in sel if r["value_rel_diff"] is not None]
                t["value_rel_diff_max"] = max(diffs) if diffs else None
            summary["table"][f"{o}/{m}"] = t
    lines = ["| objective / model | predictions (refused: no data) | predict ms (median / max) | frame ms (median / cheapest) | share of the median frame |"
             + (" reference predict ms | same configuration | max rel. Q difference |" if a.reference_host else ""),
             "|---|---|---|---|---|" + ("---|---|---|" if a.reference_host else "")]
    f = lambda x, fmt="{:.3g}": "-" if x is None else fmt.format(x)
    for k, t in summary["table"].items():
        line = (f"| {k} | {t['n']} ({t['refused']}) | {f(t['predict_ms_median'])} / {f(t['predict_ms_max'])} | {f(t['frame_ms_median'])} / {f(t['frame_ms_min'])} | "
                f"{f(t['share_of_frame'], '{:.2%}')} |")
        if a.reference_host:
            line += (f" {f(t['ref_predict_ms_median'])} | {t['same_config']} of {t['n']} | "
                     f"{f(t['value_rel_diff_max'], '{:.1e}')} |")
        lines.append(line)
    # per scene: the goal is below 1% of a frame on every scene, so the cheapest frame decides
    lines += ["", "| scene | frame ms | predict ms (median, all objectives/models) | share of the frame |"
              + (" reference predict ms | reference share |" if a.reference_host else ""),
              "|---|---|---|---|" + ("---|---|" if a.reference_host else "")]
    summary["scenes"] = {}
    for s in sorted({r["scene"] for r in rows}):
        sel = [r for r in rows if r["scene"] == s]
        t = {"frame_ms": median(r["frame_ms"] for r in sel), "predict_ms": median(r["predict_ms"] for r in sel)}
        t["share"] = t["predict_ms"] / t["frame_ms"] if t["predict_ms"] and t["frame_ms"] else None
        line = f"| {s} | {f(t['frame_ms'])} | {f(t['predict_ms'])} | {f(t['share'], '{:.2%}')} |"
        if a.reference_host:
            t["ref_predict_ms"] = median(r["ref_predict_ms"] for r in sel)
            t["ref_share"] = (t["ref_predict_ms"] / t["frame_ms"] if t["ref_predict_ms"] and t["frame_ms"]
                              else None)
            line += f" {f(t['ref_predict_ms'])} | {f(t['ref_share'], '{:.2%}')} |"
        summary["scenes"][s] = t
        lines.append(line)
    md = "\n".join(lines) + "\n"
    print(md, end="")
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        for fn, text in (("predict_cost.json", json.dumps({"summary": summary, "rows": rows}, indent=1)),
                         ("predict_cost.md", md)):
            tmp = os.path.join(a.out, fn + ".tmp")
            with open(tmp, "w") as fh:
                fh.write(text)
            os.replace(tmp, os.path.join(a.out, fn))
    if a.reference_host and any(not r["same_config"] for r in rows):
        print("predict_cost: the hosts answer differently for "
              f"{sum(1 for r in rows if not r['same_config'])} predictions", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
