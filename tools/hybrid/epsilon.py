"""Hybrid autotuning along camera paths (thesis 3.3, Figure 3.14's loop) for several epsilon:
`host --hybrid` itself, end to end, against pure search (epsilon 1).

Per scene and objective, one run of `host --hybrid --epsilon E --iterations K --camera-index
A:B` per epsilon and predictor: the camera moves through the path samples A..B (consecutive
states, as a camera moving along its path); at each state the loop explores (a K-iteration
Nelder-Mead search, every sample observed by the model) with probability E, else exploits
(one predicted configuration, built once). The model is warm-started from the baseline
database *without the rows of any scene tested* (--scenes: what a renderer shipping a model
trained elsewhere would have; a test scene's rows would leak into another's runs) and learns
online along the path; every run writes a fresh database, so no
search is answered from an earlier one. Each state renders F frames (--spp F, default K + 1:
the search's default + K iterations, so an explored state is exactly its search).

Time for F frames per state (thesis 3.3.5: the area under the cost curve):
  explore state  sum of the search's sample costs + (F - samples) x the best's cost
  exploit state  F x the predicted configuration's measured cost
  speed-up over pure search = T(epsilon = 1) / T(epsilon)
The objective's cost per frame is what the loop measured (render: the pass; build+render:
rebuild + pass, the real-time case, where every frame pays the build). For `render` the
host's own per-state clock (--clock cpu) over the state's F passes, predictor calls and
searches included, is reported beside it (`measured`), and the CPU seconds of each host
process (scene loading and warm start included).

  /usr/bin/python3 -m tools.hybrid.epsilon --db /tmp/hybrid/baseline.db --work /tmp/hybrid/epsilon \
      --out tools/hybrid/figures
"""
import hashlib
import math
import json
import os
import sys
import time

from tools.hybrid import baseline
from tools.tttools import cli, host
from tools.tttools import db as tunedb

MODELS = {"nn": "predictor_nn", "rbf": "predictor_rbf", "static": "predictor_static"}


def scene_files(path):
    """{name: (scene file, scene id)} of the baseline's finished jobs."""
    return {r["scene"]: (r["scene_file"], r["scene_id"]) for r in baseline.read_jobs(path)}


def warm_start(src_path, files, test_scenes, work):
    """The warm start of every run: a copy of the baseline's samples without the rows of any
    test scene (--scenes), so no run learns from a scene it is later tested on. Refused when
    no other scene is left to learn from."""
    ids = sorted({files[s][1] for s in test_scenes})
    rest = sorted(s for s, (_, sid) in files.items() if sid not in ids)
    if not rest:
        sys.exit(f"epsilon: every scene of {src_path} ({', '.join(sorted(files))}) is a test scene "
                 f"(--scenes): no scene is left to warm-start the models from")
    path = os.path.join(work, "without_" + "+".join(sorted(test_scenes)) + ".db")
    return tunedb.copy_samples(src_path, path, lambda r: r["scene_id"] not in ids)


def model_sets(a, model):
    """The --set arguments of `a.set` that name this model's plugin (PLUGIN.KEY=VALUE)."""
    out = []
    for kv in a.set:
        if kv.split(".", 1)[0] == MODELS[model]:
            out += ["--set", kv]
    return out


def run_name(a, scene, obj, eps, model, seed):
    """A run's cache file name: seed 1 and no --set keep the names of the first runs."""
    name = f"{scene}_{obj.replace('+', '_')}_eps{eps:g}_{model}"
    sets = model_sets(a, model) if eps < 1.0 else []
    if sets:
        name += "_" + hashlib.sha1(" ".join(sets).encode()).hexdigest()[:8]
    if seed != 1:
        name += f"_seed{seed}"
    return name + ".json"


