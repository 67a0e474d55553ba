"""Evaluation of hybrid autotuning's prediction (thesis 3.3.5) on the baseline database of
tools/hybrid/baseline.py: predictors against the Nelder-Mead search, the search's best (the
"roofline") and the best static configuration, per scene and camera.

Protocols:
  split K   per scene a random 80/20 split of its cameras (K = 0 .. --splits-1, seeded); the
            models learn from the training cameras of every scene (thesis: "80 * 7"), and
            predict the validation cameras;
  loso S    leave one scene out: the models learn from every other scene and predict all
            cameras of S;
  heldout   with --train-scenes / --test-scenes (instead of the two above): the models learn
            from every camera of the training scenes and predict every camera of the test
            scenes (the two sets must be disjoint: a scene in both would leak its rows).
Models (host --predict through the plugins, warm-started from a database holding only the
training rows): nn (predictor_nn), rbf (predictor_rbf), static (predictor_static: the one
configuration with the best geometric-mean speed-up over the default on the training states).

Costs: every configuration a model predicts for a validation camera is measured at that camera
side by side with the default and the search's best (host --measure, --rounds R, alternating
order), as a ratio to the default measured in the same process; the search's trajectory (its
default and 40 iterations) comes from the baseline, as ratios to the baseline's default. So
figures compare ratios taken in one process each, whatever the machine's load was between
the baseline and the evaluation. Per validation camera, with n = the search's samples, S =
sum of their costs / default, p = predicted / default, b = roofline / default (measured):
  speed-up over search (Fig. 3.17, 3.20)   S / (n p)
  fraction of the roofline (Fig. 3.18, 3.21) b / p
  break-even iterations (Fig. 3.19)        (S - n b) / (p - b): after that many iterations the
                                           search (then at its best) would have paid back
                                           what it lost; negative = prediction beat the search
  overhead reduction                       1 - n (p - v) / (S - n v), v = min(b0, b, p), b0 = the
                                           search's own best sample / default (baseline); per
                                           scene the geo-mean over cameras (non-positive ones
                                           clamped to 1e-9, and counted) and, defined for any
                                           sign, 1 - sum n (p - v) / sum (S - n v) ("time")

Stages are cached in --work (predictions, measurements), so a rerun continues; --no-measure
reports with what is measured. Figures (matplotlib PNG) and a JSON/Markdown summary go to
--out.

  E="/usr/bin/python3 -m tools.hybrid.evaluate"        # from the repository root
  $E --db /tmp/hybrid/baseline.db --work /tmp/hybrid/eval --out tools/hybrid/figures
  $E ... --variants norm,reward,features,table,candidates   # the studies of the README
"""
import concurrent.futures
import json
import math
import os
import random
import sys
import time

from tools.hybrid import baseline
from tools.tttools import cli, db, host

ROOT = host.ROOT
INDICATORS = ["meshes", "triangles", "lights", "camera_x", "camera_y", "camera_z", "target_x",
              "target_y", "target_z", "fov_y", "diffuse_ratio", "extent", "total_area",
              "light_area", "area_per_mesh", "mean_var_tri_size", "var_var_tri_size"]
MODELS = {"nn": "predictor_nn", "rbf": "predictor_rbf", "static": "predictor_static"}
# thesis 3.3.5 (render only / build+render): geo-means over its seven scenes
THESIS = {
    "render": {"speedup": {"nn": 1.05, "rbf": 1.04}, "roofline": {"nn": 0.95, "rbf": 0.95},
               "overhead_max": {"nn": 0.875, "rbf": 0.792}, "break_even_mean": {"nn": 1771, "rbf": 362}},
    "build+render": {"speedup": {"nn": 1.12, "rbf": None}, "roofline": {"nn": 0.92, "rbf": 0.83},
                     "overhead_max": {"nn": 0.893, "rbf": 0.534}},
}


def geomean(xs):
    xs = [x for x in xs if x is not None and x > 0 and math.isfinite(x)]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def canon(cfg):
    """A configuration's key: numbers as floats (the host prints 1.0 as 1), keys sorted."""
    norm = {k: (v if isinstance(v, (bool, str)) else float(v)) for k, v in cfg.items()}
    return json.dumps(norm, sort_keys=True, separators=(",", ":"))


def load_jobs(path, objectives):
    """{(scene, cam, obj): job} of finished baseline jobs, and each scene's file and id."""
    jobs, scenes = {}, {}
    for r in baseline.read_jobs(path):
        if r["objective"] not in objectives:
            continue
        jobs[(r["scene"], r["path_index"], r["objective"])] = {
            "default_cost": r["default_cost"], "best_cost": r["best_cost"],
            "best_config": r["best_config"], "history": r["history"],
            "scene_id": r["scene_id"], "tune_params": r["tune_params"], "res": r["resolution"],
            "threads": r["threads"], "clock": r["clock"], "spp": r["tune_spp"], "seed": r["seed"],
            "iterations": r["iterations"]}
        scenes[r["scene"]] = (r["scene_file"], r["scene_id"])
    return jobs, scenes


def cameras(jobs, objectives, min_cameras):
    """Per scene the cameras with every objective done; scenes with too few are dropped."""
    per = {}
    for (s, c, o) in jobs:
        per.setdefault(s, {}).setdefault(c, set()).add(o)
    out = {}
    for s, cams in per.items():
        ok = sorted(c for c, objs in cams.items() if all(o in objs for o in objectives))
        if len(ok) >= min_cameras:
            out[s] = ok
    return out


