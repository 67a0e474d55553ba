"""Re-measured rooflines of hybrid tuning on held-out scenes.

A tuning search's "best" configuration is the cheapest of its 41 one-pass measurements, so it
is partly the luckiest sample (the winner's curse), and a roofline taken from it flatters
every prediction compared against it. This tool measures again, per held-out state (test
scene, camera, objective), the candidates a roofline could be: the default, the search's best
and each predictor's prediction (nn, rbf, static), side by side in one host process
(`host --measure`: R rounds, every candidate rebuilt and rendered once per round, the order
alternating forward and backward between rounds). Per round each candidate's cost is divided
by the default's cost of the same round (paired ratios); a candidate's figure is the median
of its paired ratios. The re-measured roofline of a state is the fastest candidate by that
median, the default included, so it is 1 exactly where the default is the fastest.

The min of a few noisy medians still favours luck a little, so the roofline is also chosen on
the first half of the rounds and reported on the second half ("held-out rounds"): where that
figure is near 1, the candidates do not differ from the default beyond noise.

Models learn as evaluate.py's held-out protocol has them learn: from every camera of the
--train-scenes, predicting every camera of the --test-scenes (disjoint; required), through
`host --predict` warm-started from a database holding only the training rows. Per test state,
with n the search's samples and S their summed cost over its default (the baseline's
trajectory), p = prediction / default, b = the search's best / default and r the roofline
(all re-measured, medians of paired rounds):
  speed-up over the search          S / (n p)   (time for n frames: search against prediction)
  fraction of the re-measured roofline   r / p  (1: the fastest candidate)
  the roofline's gain over the default   1 / r

  R="/usr/bin/python3 -m tools.hybrid.remeasure"          # from the repository root
  nice -n 10 $R --db BASELINE.db --work /tmp/hybrid/remeasure --out tools/hybrid/figures/remeasured \\
      --train-scenes bmw-m6,bathroom,voxel,tessellated --test-scenes killeroos,living-room,staircase,veach-ajar

Measurements are cached per state in --work (a rerun measures only what is new or was
measured with other settings). --out gets remeasure.json, remeasure.md and
roofline_speed.png (speed-up over the search against the fraction of the re-measured
roofline, per predictor and test scene). --quick measures one camera per test scene at
--res 32x32 with 4 rounds (for the evidence pass: the tool runs, the figures are not results).
"""
import concurrent.futures
import json
import math
import os
import sys
import time

from tools.hybrid import baseline, evaluate
from tools.tttools import cli, host

ROLES = ("default", "search", "nn", "rbf", "static")  # candidate roles, in measuring order
LABELS = {"default": "default", "search": "search's best", "nn": "nn", "rbf": "RBF", "static": "best static"}


class InputError(SystemExit):
    """Bad input: the message names the option or file, the field and what was expected."""

    def __init__(self, message):
        super().__init__("remeasure: " + message)


def median(xs):
    s = sorted(xs)
    n = len(s)
    if not n:
        return None
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def paired(costs):
    """Per role the per-round cost ratios to the default of the same round, their median, and
    the medians over the first and the second half of the rounds. `costs`: {role: [cost per
    round]}, every list as long as the default's (a round a candidate missed is None)."""
    d = costs["default"]
    out = {}
    for role, cs in costs.items():
        ratios = [c / dc if c is not None and dc and dc > 0 else None for c, dc in zip(cs, d)]
        ok = [x for x in ratios if x is not None]
        h = len(ratios) // 2
        first = [x for x in ratios[:h] if x is not None]
        second = [x for x in ratios[h:] if x is not None]
        out[role] = {"ratios": ratios, "median": median(ok), "median_first": median(first),
                     "median_second": median(second),
                     "faster_rounds": sum(1 for x in ok if x < 1.0), "rounds": len(ok)}
    return out


def roofline(ratios, key="median"):
    """(role, ratio) of the fastest candidate by `key` (the default's ratio is 1); ties go to
    the default, then to the order of ROLES."""
    best = ("default", 1.0)
    for role in ROLES[1:]:
        v = ratios.get(role, {}).get(key)
        if v is not None and v < best[1]:
            best = (role, v)
    return best