def run(a, scene, sfile, warm, obj, eps, model, seed, path):
    """One host --hybrid run, cached in `path` (its --stats plus the process' CPU seconds);
    a cached run warm-started from another file (another set of test scenes) runs again."""
    if os.path.exists(path):
        with open(path) as f:
            out = json.load(f)
        # runs cached before the name was recorded were warm-started without their own scene
        if warm is None or out.get("warm_start", f"without_{scene}.db") == os.path.basename(warm):
            return out
    db = path[:-5] + ".db"
    for p in (db, db + "-wal", db + "-shm"):
        if os.path.exists(p):
            os.remove(p)
    args = ["--quiet", "--hybrid", "--plugin", MODELS[model], "--epsilon", f"{eps:g}",
            "--iterations", str(a.iterations), "--camera-index", a.states, "--objective", obj,
            "--tune-spp", "1", "--spp", str(a.frames), "--res", a.res, "--threads", "1",
            "--clock", "cpu", "--seed", str(seed), "--tune-params", a.tune_params,
            "--warm-start", warm, "--db", db] + (model_sets(a, model) if eps < 1.0 else []) + [sfile]
    r = host.run(a.host, args, nice=a.nice, stats=True, capture=True)
    out = {"scene": scene, "objective": obj, "epsilon": eps, "model": model, "seed": seed,
           "command": [a.host] + args, "wall_s": r.wall_s, "load1": os.getloadavg()[0],
           "cpu_s": r.cpu_s, "warm_start": os.path.basename(warm), "hybrid": r.stats["hybrid"]}
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f)
    os.replace(tmp, path)
    return out


