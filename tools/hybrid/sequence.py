"""Hybrid tuning along animated sequences (host --hybrid --sequence): a model that learnt from
searches along OTHER sequences predicts the accel configuration (update method included) per
window of frames of a test sequence, against Embree's default rebuild and against the
per-window best that a search along the test sequence itself finds.

  1. searches: `host --hybrid --sequence A:B --epsilon 1` along each --train scene and the
     --validation scene (every window of --window frames searched with tuner_nm,
     --iterations K over --params; every sample a row, one database per scene), and along
     the --test scene into search_TEST.db (what a search finds per window there; never taught
     to a predicting model);
  2. validation: each of --predictors, warm-started from the training scenes' rows only,
     predicts the validation sequence (`--hybrid --epsilon 0`); the one with the best
     speed-up over the default is chosen;
  3. test (--rounds rounds, the order rotated per round; one host process per run):
       default rebuild     plain `host --sequence` (accel_embree's defaults: rebuilt every frame)
       hybrid-predicted    the chosen predictor, warm-started from train + validation rows,
                           answering per window, each window played once (a user's run);
                           the other predictors beside it
       per-window best     predictor_nn taught the test sequence's own searches: each window
                           runs the best its search found there (checked against the search)
     A run's figure is its summed per-frame update + render ms (manifest.json); per round the
     ratios default / hybrid (speed-up) and hybrid / per-window best are taken, and their
     medians over rounds reported. Goals: speed-up >= 1.3x, within 5% of the per-window best.

A scene is a folder of scenes/ (animated-cornell, animated-stress, living-room-cylinder) or a
large sequence that tools/accel/anim_update.py generates into build/anim_scenes/ (stress-detail:
64 rigid bodies and a cloth, 378,244 triangles; skinned-detail: a Blender-skinned tentacle of
147,456 vertices; generated on first use, skinned-detail needs Blender).

Costs are CPU time (--clock cpu) of --threads 1 by default: the machine is shared, wall time
would measure the other processes. The search's own costs (the best of K noisy samples) are
printed too, but the goals use the re-measured replays.

  nice -n 10 /usr/bin/python3 -m tools.hybrid.sequence --frames 0:119 --res 160x120 \\
      --out tools/hybrid/figures/sequence/sequence.json \\
      --fig tools/hybrid/figures/sequence/sequence.png
  /usr/bin/python3 -m tools.hybrid.sequence --replot tools/hybrid/figures/sequence/sequence.json
"""
import json
import os
import statistics
import sys
import tempfile

from tools.tttools import cli, host

ROOT = host.ROOT
SCENES = os.path.join(ROOT, "scenes")


def scene_path(name):
    """The scene file of a --train/--validation/--test name: a sequence that
    tools/accel/anim_update.py generates (stress-detail, skinned-detail, skinned: written into
    build/anim_scenes/ unless there already), else a folder of scenes/."""
    from tools.accel import anim_update
    if name in anim_update.GENERATED:
        return anim_update.generated_scene(name)
    path = os.path.join(SCENES, name, "scene.json")
    if not os.path.isfile(path):
        sys.exit(f"sequence: scene '{name}' (--train/--validation/--test): expected a folder of "
                 f"scenes/ with a scene.json ({path} does not exist) or a generated sequence "
                 f"({', '.join(anim_update.GENERATED)})")
    return path


def common(args, out):
    return ["--sequence", args.frames, "--spp", str(args.spp), "--res", args.res, "--threads",
            str(args.threads), "--clock", "cpu", "--seed", "1", "--out-dir", out,
            "--aov", "none"]


def hybrid_args(args, stats):
    return ["--hybrid", "--tune-window", str(args.window), "--iterations", str(args.iterations),
            "--tune-params", args.params, "--stats", stats]


def trim(frame):
    """The manifest fields the figures read: the frame, its update and times, its state."""
    out = {k: frame[k] for k in ("index", "update", "update_ms", "render_ms") if k in frame}
    hy = frame.get("hybrid")
    if isinstance(hy, dict):
        out["hybrid"] = {k: hy[k] for k in ("state", "mode", "continued") if k in hy}
    return out