def camera_indicators(path, jobs, cams):
    """Raw indicators of every (scene, camera) from its rows, by name."""
    first = {}
    for r in db.samples(path):
        k = (r["scene_id"], db.path_index(r))
        if k not in first and r["indicators"] is not None:
            first[k] = db.indicators(r)
    out = {}
    for s, cs in cams.items():
        for c in cs:
            sid = next(j["scene_id"] for (ss, cc, _), j in jobs.items() if ss == s and cc == c)
            out[(s, c)] = first[(sid, c)]
    return out


# protocols whose rows make the main tables and figures (loso rows have their own)
MAIN = ("split", "heldout")


def scene_sets(cams, train, test):
    """The training and test scenes of --train-scenes / --test-scenes (either may be left out:
    it is then every other scene), checked: known, disjoint, both non-empty."""
    def parse(opt, text):
        names = [x for x in (text or "").split(",") if x]
        unknown = [x for x in names if x not in cams]
        if unknown:
            sys.exit(f"evaluate: {opt}: {', '.join(unknown)} not among the scenes with enough cameras "
                     f"({', '.join(sorted(cams))})")
        return names
    tr, te = parse("--train-scenes", train), parse("--test-scenes", test)
    both = sorted(set(tr) & set(te))
    if both:
        sys.exit(f"evaluate: --train-scenes and --test-scenes must be disjoint; {', '.join(both)} "
                 f"in both would be tested on its own rows")
    tr = tr or [s for s in sorted(cams) if s not in te]
    te = te or [s for s in sorted(cams) if s not in tr]
    if not tr or not te:
        sys.exit("evaluate: --train-scenes / --test-scenes leave no scene to "
                 + ("train on" if not tr else "test on"))
    return tr, te


def protocols(cams, n_splits, val_share, loso, seed, heldout=None):
    """[(name, {scene: train cams}, {scene: val cams})]; `heldout` = (train scenes, test
    scenes) replaces the splits and leave-one-scene-out by the one held-out protocol."""
    if heldout:
        tr, te = heldout
        # the scenes in the name: its training database and predictions are cached by it
        return [(f"heldout_{'+'.join(tr)}_to_{'+'.join(te)}", {s: cams[s] for s in tr},
                 {s: cams[s] for s in te})]
    out = []
    for k in range(n_splits):
        rng = random.Random(seed * 1000 + k)
        train, val = {}, {}
        for s in sorted(cams):
            cs = list(cams[s])
            rng.shuffle(cs)
            nv = max(1, round(val_share * len(cs)))
            val[s], train[s] = sorted(cs[:nv]), sorted(cs[nv:])
        out.append((f"split{k}", train, val))
    if loso:
        for s in sorted(cams):
            out.append((f"loso-{s}", {t: cams[t] for t in cams if t != s}, {s: cams[s]}))
    return out


def training_db(a, jobs, train, obj, path):
    """A database with only the training cameras' rows of the objective (what the model sees)."""
    keep = set()
    for s, cs in train.items():
        sid = next(j["scene_id"] for (ss, _, _), j in jobs.items() if ss == s)
        keep |= {(sid, c) for c in cs}
    return db.copy_samples(a.db, path, lambda r: r["objective"] == obj and
                           (r["scene_id"], db.path_index(r)) in keep)


def host_common(job):
    return ["--quiet", "--res", job["res"], "--threads", str(job["threads"]), "--clock", job["clock"],
            "--tune-spp", str(job["spp"]), "--tune-params", job["tune_params"], "--seed", str(job["seed"])]


def predict(a, job, model, variant, train_db, states, obj, path):
    """host --predict for `states` ([(scene, cam, indicators)]), cached in `path`."""
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    sfile = path + ".states.json"
    with open(sfile, "w") as f:
        json.dump([{"id": f"{s}:{c}", "indicators": ind} for s, c, ind in states], f)
    args = ["--predict", "--plugin", MODELS[model], "--warm-start", train_db, "--states", sfile,
            "--objective", obj, "--no-db"] + host_common(job) + variant.get("args", [])
    args.append(os.path.join(ROOT, "scenes", "cornell-box", "path.json"))
    r = host.run(a.host, args, capture=True)
    out = r.json()
    out["wall_s"] = r.wall_s
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(out, f)
    os.replace(tmp, path)
    os.remove(sfile)
    return out