def totals(res, frames):
    """Time for `frames` frames per state: modelled from the costs, and the host's clock."""
    T = measured = 0.0
    n = {"explore": 0, "exploit": 0, "fallback": 0}
    for s in res["hybrid"]["states"]:
        # an infeasible or failed measurement leaves no cost: the state then ran its default
        cost = s["cost"] if s["cost"] is not None else s["default_cost"] or 0.0
        if s["mode"] == "explore":
            T += s["search_cost"] + max(0, frames - s["samples"]) * cost
        else:
            T += frames * cost
        n[s["mode"]] += 1
        n["fallback"] += bool(s.get("fallback"))
        measured += s["total_ms"]
    return {"T": T, "measured": measured, "states": len(res["hybrid"]["states"]), **n,
            "cpu_s": res["cpu_s"], "load1": res["load1"]}


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--db", required=True, help="baseline database (tools/hybrid/baseline.py)")
    ap.add_argument("--work", required=True, help="warm-start DBs and the runs (cached: reruns continue)")
    ap.add_argument("--out", default=None, help="folder for epsilon.json/.md and the chart")
    ap.add_argument("--scenes", default="killeroos,living-room", help="the test scenes (comma-"
                    "separated): the warm start holds the baseline's rows of every other scene")
    ap.add_argument("--objectives", default="render,build+render")
    ap.add_argument("--epsilons", default="0,0.1,0.3,1")
    ap.add_argument("--models", default="nn,rbf")
    ap.add_argument("--states", default="40:59", help="path samples A:B (both included)")
    ap.add_argument("--iterations", type=int, default=40, help="K, the search's iterations")
    ap.add_argument("--frames", type=int, default=0, help="frames per state (default K + 1)")
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--tune-params", default=baseline.TUNE_PARAMS)
    ap.add_argument("--seeds", default="1", help="comma-separated seeds (the epsilon draws and the "
                    "search's): every run is repeated per seed")
    ap.add_argument("--set", action="append", default=[], metavar="PLUGIN.KEY=VALUE",
                    help="a predictor setting for the runs of that predictor (repeatable)")
    ap.add_argument("--nice", type=int, default=19)
    ap.add_argument("--no-run", action="store_true", help="report the cached runs only")
    a = ap.parse_args()
    a.frames = a.frames or a.iterations + 1
    if not a.no_run:
        a.host = host.find(a.host)
    eps = sorted({float(e) for e in a.epsilons.split(",")}, reverse=True)
    if 1.0 not in eps:
        eps.insert(0, 1.0)
    files = scene_files(a.db)
    os.makedirs(os.path.join(a.work, "runs"), exist_ok=True)
    results = []
    t0 = time.time()
    seeds = [int(x) for x in a.seeds.split(",")]
    # seeds innermost but one: whenever the run stops, every scene has its first seeds done
    test_scenes = a.scenes.split(",")
    for s in test_scenes:
        if s not in files:
            sys.exit(f"epsilon: {s} has no finished job in {a.db}")
    warm = None if a.no_run else warm_start(a.db, files, test_scenes, a.work)
    todo = [(s, o, e, m, sd) for sd in seeds for s in test_scenes for o in a.objectives.split(",")
            for e in eps for m in (a.models.split(",")[:1] if e == 1.0 else a.models.split(","))]
    for k, (s, o, e, m, sd) in enumerate(todo):
        sfile = files[s][0]
        path = os.path.join(a.work, "runs", run_name(a, s, o, e, m, sd))
        if a.no_run and not os.path.exists(path):
            continue
        r = run(a, s, sfile, warm, o, e, m, sd, path)
        r.setdefault("seed", sd)
        results.append(r)
        el = time.time() - t0
        print(f"[{k + 1}/{len(todo)}] {s} {o} eps {e:g} {m} seed {sd}: {r['hybrid']['explored']} explored, "
              f"{r['cpu_s']:.0f} CPU s, elapsed {el / 60:.1f} min, load {os.getloadavg()[0]:.1f}", flush=True)
    rows = []
    for r in results:
        t = totals(r, a.frames)
        same = [x for x in results if x["scene"] == r["scene"] and x["objective"] == r["objective"]
                and x["seed"] == r["seed"]]
        base = next((x for x in same if x["epsilon"] == 1.0), None)
        if base is None:
            continue
        b = totals(base, a.frames)
        # what epsilon-greedy would give without online learning: a mix of the epsilon 1 run
        # and the same model's epsilon 0 run, state by state in expectation
        zero = next((x for x in same if x["epsilon"] == 0.0 and x["model"] == r["model"]), None)
        mix = None
        if zero is not None:
            t0 = totals(zero, a.frames)["T"]
            mix = b["T"] / (r["epsilon"] * b["T"] + (1 - r["epsilon"]) * t0)
        d = sum(a.frames * st["default_cost"] for st in base["hybrid"]["states"] if st["default_cost"])
        rows.append({"scene": r["scene"], "objective": r["objective"], "epsilon": r["epsilon"],
                     "model": r["model"], "seed": r["seed"], **t, "speedup": b["T"] / t["T"],
                     "speedup_measured": b["measured"] / t["measured"], "speedup_cpu": b["cpu_s"] / t["cpu_s"],
                     "speedup_over_default": d / t["T"], "speedup_mix": mix})
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        meta = {"states": a.states, "iterations": a.iterations, "frames_per_state": a.frames,
                "res": a.res, "seeds": seeds, "set": a.set,
                "warm_start": "baseline rows of the scenes not tested"}
        with open(os.path.join(a.out, "epsilon.json"), "w") as f:
            json.dump({"settings": meta, "rows": rows, "mean_over_seeds": over_seeds(rows)}, f, indent=1)
        with open(os.path.join(a.out, "epsilon.md"), "w") as f:
            f.write(table(rows))
        draw(rows, a)
    print(table(rows))
    return 0