def state_figures(job, roles, ratios, models):
    """The figures of one state from its paired ratios: roofline, per model speed-up over the
    search and fraction of the roofline, the roofline chosen on the first half of the rounds
    and measured on the second."""
    d = job["default_cost"]
    costs = [d] + [h["cost"] for h in job["history"] if h["cost"] < 1e299]
    n, S = len(costs), sum(costs) / d
    role, r = roofline(ratios)
    hrole, _ = roofline(ratios, "median_first")
    held = ratios[hrole]["median_second"] if hrole != "default" else 1.0
    out = {"n": n, "search_sum": S, "roofline_role": role, "roofline": r,
           "default_is_roofline": role == "default",
           "heldout_roofline_role": hrole, "heldout_roofline": held,
           "search_best_baseline": job["best_cost"] / d,
           "search_best": ratios["search"]["median"], "models": {}}
    # the default and the search's best as references beside the predictors (the default's
    # speed-up over the search is S / n: what not searching at all would give)
    for m in ("default", "search") + tuple(models):
        p = ratios.get(m, {}).get("median")
        if p is None or not p > 0:
            continue
        out["models"][m] = {"p": p, "speedup": S / (n * p), "fraction": r / p,
                            "faster_rounds": ratios[m]["faster_rounds"], "rounds": ratios[m]["rounds"],
                            "config": roles.get(m)}
    return out


def summarize(states, models, objectives):
    """Per objective and test scene (geo-means over its cameras) and per objective over every
    test state: each model's speed-up and fraction of the roofline, the roofline's gain, the
    search's best re-measured, where the default is the roofline."""
    g = evaluate.geomean
    out = {}
    for o in objectives:
        sel = [s for s in states if s["objective"] == o]
        if not sel:
            continue
        groups = {sc: [s for s in sel if s["scene"] == sc] for sc in sorted({s["scene"] for s in sel})}
        groups["all"] = sel
        per = {}
        for sc, ss in groups.items():
            e = {"cameras": len(ss),
                 "roofline": g(s["roofline"] for s in ss),
                 "heldout_roofline": g(s["heldout_roofline"] for s in ss),
                 "search_best": g(s["search_best"] for s in ss),
                 "search_best_baseline": g(s["search_best_baseline"] for s in ss),
                 "default_is_roofline": sum(1 for s in ss if s["default_is_roofline"]),
                 "roofline_roles": {r: sum(1 for s in ss if s["roofline_role"] == r) for r in ROLES
                                    if any(s["roofline_role"] == r for s in ss)},
                 "models": {}}
            for m in ("default", "search") + tuple(models):
                xs = [s["models"][m] for s in ss if m in s["models"]]
                if xs:
                    e["models"][m] = {"speedup": g(x["speedup"] for x in xs),
                                      "fraction": g(x["fraction"] for x in xs),
                                      "p": g(x["p"] for x in xs), "n": len(xs)}
            # the default is this scene's roofline when no candidate is faster than it by the
            # geo-mean over the scene's cameras
            e["default_fastest_on_geomean"] = all(v["p"] >= 1.0 for k, v in e["models"].items()
                                                  if k != "default")
            per[sc] = e
        out[o] = per
    return out


def check_baseline(path):
    """The baseline database exists and has finished jobs (InputError otherwise)."""
    if not os.path.isfile(path):
        raise InputError(f"--db {path}: no such file (a baseline database of tools/hybrid/baseline.py)")
    what = f"--db {path}: table hybrid_jobs: expected a baseline database of tools/hybrid/baseline.py"
    try:
        rows = baseline.read_jobs(path)
    except SystemExit as e:  # read_jobs' own message: no hybrid_jobs table
        raise InputError(f"{what} ({e})")
    except Exception as e:  # noqa: BLE001 (sqlite3's DatabaseError: not a database at all)
        raise InputError(f"{what} ({type(e).__name__}: {e})")
    if not any(r["history"] for r in rows):
        raise InputError(f"--db {path}: table hybrid_jobs: expected finished jobs, found none")