def run(exe, args, argv, folder, log):
    os.makedirs(folder, exist_ok=True)
    host.run(exe, argv, nice=args.nice, log=log)
    with open(os.path.join(folder, "manifest.json")) as f:
        return [trim(fr) for fr in json.load(f)["frames"]]


def frames_ms(frames):
    return sum(f.get("update_ms", 0.0) + f["render_ms"] for f in frames)


def search(exe, args, scene, db, work, tag):
    """A search along `scene` (epsilon 1) into `db`; its --stats hybrid record."""
    folder = os.path.join(work, tag)
    stats = os.path.join(work, tag + ".json")
    if not os.path.exists(stats):
        # a search that did not finish (the host writes its --stats when stopped too) left
        # rows of part of the sequence: start its database afresh, and name the record only
        # once the host has exited cleanly, so that a resumed --work never reuses a partial one
        for x in (db, db + "-wal", db + "-shm"):
            if os.path.exists(x):
                os.remove(x)
        part = stats + ".part"
        run(exe, args, common(args, folder) + hybrid_args(args, part) +
            ["--epsilon", "1", "--db", db, scene], folder, os.path.join(work, tag + ".log"))
        os.replace(part, stats)
    with open(stats) as f:
        return json.load(f)["hybrid"]


def rounds(exe, args, tmp, tag, scene, methods):
    """Every method once per round (the order rotated per round): per method its runs'
    manifest frames and --stats hybrid records (None for plain sequences)."""
    labels = list(methods)
    runs = {k: [] for k in labels}
    stats = {k: [] for k in labels}
    for r in range(args.rounds):
        for k in labels[r % len(labels):] + labels[:r % len(labels)]:
            folder = os.path.join(tmp, f"{tag}_r{r}_{labels.index(k)}")
            st = folder + ".json"
            extra = [] if methods[k] is None else \
                hybrid_args(args, st) + ["--epsilon", "0", "--no-db"] + methods[k]
            runs[k].append(run(exe, args, common(args, folder) + extra + [scene], folder,
                               folder + ".log"))
            if extra:
                with open(st) as f:
                    stats[k].append(json.load(f)["hybrid"])
    return runs, stats


def ratios(runs, ref, best=None):
    """Per method: median frame ms, rebuilt frames, median per-round speed-up over `ref`
    and (with `best`) median per-round ratio to `best`."""
    rows = {}
    for k, rs in runs.items():
        rows[k] = {
            "frame_ms": statistics.median(frames_ms(r) / len(r) for r in rs),
            "rebuilt": statistics.median(sum(f.get("update") == "rebuild" for f in r) for r in rs),
            "speedup": statistics.median(frames_ms(a) / frames_ms(b)
                                         for a, b in zip(runs[ref], rs)),
        }
        if best:
            rows[k]["of_best"] = statistics.median(frames_ms(b) / frames_ms(a)
                                                   for a, b in zip(runs[best], rs))
    return rows


def summarize(data):
    rows = ratios(data["runs"], "default rebuild", "per-window best")
    h = rows["hybrid-predicted"]
    goals = {"hybrid-predicted >= 1.3x default rebuild": h["speedup"] >= 1.3,
             "hybrid-predicted within 5% of the per-window best": h["of_best"] <= 1.05}
    return rows, goals


def short(c):
    return f"{c['updateMethod']} q{c['quality']} N{c['refitInterval']}"