def geomean(xs):
    xs = [x for x in xs if x and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else None


def over_seeds(rows):
    """Per scene, objective, epsilon and model: geo-means over the seeds, min and max."""
    keys = sorted({(r["scene"], r["objective"], r["epsilon"], r["model"] if r["epsilon"] < 1 else "search")
                   for r in rows}, key=lambda k: (k[0], k[1], -k[2], k[3]))
    out = []
    for s, o, e, m in keys:
        sel = [r for r in rows if (r["scene"], r["objective"], r["epsilon"]) == (s, o, e) and
               (e == 1.0 or r["model"] == m)]
        if e == 1.0:  # one search run per seed, whatever model its row was filed under
            sel = list({r["seed"]: r for r in sel}.values())
        out.append({"scene": s, "objective": o, "epsilon": e, "model": m, "seeds": sorted(r["seed"] for r in sel),
                    "explored": sum(r["explore"] for r in sel), "states": sum(r["states"] for r in sel),
                    **{k: geomean(r[k] for r in sel) for k in ("speedup", "speedup_measured", "speedup_over_default")},
                    "speedup_min": min(r["speedup"] for r in sel), "speedup_max": max(r["speedup"] for r in sel),
                    "measured_min": min(r["speedup_measured"] for r in sel),
                    "measured_max": max(r["speedup_measured"] for r in sel),
                    "cpu_s": sum(r["cpu_s"] for r in sel) / len(sel),
                    "load1": [r["load1"] for r in sel]})
    return out


def table(rows):
    lines = ["| scene | objective | epsilon | model | seeds | explored/states | speed-up over search: "
             "geo-mean (min-max) | render, host clock: geo-mean (min-max) | over default | host CPU s "
             "per run |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in over_seeds(rows):
        meas = (f"{r['speedup_measured']:.2f} ({r['measured_min']:.2f}-{r['measured_max']:.2f})"
                if r["objective"] == "render" else "")
        lines.append(f"| {r['scene']} | {r['objective']} | {r['epsilon']:g} | {r['model']} | "
                     f"{len(r['seeds'])} | {r['explored']}/{r['states']} | {r['speedup']:.2f} "
                     f"({r['speedup_min']:.2f}-{r['speedup_max']:.2f}) | {meas} | "
                     f"{r['speedup_over_default']:.2f} | {r['cpu_s']:.0f} |")
    return "\n".join(lines) + "\n"


def draw(rows, a):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import ScalarFormatter
    objs = sorted({r["objective"] for r in rows}, key=lambda o: o != "render")
    # render once more on the host's own clock: the searched states pay a build per iteration
    # (the objective counts the pass only), the exploited ones one build
    panels = [(o, "speedup") for o in objs] + [(o, "speedup_measured") for o in objs if o == "render"]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.0 * len(panels), 3.9), squeeze=False)
    colors = {"nn": "#1f77b4", "rbf": "#2ca02c", "static": "#7f7f7f"}
    marks = ["o", "s", "^", "D", "v"]
    agg = over_seeds(rows)
    nseeds = max(len(r["seeds"]) for r in agg)
    scenes = sorted({r["scene"] for r in agg})
    lo = {"speedup": "speedup_min", "speedup_measured": "measured_min"}
    hi = {"speedup": "speedup_max", "speedup_measured": "measured_max"}
    for ax, (o, key) in zip(axes[0], panels):
        for si, s in enumerate(scenes):
            for m in sorted({r["model"] for r in agg if r["epsilon"] < 1}):
                pts = sorted((r["epsilon"], r[key], r[lo[key]], r[hi[key]]) for r in agg if r["scene"] == s
                             and r["objective"] == o and (r["model"] == m or r["epsilon"] == 1.0))
                ax.errorbar([p[0] for p in pts], [p[1] for p in pts],
                            yerr=[[max(0.0, p[1] - p[2]) for p in pts], [max(0.0, p[3] - p[1]) for p in pts]],
                            marker=marks[si % len(marks)], color=colors.get(m, "k"), alpha=0.75,
                            capsize=2, label=f"{s}, {m}")
                grid = [k / 20 for k in range(21)]
                if key == "speedup" and pts and pts[0][0] == 0.0:
                    # the mix curve through epsilon 0 and 1: T1 / (e T1 + (1 - e) T0)
                    s0 = pts[0][1]
                    ax.plot(grid, [1 / (e + (1 - e) / s0) for e in grid], ls=":", color=colors.get(m, "k"),
                            alpha=0.6)
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xlabel("epsilon (probability of exploring a state)")
        ax.set_ylabel("speed-up over pure search (epsilon 1)")
        ax.set_yscale("log")
        ax.yaxis.set_major_formatter(ScalarFormatter())
        ax.yaxis.set_minor_formatter(ScalarFormatter())
        if key == "speedup":
            ax.set_title(f"{o} (the objective): {a.frames} frames per state, path samples {a.states},\n"
                         f"geo-mean of {nseeds} seeds (bars: min-max; dotted: the mix of epsilon 0 "
                         f"and 1 without online learning)", fontsize=8)
        else:
            ax.set_title(f"{o}, end to end on the host's clock: {a.frames} passes per state,\n"
                         f"the search's builds and the predictor's calls included", fontsize=8)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out, "hybrid_epsilon.png"), dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