class Measurer:
    """host --measure of one state's candidates, cached in --work/measure/ per state."""

    def __init__(self, a, jobs, scenes):
        self.a, self.jobs, self.scenes = a, jobs, scenes
        self.dir = os.path.join(a.work, "measure")
        os.makedirs(self.dir, exist_ok=True)

    def path(self, s, c, o):
        return os.path.join(self.dir, f"{s}_{c:03d}_{o.replace('+', '_')}.json")

    def settings(self, job):
        return {"rounds": self.a.rounds, "res": self.a.res or job["res"], "spp": job["spp"],
                "threads": job["threads"], "clock": job["clock"]}

    def cached(self, s, c, o, configs):
        p = self.path(s, c, o)
        if not os.path.exists(p):
            return None
        with open(p) as f:
            d = json.load(f)
        want = [evaluate.canon(x) for x in configs]
        if d.get("settings") != self.settings(self.jobs[(s, c, o)]) or d.get("asked") != want:
            return None
        return d

    def measure(self, s, c, o, roles, cached_only=False):
        """Measures the distinct configurations of `roles` ({role: config}) side by side;
        returns (the state's record {settings, asked, roles, costs, load1, wall_s}, whether it
        was measured now); (None, False) with `cached_only` and nothing cached."""
        job = self.jobs[(s, c, o)]
        uniq, index = [], {}
        for role in ROLES:
            cfg = roles.get(role)
            if cfg is None:
                continue
            k = evaluate.canon(cfg)
            if k not in index:
                index[k] = len(uniq)
                uniq.append(cfg)
        hit = self.cached(s, c, o, uniq)
        if hit or cached_only:
            return hit, False
        todo = os.path.join(self.dir, f"todo_{s}_{c}_{o.replace('+', '_')}_{os.getpid()}.json")
        with open(todo, "w") as f:
            json.dump(uniq, f)
        st = self.settings(job)
        args = ["--measure", todo, "--rounds", str(self.a.rounds), "--camera-index", str(c),
                "--objective", o, "--no-db", "--quiet", "--res", st["res"], "--threads", str(job["threads"]),
                "--clock", job["clock"], "--tune-spp", str(job["spp"]), "--tune-params", job["tune_params"],
                "--seed", str(job["seed"]), self.scenes[s][0]]
        try:
            r = host.run(self.a.host, args, nice=self.a.nice, capture=True)
        finally:
            os.remove(todo)
        res = r.json()
        if len(res["configs"]) != len(uniq) or res["rounds"] != self.a.rounds:
            raise host.HostError(f"remeasure: host --measure {s}:{c}:{o} answered "
                                 f"{len(res['configs'])} configurations x {res['rounds']} rounds, "
                                 f"expected {len(uniq)} x {self.a.rounds}")
        costs = []
        for item in res["configs"]:
            cs = item.get("cost") or []
            costs.append(cs if item.get("status") == "ok" and len(cs) == self.a.rounds
                         else [None] * self.a.rounds)
        if any(x is None for x in costs[0]):
            raise host.HostError(f"remeasure: host --measure {s}:{c}:{o}: the default failed")
        d = {"settings": st, "asked": [evaluate.canon(x) for x in uniq],
             "roles": {role: index[evaluate.canon(cfg)] for role, cfg in roles.items() if cfg is not None},
             "measured": [item.get("config") for item in res["configs"]],
             "host_ratio_to_first": [item.get("ratio_to_first") for item in res["configs"]],
             "costs": costs, "wall_s": r.wall_s, "load1": os.getloadavg()[0]}
        tmp = self.path(s, c, o) + ".tmp"
        with open(tmp, "w") as f:
            json.dump(d, f)
        os.replace(tmp, self.path(s, c, o))
        return d, True


def fmt(x, spec="{:.3f}"):
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else spec.format(x)