class Measurements:
    """Ratios to the default of configurations measured side by side, per (scene, cam, obj),
    kept in one JSON file per camera: {canonical config: [ratio, ...]}."""

    def __init__(self, a, jobs, scenes):
        self.a, self.jobs, self.scenes = a, jobs, scenes
        self.dir = os.path.join(a.work, "measure")
        os.makedirs(self.dir, exist_ok=True)
        self.cache = {}

    def _path(self, s, c, o):
        return os.path.join(self.dir, f"{s}_{c:02d}_{o.replace('+', '_')}.json")

    def get(self, s, c, o):
        k = (s, c, o)
        if k not in self.cache:
            p = self._path(s, c, o)
            self.cache[k] = json.load(open(p)) if os.path.exists(p) else {"ratios": {}, "runs": []}
        return self.cache[k]

    def ratio(self, s, c, o, cfg):
        rs = self.get(s, c, o)["ratios"].get(canon(cfg))
        return None if not rs else sorted(rs)[len(rs) // 2]

    def missing(self, s, c, o, cfgs):
        have = self.get(s, c, o)["ratios"]
        return [cfg for cfg in cfgs if canon(cfg) not in have]

    def measure(self, s, c, o, cfgs):
        """Measures default, roofline and `cfgs` side by side; appends their ratios."""
        job = self.jobs[(s, c, o)]
        todo = [self.a.default_config, job["best_config"]] + cfgs
        seen, uniq = set(), []
        for cfg in todo:
            if canon(cfg) not in seen:
                seen.add(canon(cfg))
                uniq.append(cfg)
        f = os.path.join(self.dir, f"todo_{s}_{c}_{o.replace('+', '_')}_{os.getpid()}.json")
        with open(f, "w") as fh:
            json.dump(uniq, fh)
        args = ["--measure", f, "--rounds", str(self.a.rounds), "--camera-index", str(c),
                "--objective", o, "--no-db"] + host_common(job) + [self.scenes[s][0]]
        r = host.run(self.a.host, args, nice=self.a.nice, capture=True, check=False)
        os.remove(f)
        if r.returncode != 0:
            print(f"evaluate: measure {s}:{c}:{o} failed (exit {r.returncode}): {r.stderr[-1500:]}",
                  file=sys.stderr, flush=True)
            return False
        res = r.json()
        d = self.get(s, c, o)
        # keyed by the configuration asked for: the host measures it as the space's check
        # repairs it (sahBlockSize to a power of two), as the tuning loop did
        for asked, item in zip(uniq, res["configs"]):
            if item.get("ratio_to_first") is not None:
                d["ratios"].setdefault(canon(asked), []).append(item["ratio_to_first"])
        d["runs"].append({"configs": len(uniq), "rounds": res["rounds"], "wall_s": r.wall_s,
                          "load1": os.getloadavg()[0],
                          "default_ms": res["configs"][0].get("median_cost")})
        tmp = self._path(s, c, o) + ".tmp"
        with open(tmp, "w") as fh:
            json.dump(d, fh)
        os.replace(tmp, self._path(s, c, o))
        return True


# Every variant's --set lands on top of the plugins' current defaults (since session 8:
# predictor_rbf poolSource=states, reward=relative), so a study re-run today answers its
# question against today's default; the README's tables say which defaults each ran with.
VARIANTS = {
    "default": {"args": []},
    # camera bound and scale of the state (README: "Indicators")
    "norm-table": {"args": ["--indicator-norm", "camera=table"], "study": "norm"},
    "norm-text": {"args": ["--indicator-norm", "camera=text"], "study": "norm"},
    "norm-log": {"args": ["--indicator-norm", "scale=log"], "study": "norm"},
    "norm-text-log": {"args": ["--indicator-norm", "camera=text,scale=log"], "study": "norm"},
    # RBF reward
    "reward-relative": {"args": ["--set", "predictor_rbf.reward=relative"], "study": "reward", "models": ["rbf"]},
    # RBF feature count (default: 3.5 x 29 = 102)
    **{f"features-{f}": {"args": ["--set", f"predictor_rbf.features={f}"], "study": "features",
                          "models": ["rbf"]} for f in (10, 25, 50, 200, 400)},
    # NN table size (training states kept)
    **{f"table-{n}": {"args": ["--set", f"predictor_nn.maxStates={n}"], "study": "table",
                       "models": ["nn"]} for n in (1, 2, 4, 8, 16, 32)},
    # the relative reward with the argmax limited to configurations the search found good
    # (pool only), and with the default candidates
    "reward-relative-pool": {"args": ["--set", "predictor_rbf.reward=relative", "--set",
                                      "predictor_rbf.lhsCandidates=0", "--set", "predictor_rbf.refine=0"],
                             "study": "reward", "models": ["rbf"]},
    # session 7 (issue 15, RBF on render): the relative reward with a small pool (the
    # configurations with the highest speed-up over their state's default anywhere), feature
    # widths, and a converged Greedy-GQ (more passes, decaying step)
    **{f"rel-pool{k}": {"args": ["--set", "predictor_rbf.reward=relative", "--set",
                                 f"predictor_rbf.poolSize={k}"], "study": "rbf7-pool", "models": ["rbf"]}
       for k in (4, 8, 16)},
    **{f"width-{w}": {"args": ["--set", f"predictor_rbf.width={w}"], "study": "rbf7-width", "models": ["rbf"]}
       for w in (0.3, 3)},
    "converged": {"args": ["--set", "predictor_rbf.epochs=200", "--set", "predictor_rbf.decay=20000"],
                  "study": "rbf7-converged", "models": ["rbf"]},
    # session 8 (issue 15, RBF on render): the candidates are the training states' best
    # configurations (poolSource=states, what each search found, by mean cost) instead of the
    # highest single rewards, with either reward (states + relative became the default)
    "states": {"args": ["--set", "predictor_rbf.poolSource=states"], "study": "rbf8-states",
               "models": ["rbf"]},
    "states-relative": {"args": ["--set", "predictor_rbf.poolSource=states", "--set",
                                 "predictor_rbf.reward=relative"], "study": "rbf8-states", "models": ["rbf"]},
    # ... and the earlier default (session 6: the highest single rewards, R = 1/cost)
    "rewards-inverse": {"args": ["--set", "predictor_rbf.poolSource=rewards", "--set",
                                 "predictor_rbf.reward=inverse"], "study": "rbf8-states", "models": ["rbf"]},
    # item 7 again under the default (states pool, relative reward): the feature count
    **{f"states-features-{f}": {"args": ["--set", f"predictor_rbf.features={f}"],
                                "study": "rbf8-features", "models": ["rbf"]} for f in (10, 25, 50, 200, 400)},
    # RBF argmax candidates: a question about the argmax of one trained model (the candidates
    # do not change the training), so answered from the predictions alone: does the answer
    # still change with more candidates? (summary "candidates"); the pool alone (0-0, only
    # configurations the searches measured) is measured too
    **{f"cand-{l}-{r}": {"args": ["--set", f"predictor_rbf.lhsCandidates={l}", "--set",
                                  f"predictor_rbf.refine={r}"], "study": "candidates", "models": ["rbf"],
                         "measure": (l, r) == (0, 0)}
       for l, r in ((0, 0), (64, 0), (256, 0), (1024, 3), (4096, 3))},
}


def reward_spread(path, jobs, cams, objectives):
    """Why a reward scale matters (issue 15 item 3): over the baseline's samples of every
    state (scene, camera) of the protocol, the share of the reward's variance that lies
    within the states, i.e. the most the action (configuration) can explain, for R = 1/cost
    and for R = default / cost; and how far a state's best sample is below its default."""
    costs_of = {}
    for r in db.samples(path):
        if db.ok(r) and 0 < r["cost"] < 1e299:
            costs_of.setdefault((r["scene_id"], r["objective"], db.path_index(r)), []).append(r["cost"])
    out = {}
    for o in objectives:
        inv, rel, gain = {}, {}, []
        for s, cs in cams.items():
            for c in cs:
                job = jobs.get((s, c, o))
                if not job:
                    continue
                costs = costs_of.get((job["scene_id"], o, c), [])
                if len(costs) < 2:
                    continue
                inv[(s, c)] = [1.0 / x for x in costs]
                rel[(s, c)] = [job["default_cost"] / x for x in costs]
                gain.append(job["best_cost"] / job["default_cost"])

        def within(groups):
            allv = [x for g in groups.values() for x in g]
            mean = sum(allv) / len(allv)
            tot = sum((x - mean) ** 2 for x in allv)
            win = sum(sum((x - sum(g) / len(g)) ** 2 for x in g) for g in groups.values())
            return win / tot if tot > 0 else float("nan")
        if inv:
            means = [sum(g) / len(g) for g in inv.values()]
            gain.sort()
            out[o] = {"states": len(inv), "samples": sum(len(g) for g in inv.values()),
                      "within_share_inverse": within(inv), "within_share_relative": within(rel),
                      "inverse_state_mean_min": min(means), "inverse_state_mean_max": max(means),
                      "best_over_default_median": gain[len(gain) // 2]}
    return out


def candidates_study(preds, objectives, largest="cand-4096-3"):
    """Per candidate set of the RBF's argmax, against the largest one (same trained model:
    the candidates do not change the training): the share of states answered with the same
    configuration, and the median and worst shortfall of its Q below the largest set's."""
    out = {}
    for (vname, m, pname, o), (d, _) in preds.items():
        if m != "rbf" or not (vname.startswith("cand-") or vname == "default"):
            continue
        ref = preds.get((largest, m, pname, o))
        if not ref:
            continue
        for key, (cfg, item) in d.items():
            rcfg, ritem = ref[0].get(key, (None, None))
            if cfg is None or rcfg is None or not ritem.get("value"):
                continue
            e = out.setdefault(f"{vname}/{o}", {"same": 0, "n": 0, "gaps": [], "candidates": [], "ms": []})
            e["n"] += 1
            e["same"] += canon(cfg) == canon(rcfg)
            e["gaps"].append((ritem["value"] - item["value"]) / abs(ritem["value"]))
            e["candidates"].append(item.get("candidates") or 0)
            e["ms"].append(item.get("predict_ms") or 0.0)
    for e in out.values():
        g, c, ms = sorted(e.pop("gaps")), sorted(e.pop("candidates")), sorted(e.pop("ms"))
        e.update({"same_share": e["same"] / e["n"], "q_gap_median": g[len(g) // 2], "q_gap_max": g[-1],
                  "candidates_median": c[len(c) // 2], "predict_ms_median": ms[len(ms) // 2]})
    return out


def metrics(job, p, b):
    """Per-camera figures from the search trajectory (baseline) and measured ratios p, b."""
    d = job["default_cost"]
    costs = [d] + [h["cost"] for h in job["history"] if h["cost"] < 1e299]
    n = len(costs)
    S = sum(costs) / d
    out = {"speedup": S / (n * p), "roofline": b / p, "n": n}
    out["break_even"] = (S - n * b) / (p - b) if p != b else float("inf")
    # thesis 3.3.5: the overhead against "the best-known configuration for a camera and scene
    # ... the best among both the search and the predictions to make sure the overhead is
    # non-negative": v includes the search's own best sample b0 (baseline), so the search's
    # overhead S - n v >= S - n b0 >= 0 (with v = min(b, p) alone, a re-measured best above
    # b0 made it negative at 7 of 120 render cameras of session 6)
    b0 = job["best_cost"] / d
    v = min(b0, b, p)
    over = S - n * v
    out["overhead_pred"], out["overhead_search"] = n * (p - v), over
    out["overhead_reduction"] = 1.0 - n * (p - v) / over if over > 0 else float("nan")
    return out


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--db", required=True, help="baseline database (tools/hybrid/baseline.py)")
    ap.add_argument("--work", required=True, help="cache of training DBs, predictions, measurements")
    ap.add_argument("--out", default=None, help="folder for figures and summary.json/.md")
    ap.add_argument("--objectives", default="render,build+render")
    ap.add_argument("--models", default="nn,rbf,static")
    ap.add_argument("--splits", type=int, default=15)
    ap.add_argument("--val", type=float, default=0.2)
    ap.add_argument("--no-loso", action="store_true", help="skip leave-one-scene-out")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--min-cameras", type=int, default=5)
    ap.add_argument("--scenes", default=None, help="comma-separated subset")
    ap.add_argument("--train-scenes", default=None, metavar="A,B", help="learn from every camera "
                    "of these scenes only (default with --test-scenes: every other scene); replaces "
                    "the splits and leave-one-scene-out by one held-out protocol")
    ap.add_argument("--test-scenes", default=None, metavar="C,D", help="predict every camera of "
                    "these scenes (disjoint from --train-scenes; default with --train-scenes: every "
                    "other scene)")
    ap.add_argument("--variants", default="", help="studies to run besides the default models: "
                    "norm, reward, features, table, candidates")
    ap.add_argument("--variant-splits", type=int, default=5, help="splits used by the studies")
    ap.add_argument("--rounds", type=int, default=2, help="side-by-side rounds per measurement")
    ap.add_argument("--nice", type=int, default=19)
    ap.add_argument("--jobs", type=int, default=1, help="measuring host processes at a time")
    ap.add_argument("--shard", default=None, help="K/N: measure only the K-th of N interleaved "
                    "parts of the cameras (N evaluations side by side; then --no-measure reports)")
    ap.add_argument("--no-measure", action="store_true", help="report with what is measured")
    a = ap.parse_args()
    if a.shard:
        try:
            a.shard = tuple(int(x) for x in a.shard.split("/"))
            assert len(a.shard) == 2 and 0 <= a.shard[0] < a.shard[1]
        except (ValueError, AssertionError):
            ap.error(f"--shard: expected K/N with 0 <= K < N, got {a.shard!r}")
    objectives = a.objectives.split(",")
    models = a.models.split(",")
    os.makedirs(a.work, exist_ok=True)
    jobs, scenes = load_jobs(a.db, objectives)
    cams = cameras(jobs, objectives, a.min_cameras)
    if a.scenes:
        cams = {s: c for s, c in cams.items() if s in a.scenes.split(",")}
    if not cams:
        sys.exit(f"evaluate: no scene has {a.min_cameras} cameras with every objective done in {a.db}")
    heldout = None
    if a.train_scenes or a.test_scenes:
        heldout = scene_sets(cams, a.train_scenes, a.test_scenes)
        cams = {s: c for s, c in cams.items() if s in heldout[0] + heldout[1]}
    print("evaluate: " + ", ".join(f"{s} {len(c)} cameras" for s, c in sorted(cams.items())), flush=True)
    if heldout:
        print(f"evaluate: training on {', '.join(heldout[0])}; testing on {', '.join(heldout[1])}",
              flush=True)
    a.host = host.find(a.host)
    a.default_config = host.default_config(a.host, "accel_embree")
    inds = camera_indicators(a.db, jobs, cams)
    prots = protocols(cams, a.splits, a.val, not a.no_loso, a.seed, heldout)
    studies = [v for v in a.variants.split(",") if v]
    runs = [("default", m, p) for p in prots for m in models]
    for name, v in VARIANTS.items():
        if v.get("study") in studies:
            for m in v.get("models", ["nn", "rbf"]):
                runs += [(name, m, p) for p in prots[:a.variant_splits]]

    # 1. predictions (cheap: no rendering)
    preds = {}  # (variant, model, protocol, obj) -> {(scene, cam): (config, info)}
    pdir = os.path.join(a.work, "predict")
    tdir = os.path.join(a.work, "train")
    os.makedirs(pdir, exist_ok=True)
    os.makedirs(tdir, exist_ok=True)
    t0 = time.time()
    for k, (vname, m, (pname, train, val)) in enumerate(runs):
        for o in objectives:
            some = next(j for (s, _, oo), j in jobs.items() if oo == o)
            tdb = training_db(a, jobs, train, o, os.path.join(tdir, f"{pname}_{o.replace('+', '_')}.db"))
            states = [(s, c, inds[(s, c)]) for s in sorted(val) for c in val[s]]
            out = predict(a, some, m, VARIANTS[vname], tdb, states, o,
                          os.path.join(pdir, f"{vname}_{m}_{pname}_{o.replace('+', '_')}.json"))
            d = {}
            for item in out["predictions"]:
                s, c = item["id"].split(":")
                d[(s, int(c))] = (item.get("config"), item)
            preds[(vname, m, pname, o)] = (d, out)
        if (k + 1) % 10 == 0:
            print(f"  predictions {k + 1}/{len(runs)} ({time.time() - t0:.0f} s)", flush=True)

    # 2. measurements: every predicted configuration at its camera, with default and roofline
    meas = Measurements(a, jobs, scenes)
    need = {}
    for (vname, m, pname, o), (d, _) in preds.items():
        if not VARIANTS[vname].get("measure", True):
            continue
        for (s, c), (cfg, _) in d.items():
            if cfg is not None:
                need.setdefault((s, c, o), {})[canon(cfg)] = cfg
    todo = [(k, meas.missing(*k, list(v.values()))) for k, v in sorted(need.items())]
    todo = [(k, v) for k, v in todo if v]
    if a.shard:
        # K/N: the K-th of N interleaved parts, for N processes beside each other (each
        # camera's file is written by one of them); report afterwards with --no-measure
        k, n = a.shard
        todo = todo[k::n]
    if todo and not a.no_measure:
        print(f"evaluate: measuring {sum(len(v) for _, v in todo)} configurations at {len(todo)} "
              f"cameras ({a.rounds} rounds side by side)", flush=True)
        t0 = time.time()
        # --jobs host processes at a time (each camera's file is its own: no two share one);
        # costs are CPU time of one thread, ratios taken within one process
        with concurrent.futures.ThreadPoolExecutor(max_workers=a.jobs) as pool:
            futs = {pool.submit(meas.measure, s, c, o, cfgs): (s, c, o, len(cfgs))
                    for (s, c, o), cfgs in todo}
            for i, fut in enumerate(concurrent.futures.as_completed(futs)):
                s, c, o, n = futs[fut]
                fut.result()
                el = time.time() - t0
                print(f"  [{i + 1}/{len(todo)}] {s}:{c}:{o} {n} configs, elapsed {el / 60:.1f} min, "
                      f"eta {el / (i + 1) * (len(todo) - i - 1) / 60:.0f} min, load "
                      f"{os.getloadavg()[0]:.1f}", flush=True)

    # 3. figures per camera
    rows = []  # dicts: variant, model, protocol, obj, scene, cam, metrics
    for (vname, m, pname, o), (d, out) in preds.items():
        for (s, c), (cfg, item) in d.items():
            job = jobs[(s, c, o)]
            p = meas.ratio(s, c, o, cfg) if cfg else None
            b = meas.ratio(s, c, o, job["best_config"])
            if p is None or b is None:
                continue
            r = {"variant": vname, "model": m, "protocol": pname, "objective": o, "scene": s,
                 "camera": c, "p": p, "b": b, "predict_ms": item.get("predict_ms"),
                 "memory_bytes": out.get("memory_bytes"), "entries": out.get("entries"),
                 "default_ms": job["default_cost"]}
            r.update(metrics(job, p, b))
            rows.append(r)
    summary = summarize(rows, cams, objectives, models)
    summary["scenes"] = {s: len(c) for s, c in cams.items()}
    if heldout:
        summary["heldout"] = {"train": heldout[0], "test": heldout[1]}
    summary["example"] = example(rows, jobs)
    summary["reward_spread"] = reward_spread(a.db, jobs, cams, objectives)
    summary["candidates"] = candidates_study(preds, objectives)
    summary["measured_configs"] = sum(len(meas.get(s, c, o)["ratios"]) for s in cams for c in cams[s] for o in objectives)
    summary["load_during_measurement"] = [r["load1"] for s in cams for c in cams[s] for o in objectives
                                          for r in meas.get(s, c, o)["runs"]]
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        with open(os.path.join(a.out, "rows.json"), "w") as f:
            json.dump(rows, f)
        with open(os.path.join(a.out, "summary.json"), "w") as f:
            json.dump(summary, f, indent=1, sort_keys=True)
        with open(os.path.join(a.out, "summary.md"), "w") as f:
            f.write(markdown(summary, a))
        from tools.hybrid import figures
        figures.draw(rows, summary, a.out)
    print(json.dumps(summary["table"], indent=1))
    return 0


def example(rows, jobs, scene="bmw-m6", objective="render"):
    """Fig. 3.16's data: the first validation camera of split 0 (or of the held-out
    protocol) in `scene` (the thesis' car), its search curve as ratios to the default, the
    roofline and each model's prediction."""
    protocol = next((p for p in ("split0",) + tuple(sorted({r["protocol"] for r in rows}))
                     if p.startswith(("split0", "heldout")) and any(r["protocol"] == p for r in rows)),
                    "split0")
    sel = [r for r in rows if r["variant"] == "default" and r["protocol"] == protocol and
           r["objective"] == objective]
    if not any(r["scene"] == scene for r in sel):
        scene = sorted({r["scene"] for r in sel})[0] if sel else None
    cams = sorted(r["camera"] for r in sel if r["scene"] == scene)
    if not cams:
        return None
    c = cams[0]
    job = jobs[(scene, c, objective)]
    d = job["default_cost"]
    search = [1.0] + [h["cost"] / d for h in job["history"] if h["cost"] < 1e299]
    pick = {r["model"]: r for r in sel if r["scene"] == scene and r["camera"] == c}
    return {"scene": scene, "camera": c, "objective": objective, "protocol": protocol,
            "default_ms": d, "search": search, "roofline": next(iter(pick.values()))["b"],
            "predicted": {m: r["p"] for m, r in pick.items()}}


def markdown(summary, a):
    """summary.md: the README's tables (geo-means beside the thesis' figures)."""
    def f(x, fmt="{:.3f}"):
        return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else fmt.format(x)
    t = summary["table"]
    cams = summary["scenes"]
    loads = summary["load_during_measurement"]
    ho = summary.get("heldout")
    split = (f"trained on every camera of {', '.join(ho['train'])}, tested on every camera of "
             f"{', '.join(ho['test'])}" if ho else
             f"80/20 camera splits x {a.splits} (per scene, seeded), leave-one-scene-out")
    out = [f"Protocol: {len(cams)} scenes ({', '.join(f'{s} {n}' for s, n in sorted(cams.items()))} "
           f"cameras), {split}; "
           f"measurements side by side, {a.rounds} rounds alternating, CPU time of one thread; "
           f"load average during the measurements {f(min(loads) if loads else None, '{:.1f}')}-"
           f"{f(max(loads) if loads else None, '{:.1f}')}.", ""]
    for o in ("render", "build+render"):
        th = THESIS.get(o, {})
        out += [f"**{o}**", "",
                "| model | speed-up over search (thesis) | fraction of roofline (thesis) | overhead "
                "reduction: geo-mean of scenes / best scene (thesis best) | overhead reduction, time: "
                "all cameras / worst scene; cameras <= 0 | break-even: mean of "
                "positive / negative of all | leave-one-scene-out speed-up / roofline | vs best "
                "static | predict ms / frame ms |", "|---|---|---|---|---|---|---|---|---|"]
        for m in ("nn", "rbf", "static"):
            r = t.get(f"{o}/{m}")
            if not r:
                continue
            out.append(
                f"| {m} | {f(r['speedup'])} ({f(th.get('speedup', {}).get(m), '{:.2f}')}) | "
                f"{f(r['roofline'])} ({f(th.get('roofline', {}).get(m), '{:.2f}')}) | "
                f"{f(r['overhead_reduction_geomean_of_scenes'])} / {f(r['overhead_reduction_max_scene'])} "
                f"({f(th.get('overhead_max', {}).get(m), '{:.3f}')}) | "
                f"{f(r['overhead_reduction_time'])} / {f(r['overhead_reduction_time_min_scene'])}; "
                f"{r['overhead_reduction_nonpositive']} of {r['n']} | "
                f"{f(r['break_even_mean_positive'], '{:.0f}')} / {r['break_even_negative']} of "
                f"{r['break_even_points']} | {f(r['loso_speedup'])} / {f(r['loso_roofline'])} | "
                f"{f(r['beats_static'])} | {f(r['predict_ms_median'], '{:.3g}')} / "
                f"{f(r['frame_ms_median'], '{:.3g}')} |")
        out.append("")
        ps = summary["per_scene"]
        models = [m for m in ("nn", "rbf", "static") if f"{o}/{m}" in ps]
        if models:
            out += ["| scene | " + " | ".join(f"{m} speed-up (LOSO)" for m in models) + " | " +
                    " | ".join(f"{m} roofline" for m in models) + " |",
                    "|---|" + "---|" * (2 * len(models))]
            for sc in sorted(set().union(*(ps[f"{o}/{m}"] for m in models))):
                out.append(f"| {sc} | " + " | ".join(
                    f"{f(ps[f'{o}/{m}'][sc]['speedup'])} ({f(ps[f'{o}/{m}'][sc]['loso_speedup'])})"
                    for m in models) + " | " + " | ".join(f(ps[f"{o}/{m}"][sc]["roofline"]) for m in models) + " |")
            out.append("")
    rs = summary.get("reward_spread", {})
    if rs:
        out += ["Reward scale (item 3): share of the reward's variance within a state (the most "
                "the configuration can explain; the rest is which state it is), over the baseline's "
                "samples; and the search's best sample / the default, median of the states.", "",
                "| objective | states / samples | R = 1/cost: within states | state means of 1/cost (1/ms) "
                "| R = default/cost: within states | best / default (median) |", "|---|---|---|---|---|---|"]
        for o in ("render", "build+render"):
            v = rs.get(o)
            if v:
                out.append(f"| {o} | {v['states']} / {v['samples']} | {f(v['within_share_inverse'])} | "
                           f"{f(v['inverse_state_mean_min'], '{:.4f}')}-{f(v['inverse_state_mean_max'], '{:.4f}')} | "
                           f"{f(v['within_share_relative'])} | {f(v['best_over_default_median'])} |")
        out.append("")
    cs = summary.get("candidates", {})
    if cs:
        out += ["Argmax candidates (RBF, item 3), from the predictions of one trained model per split "
                "against the largest set (4096 Latin-hypercube points + 3 refinement rounds): same "
                "answer, and Q's shortfall below the largest set's answer.", "",
                "| candidates: LHS-refine / objective | states | same answer | Q shortfall median / max "
                "| candidates compared (median) | predict ms |", "|---|---|---|---|---|---|"]
        for k in sorted(cs, key=lambda k: (k.split("/")[1], k)):
            v = cs[k]
            out.append(f"| {k} | {v['n']} | {f(v['same_share'])} | {f(v['q_gap_median'], '{:.2%}')} / "
                       f"{f(v['q_gap_max'], '{:.2%}')} | {v['candidates_median']} | "
                       f"{f(v['predict_ms_median'], '{:.3g}')} |")
        out.append("")
    st = summary.get("studies", {})
    if st:
        out += ["| study / objective / model | speed-up (splits) | roofline | leave-one-scene-out "
                "speed-up / roofline | overhead reduction, time | slower than the default | same "
                "splits, default: speed-up / roofline | entries | memory KiB | predict ms |",
                "|---|---|---|---|---|---|---|---|---|---|"]
        for k in sorted(st):
            v = st[k]
            out.append(f"| {k} | {f(v['speedup'])} | {f(v['roofline'])} | {f(v['loso_speedup'])} / "
                       f"{f(v['loso_roofline'])} ({v['loso_n']}) | {f(v['overhead_reduction_time'])} | "
                       f"{v['slower_than_default']} of {v['n']} | {f(v['default_speedup'])} / "
                       f"{f(v['default_roofline'])} | {v['entries']} | {f((v['memory_bytes'] or 0) / 1024, '{:.0f}')} | "
                       f"{f(v['predict_ms_median'], '{:.3g}')} |")
    return "\n".join(out) + "\n"


def overhead_time(rows):
    """1 - (the predictions' summed overhead) / (the search's summed overhead) over `rows`."""
    den = sum(r["overhead_search"] for r in rows if r["overhead_search"] > 0)
    return 1.0 - sum(r["overhead_pred"] for r in rows if r["overhead_search"] > 0) / den if den > 0 else float("nan")


def summarize(rows, cams, objectives, models):
    out = {"table": {}, "per_scene": {}, "studies": {}}
    for o in objectives:
        for m in models:
            sel = [r for r in rows if r["variant"] == "default" and r["model"] == m and r["objective"] == o
                   and r["protocol"].startswith(MAIN)]
            loso = [r for r in rows if r["variant"] == "default" and r["model"] == m and r["objective"] == o
                    and r["protocol"].startswith("loso")]
            if not sel:
                continue
            be = [r["break_even"] for r in sel if math.isfinite(r["break_even"])]
            pos = sorted(x for x in be if 0 < x < 10000)
            per_scene = {}
            # the scenes predicted (a held-out protocol predicts its test scenes only)
            for s in sorted({r["scene"] for r in sel + loso}):
                ss = [r for r in sel if r["scene"] == s]
                ls = [r for r in loso if r["scene"] == s]
                per_scene[s] = {"speedup": geomean(r["speedup"] for r in ss),
                                "roofline": geomean(r["roofline"] for r in ss),
                                "overhead_reduction": geomean(max(1e-9, r["overhead_reduction"]) for r in ss
                                                              if math.isfinite(r["overhead_reduction"])),
                                # the share of the search's overhead time the prediction removes,
                                # summed over the scene's validation cameras (defined for any sign)
                                "overhead_reduction_time": overhead_time(ss),
                                "loso_speedup": geomean(r["speedup"] for r in ls),
                                "loso_roofline": geomean(r["roofline"] for r in ls), "n": len(ss)}
            out["per_scene"][f"{o}/{m}"] = per_scene
            pm = [r["predict_ms"] for r in sel if r["predict_ms"] is not None]
            frames = [r["default_ms"] for r in sel]
            out["table"][f"{o}/{m}"] = {
                "speedup": geomean(r["speedup"] for r in sel),
                "roofline": geomean(r["roofline"] for r in sel),
                "overhead_reduction_geomean_of_scenes": geomean(v["overhead_reduction"] for v in per_scene.values()),
                "overhead_reduction_time": overhead_time(sel),
                "overhead_reduction_time_min_scene": min(v["overhead_reduction_time"] for v in per_scene.values()),
                "overhead_reduction_nonpositive": sum(1 for r in sel if not r["overhead_reduction"] > 0),
                "overhead_reduction_max_scene": max((v["overhead_reduction"] for v in per_scene.values()
                                                     if math.isfinite(v["overhead_reduction"])), default=float("nan")),
                "break_even_mean_positive": sum(pos) / len(pos) if pos else float("nan"),
                "break_even_median_positive": pos[len(pos) // 2] if pos else float("nan"),
                "break_even_negative": sum(1 for x in be if x < 0), "break_even_points": len(be),
                "loso_speedup": geomean(r["speedup"] for r in loso),
                "loso_roofline": geomean(r["roofline"] for r in loso),
                "beats_static": None,
                "predict_ms_median": sorted(pm)[len(pm) // 2] if pm else None,
                "frame_ms_median": sorted(frames)[len(frames) // 2] if frames else None,
                "memory_bytes": sel[0]["memory_bytes"], "entries": sel[0]["entries"], "n": len(sel)}
    for o in objectives:
        st = out["table"].get(f"{o}/static")
        for m in models:
            t = out["table"].get(f"{o}/{m}")
            if t and st and m != "static":
                t["beats_static"] = t["speedup"] / st["speedup"]
    # studies: geo-means per variant over the splits they ran on, against the default on the
    # same splits
    for v in sorted({r["variant"] for r in rows} - {"default"}):
        for o in objectives:
            for m in models:
                allv = [r for r in rows if r["variant"] == v and r["model"] == m and r["objective"] == o]
                sel = [r for r in allv if r["protocol"].startswith(MAIN)]
                lsel = [r for r in allv if r["protocol"].startswith("loso")]
                if not sel:
                    continue
                keys = {(r["protocol"], r["scene"], r["camera"]) for r in sel}
                base = [r for r in rows if r["variant"] == "default" and r["model"] == m and
                        r["objective"] == o and (r["protocol"], r["scene"], r["camera"]) in keys]
                out["studies"][f"{v}/{o}/{m}"] = {
                    "speedup": geomean(r["speedup"] for r in sel), "roofline": geomean(r["roofline"] for r in sel),
                    "default_speedup": geomean(r["speedup"] for r in base),
                    "default_roofline": geomean(r["roofline"] for r in base),
                    "loso_speedup": geomean(r["speedup"] for r in lsel),
                    "loso_roofline": geomean(r["roofline"] for r in lsel), "loso_n": len(lsel),
                    "overhead_reduction_time": overhead_time(sel),
                    "slower_than_default": sum(1 for r in sel if r["p"] > 1.0),
                    "memory_bytes": sel[0]["memory_bytes"], "entries": sel[0]["entries"],
                    "predict_ms_median": sorted(r["predict_ms"] for r in sel)[len(sel) // 2], "n": len(sel)}
    return out


if __name__ == "__main__":
    sys.exit(main())