def report(data):
    rows, goals = summarize(data)
    print(f"train: {', '.join(data['train'])}; validation: {data['validation']} (chooses the "
          f"predictor); test: {data['test']} (predicted by a model warm-started from train + "
          f"validation)")
    print(f"frames {data['frames']}, {data['res']}, {data['spp']} spp, {data['threads']} "
          f"thread(s), CPU time, window {data['window']}, K {data['iterations']} over "
          f"{data['params']}, {data['rounds']} rounds; load {data['load_start']} -> "
          f"{data['load_end']}")
    print(f"validation on {data['validation']} (model from {', '.join(data['train'])}):")
    for k, r in data["validation_rows"].items():
        print(f"  {k:26s} {r['frame_ms']:9.2f} ms/frame {r['rebuilt']:5.0f} rebuilt "
              f"{r['speedup']:7.3f}x default")
    print(f"  chosen: {data['chosen']}")
    print(f"test on {data['test']}:")
    print(f"  {'method':34s} {'frame ms':>9s} {'rebuilt':>8s} {'x default':>10s} {'/ best':>8s}")
    for k, r in rows.items():
        print(f"  {k:34s} {r['frame_ms']:9.2f} {r['rebuilt']:8.0f} {r['speedup']:10.3f} "
              f"{r['of_best']:8.3f}")
    for k, cfgs in data["predicted"].items():
        distinct = sorted({short(c) for c in cfgs})
        print(f"  {k}: {len(distinct)} distinct configuration(s): {'; '.join(distinct)}")
    s = data["search"]
    print(f"search along the test sequence: {s['states']} windows, per-window best as the "
          f"search measured it {s['best_ms']:.2f} ms per frame (the cheapest of K noisy "
          f"samples); {s['frames_played']} frames played for {s['frames_written']} written "
          f"({s['overhead']:.1f}x the frames)")
    print(f"per-window best replay: {data['best_agree']} of {s['states']} windows ran the "
          f"search's best configuration")
    print(f"state (pose + indicators) per window: median {data['state_ms']:.3f} ms")
    for name, ok in goals.items():
        print(f"goal: {name}: {'met' if ok else 'MISSED'}")
    return rows, goals