def markdown(res):
    st = res["settings"]
    loads = res["load_during_measurement"]
    missing = (f"; {res['not_measured']} more states were not measured (the run was stopped "
               f"or limited), so the table covers the cameras measured" if res.get("not_measured") else "")
    out = [f"Held-out protocol: trained on every camera of {', '.join(st['train'])}; tested on "
           f"the cameras of {', '.join(st['test'])} ({res['states']} states measured{missing}). Each state's "
           f"candidates measured side by side in one host process, {st['rounds']} rounds "
           f"alternating order, paired ratios to the default's cost in the same round, medians; "
           f"CPU time of one thread, {st['res'] or 'the baseline resolution'}, nice {st['nice']}, "
           f"on a shared, loaded 2-core machine (load average "
           f"{fmt(min(loads) if loads else None, '{:.1f}')}-{fmt(max(loads) if loads else None, '{:.1f}')}).",
           ""]
    for o, per in res["summary"].items():
        models = [m for m in ("nn", "rbf", "static") if any(m in e["models"] for e in per.values())]
        out += [f"**{o}** (geo-means over each scene's cameras; speed-up over the search / "
                f"fraction of the re-measured roofline)", "",
                "| scene | cameras | roofline / default (held-out rounds) | default is the roofline "
                "| search's best / default: baseline, re-measured | "
                + " | ".join(LABELS[m] for m in models) + " | default (no search) |",
                "|---|---|---|---|---|" + "---|" * (len(models) + 1)]
        for sc, e in per.items():
            cells = []
            for m in models + ["default"]:
                v = e["models"].get(m)
                cells.append("-" if not v else f"{fmt(v['speedup'])}x / {fmt(v['fraction'])}")
            out.append(f"| {sc} | {e['cameras']} | {fmt(e['roofline'])} ({fmt(e['heldout_roofline'])}) | "
                       f"{e['default_is_roofline']} of {e['cameras']} | "
                       f"{fmt(e['search_best_baseline'])}, {fmt(e['search_best'])} | " + " | ".join(cells) + " |")
        out.append("")
    return "\n".join(out) + "\n"