def plot(data, path):
    """Per-frame update + render along the test sequence (median over rounds) per method."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 4.2))
    for k, runs in data["runs"].items():
        n = min(len(r) for r in runs)
        ax.plot([runs[0][i]["index"] for i in range(n)],
                [statistics.median(r[i].get("update_ms", 0.0) + r[i]["render_ms"] for r in runs)
                 for i in range(n)], label=k, lw=1.1)
    ax.set(xlabel="frame", ylabel="update + render ms (CPU, median over rounds)",
           title=f"test {data['test']}: hybrid-predicted ({data['chosen']})\nlearnt from "
                 f"{', '.join(data['train'])}; validation {data['validation']}")
    ax.title.set_fontsize(9)
    ax.legend(fontsize=7)
    fig.text(0.01, 0.005, f"{data['res']}, {data['spp']} spp, {data['threads']} thread, windows "
             f"of {data['window']} frames, {data['rounds']} interleaved rounds, loaded shared "
             f"machine", fontsize=7)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def main(argv=None):
    p = cli.parser(__doc__)
    p.add_argument("--train", default="animated-cornell",
                   help="scenes (folders of scenes/ or generated sequences such as "
                        "stress-detail) searched for the training rows")
    p.add_argument("--validation", default="animated-stress",
                   help="the scene that chooses the predictor (its searches then train too)")
    p.add_argument("--test", default="living-room-cylinder", help="the predicted scene")
    p.add_argument("--predictors", default="predictor_nn,predictor_rbf")
    p.add_argument("--frames", default="0:119")
    p.add_argument("--res", default="160x120")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--window", type=int, default=8, help="frames per state (--tune-window)")
    p.add_argument("--iterations", type=int, default=12, help="tuner_nm iterations per window")
    p.add_argument("--params", default="updateMethod,refitInterval,refitSahGrowth,quality",
                   help="the searched and predicted parameters (--tune-params): few enough "
                        "for K iterations of Nelder-Mead to move beyond its first simplex")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--work", help="keep the searches' databases and runs here (resumable)")
    p.add_argument("--nice", type=int, default=None)
    p.add_argument("--out", help="the raw figures as JSON")
    p.add_argument("--fig", help="PNG: per-frame update + render along the test sequence")
    p.add_argument("--replot", help="a JSON of --out: print (and --fig draw) it, measure nothing")
    args = p.parse_args(argv)
    if args.replot:
        with open(args.replot) as f:
            data = json.load(f)
        report(data)
        if args.fig:
            plot(data, args.fig)
        return 0
    exe = host.find(args.host)
    train = [t for t in args.train.split(",") if t]
    for t in [*train, args.validation, args.test]:
        scene_path(t)  # a bad name fails here, before any search runs
    predictors = [x for x in args.predictors.split(",") if x]
    if len({*train, args.validation, args.test}) != len(train) + 2:
        sys.exit("sequence: --train, --validation and --test scenes overlap: keep them apart")
    load_start = os.getloadavg()
    with tempfile.TemporaryDirectory(prefix="tt_seq_hybrid.") as tmp:
        work = args.work or tmp
        os.makedirs(work, exist_ok=True)
        dbs = {t: os.path.join(work, f"train_{t}.db") for t in [*train, args.validation]}
        for t in [*train, args.validation]:
            search(exe, args, scene_path(t), dbs[t], work, "train_" + t)
        # one database per test scene: folds sharing a --work folder never mix their searches
        search_db = os.path.join(work, f"search_{args.test}.db")
        found = search(exe, args, scene_path(args.test), search_db, work, "search_" + args.test)

        def warm(names):
            return [x for t in names for x in ("--warm-start", dbs[t])]

        # validation: the model learnt from the training scenes predicts the validation
        # sequence; the predictor with the best speed-up over the default is chosen
        methods = {"default rebuild": None}
        for pr in predictors:
            methods[pr] = warm(train) + ["--plugin", pr]
        vruns, _ = rounds(exe, args, tmp, "val", scene_path(args.validation), methods)
        vrows = ratios(vruns, "default rebuild")
        chosen = max(predictors, key=lambda pr: vrows[pr]["speedup"])
        # test: the chosen predictor, taught train + validation, predicts the test sequence
        methods = {"default rebuild": None,
                   "hybrid-predicted": warm([*train, args.validation]) + ["--plugin", chosen]}
        for pr in predictors:
            if pr != chosen:
                methods[f"hybrid-predicted ({pr})"] = warm([*train, args.validation]) + \
                    ["--plugin", pr]
        methods["per-window best"] = ["--warm-start", search_db, "--plugin", "predictor_nn"]
        runs, stats = rounds(exe, args, tmp, "test", scene_path(args.test), methods)
        load_end = os.getloadavg()
    best_cfg = [s["config"] for s in found["states"]]
    replay_cfg = [s["config"] for s in stats["per-window best"][0]["states"]]
    n = len(best_cfg)
    data = {"train": train, "validation": args.validation, "test": args.test,
            "predictors": predictors, "chosen": chosen,
            "frames": args.frames, "res": args.res, "spp": args.spp, "threads": args.threads,
            "window": args.window, "iterations": args.iterations, "params": args.params,
            "rounds": args.rounds,
            "load_start": [round(x, 2) for x in load_start],
            "load_end": [round(x, 2) for x in load_end],
            "validation_rows": vrows, "validation_runs": vruns,
            "search": {"states": n,
                       "best_ms": sum(s["cost"] for s in found["states"]) / n,
                       "frames_played": found["frames_played"],
                       "frames_written": sum(s["last_frame"] - s["first_frame"] + 1
                                             for s in found["states"]),
                       "configs": best_cfg},
            "best_agree": sum(a == b for a, b in zip(best_cfg, replay_cfg)),
            "state_ms": statistics.median(s["state_ms"] for s in found["states"]),
            "predicted": {k: [s["config"] for s in v[0]["states"]] for k, v in stats.items()
                          if v},
            "runs": runs}
    data["search"]["overhead"] = data["search"]["frames_played"] / data["search"]["frames_written"]
    rows, goals = report(data)
    data["summary"], data["goals"] = rows, goals
    if args.out:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        tmp_out = args.out + ".tmp"
        with open(tmp_out, "w") as f:
            json.dump(data, f, separators=(",", ":"))
        os.replace(tmp_out, args.out)
    if args.fig:
        plot(data, args.fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