def draw(res, path):
    """Speed-up over the search against the fraction of the re-measured roofline, per
    predictor (colour) and test scene (marker), one panel per objective; the default and the
    search's best drawn as references. Written atomically."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    colors = {"nn": "#1f77b4", "rbf": "#2ca02c", "static": "#7f7f7f", "default": "#d62728",
              "search": "#ff7f0e"}
    markers = "osD^v<>px*"
    objs = list(res["summary"])
    fig, axes = plt.subplots(1, len(objs), figsize=(5.6 * len(objs), 4.6), squeeze=False)
    st = res["settings"]
    for ax, o in zip(axes[0], objs):
        per = res["summary"][o]
        scenes = [s for s in per if s != "all"]
        # largest first, so that candidates on the same point show as rings around each other
        for m, size in (("default", 130), ("search", 130), ("static", 90), ("rbf", 55), ("nn", 24)):
            for si, sc in enumerate(scenes):
                v = per[sc]["models"].get(m)
                if not v:
                    continue
                ax.scatter(v["fraction"], v["speedup"], color=colors[m], marker=markers[si % len(markers)],
                           s=size, alpha=0.9, edgecolors="k" if m in ("default", "search") else "none",
                           linewidths=0.6)
        for m in ("nn", "rbf", "static", "default", "search"):
            if any(m in per[sc]["models"] for sc in scenes):
                ax.scatter([], [], color=colors[m], marker="s", label=LABELS[m])
        for si, sc in enumerate(scenes):
            ax.scatter([], [], color="w", edgecolors="k", marker=markers[si % len(markers)],
                       label=f"{sc} (default fastest at {per[sc]['default_is_roofline']}/{per[sc]['cameras']})")
        ax.axvline(1.0, color="k", lw=0.7, ls="--")
        ax.axhline(1.0, color="k", lw=0.5, ls=":")
        ax.set_xlabel("fraction of the re-measured roofline (geo-mean over cameras)")
        ax.set_ylabel("speed-up over the search (geo-mean)")
        ax.set_title(f"{o}: held-out scenes, {st['rounds']} paired rounds", fontsize=10)
        ax.legend(fontsize=7, loc="best")
    loads = res["load_during_measurement"]
    fig.suptitle("Hybrid tuning against the re-measured roofline (fastest of default, search's best "
                 f"and predictions; medians of paired rounds; shared 2-core machine at load "
                 f"{fmt(min(loads) if loads else None, '{:.0f}')}-{fmt(max(loads) if loads else None, '{:.0f}')}, "
                 f"nice {st['nice']})", fontsize=8.5)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=100)
    plt.close(fig)
    os.replace(tmp, path)


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument("--db", required=True, help="baseline database (tools/hybrid/baseline.py)")
    ap.add_argument("--work", required=True, help="cache of training DBs, predictions, measurements")
    ap.add_argument("--out", default=None, help="folder for remeasure.json/.md and roofline_speed.png")
    ap.add_argument("--train-scenes", default=None, metavar="A,B",
                    help="learn from every camera of these (default: every scene not tested)")
    ap.add_argument("--test-scenes", required=True, metavar="C,D",
                    help="re-measure and report every camera of these (disjoint from --train-scenes)")
    ap.add_argument("--objectives", default="render,build+render")
    ap.add_argument("--models", default="nn,rbf,static")
    ap.add_argument("--rounds", type=int, default=8, help="paired rounds per state (even, >= 2)")
    ap.add_argument("--cameras", type=int, default=0, help="at most this many cameras per test scene (0: all)")
    ap.add_argument("--res", default=None, help="measure at WxH instead of the baseline's resolution")
    ap.add_argument("--min-cameras", type=int, default=1)
    ap.add_argument("--nice", type=int, default=10)
    ap.add_argument("--jobs", type=int, default=1, help="measuring host processes at a time")
    ap.add_argument("--no-measure", action="store_true", help="report with what is measured")
    ap.add_argument("--max-minutes", type=float, default=0, help="start no measurement after this "
                    "many minutes; report what is measured (0: no limit)")
    ap.add_argument("--quick", action="store_true", help="1 camera per test scene, 32x32, 4 rounds")
    a = ap.parse_args(argv)
    if a.quick:
        a.cameras, a.res, a.rounds = a.cameras or 1, a.res or "32x32", 4
    if a.rounds < 2 or a.rounds % 2:
        raise InputError(f"--rounds {a.rounds}: expected an even number >= 2 (medians of paired "
                         "rounds, half of them to choose the roofline, half to measure it)")
    if a.res is not None:
        w, _, h = a.res.partition("x")
        if not (w.isdigit() and h.isdigit() and int(w) > 0 and int(h) > 0):
            raise InputError(f"--res {a.res!r}: expected WxH with positive integers, e.g. 32x32")
    objectives = [o for o in a.objectives.split(",") if o]
    for o in objectives:
        if o not in ("render", "build+render"):
            raise InputError(f"--objectives: {o!r}: expected render and/or build+render")
    models = [m for m in a.models.split(",") if m]
    for m in models:
        if m not in evaluate.MODELS:
            raise InputError(f"--models: {m!r}: expected some of {', '.join(evaluate.MODELS)}")
    check_baseline(a.db)
    os.makedirs(a.work, exist_ok=True)
    jobs, scenes = evaluate.load_jobs(a.db, objectives)
    cams = evaluate.cameras(jobs, objectives, a.min_cameras)
    if not cams:
        raise InputError(f"--db {a.db}: no scene has {a.min_cameras} cameras with every objective "
                         f"({', '.join(objectives)}) done")
    tr, te = evaluate.scene_sets(cams, a.train_scenes, a.test_scenes)
    a.host = host.find(a.host)
    a.default_config = host.default_config(a.host, "accel_embree")
    test_cams = {s: (cams[s][:a.cameras] if a.cameras > 0 else cams[s]) for s in te}
    inds = evaluate.camera_indicators(a.db, jobs, {s: cams[s] for s in tr + te})
    (pname, train, _), = evaluate.protocols(cams, 0, 0.0, False, 0, (tr, te))
    print(f"remeasure: training on {', '.join(tr)}; testing on "
          + ", ".join(f"{s} ({len(c)} cameras)" for s, c in test_cams.items()), flush=True)

    # 1. predictions of every model for every test state
    for d in ("train", "predict"):
        os.makedirs(os.path.join(a.work, d), exist_ok=True)
    preds = {}
    for o in objectives:
        some = next(j for (_, _, oo), j in jobs.items() if oo == o)
        tdb = evaluate.training_db(a, jobs, train, o, os.path.join(a.work, "train", f"{pname}_{o.replace('+', '_')}.db"))
        states = [(s, c, inds[(s, c)]) for s in te for c in test_cams[s]]
        for m in models:
            out = evaluate.predict(a, some, m, evaluate.VARIANTS["default"], tdb, states, o,
                                   os.path.join(a.work, "predict", f"{m}_{pname}_{len(states)}_{o.replace('+', '_')}.json"))
            for item in out["predictions"]:
                s, c = item["id"].split(":")
                preds[(m, s, int(c), o)] = item.get("config")

    # 2. every test state's candidates, side by side
    meas = Measurer(a, jobs, scenes)
    # the k-th camera of every scene before the (k+1)-th of any: a run stopped early (or
    # --max-minutes) leaves every test scene with its first cameras measured
    todo = []
    for k in range(max(len(c) for c in test_cams.values())):
        for s in te:
            if k >= len(test_cams[s]):
                continue
            c = test_cams[s][k]
            for o in objectives:
                job = jobs[(s, c, o)]
                roles = {"default": a.default_config, "search": job["best_config"]}
                roles.update({m: preds.get((m, s, c, o)) for m in models})
                todo.append(((s, c, o), roles))
    records, measured, skipped = {}, 0, []
    t0 = time.time()

    def one(k, roles):
        late = a.max_minutes and time.time() - t0 > 60 * a.max_minutes
        if a.no_measure or late:
            return meas.measure(*k, roles, cached_only=True)
        return meas.measure(*k, roles)

    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        futs = {pool.submit(one, k, roles): (k, roles) for k, roles in todo}
        for i, fut in enumerate(concurrent.futures.as_completed(futs)):
            k, roles = futs[fut]
            rec, new = fut.result()
            if rec is None:
                skipped.append(k)
                continue
            records[k] = (rec, roles)
            measured += new
            el = time.time() - t0
            print(f"  [{i + 1}/{len(todo)}] {k[0]}:{k[1]}:{k[2]} {'measured' if new else 'cached'}, "
                  f"{el / 60:.1f} min, load {os.getloadavg()[0]:.1f}", flush=True)
    if skipped:
        print(f"remeasure: {len(skipped)} of {len(todo)} states not measured (--no-measure or "
              f"--max-minutes): the report covers the {len(records)} measured", flush=True)
    if not records:
        raise InputError("no test state is measured yet (run without --no-measure)")

    # 3. figures
    states = []
    for (s, c, o), (rec, roles) in sorted(records.items()):
        costs = {role: rec["costs"][i] for role, i in rec["roles"].items()}
        ratios = paired(costs)
        f = state_figures(jobs[(s, c, o)], roles, ratios, models)
        f.update({"scene": s, "camera": c, "objective": o,
                  "ratios": {role: {k: v for k, v in r.items()} for role, r in ratios.items()}})
        states.append(f)
    # the host's niceness: --nice on top of this process' own (nice -n is relative)
    res = {"settings": {"train": tr, "test": te, "rounds": a.rounds, "res": a.res,
                        "nice": min(19, os.nice(0) + a.nice),
                        "cameras": {s: c for s, c in test_cams.items()}, "models": models,
                        "objectives": objectives, "db": os.path.basename(a.db)},
           "states": len(states), "measured_now": measured, "not_measured": len(skipped),
           "load_during_measurement": [rec["load1"] for rec, _ in records.values()],
           "summary": summarize(states, models, objectives), "rows": states}
    text = markdown(res)
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        for name, body in (("remeasure.json", json.dumps(res, indent=1, sort_keys=True) + "\n"),
                           ("remeasure.md", text)):
            tmp = os.path.join(a.out, name + ".tmp")
            with open(tmp, "w") as fh:
                fh.write(body)
            os.replace(tmp, os.path.join(a.out, name))
        draw(res, os.path.join(a.out, "roofline_speed.png"))
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
