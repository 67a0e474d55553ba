"""Per-frame acceleration-structure update + render time along an animated sequence, per
way of choosing accel_embree's configuration (thesis 3.2.3's dynamic scenes; goals: tuned
>= 1.3x Embree's default rebuild, the tuned rebuild schedule beating both always rebuild and
always refit):

  default rebuild       Embree's defaults, built from scratch every frame
  always refit          refit every frame (never rebuilt)
  refit, tuned schedule refit with a rebuild every N frames or once the refitted tree's SAH
                        cost grew by a factor G: the best of a sweep of whole sequences over
                        --intervals N and --growths G (the least of --sweep-rounds runs
                        each, before the rounds)
  best static           the configuration a still tune finds (build+render of one still
                        frame at the sequence's start time, the update parameters left out),
                        rebuilt every frame
  tuned, replayed       the best configuration of a tuning along the sequence (tuner_nm over
                        the whole space, update parameters included), replayed as fixed
  tuned, live           that tuning itself: the sequence with the search running in it, its
                        measurement windows included (what a user's one tuned run costs)
  hybrid-predicted      host --hybrid --sequence --epsilon 0: a model (--hybrid-predictor,
                        default predictor_rbf, which tools/hybrid/sequence.py's validation
                        chose in the living-room-cylinder fold; nn in the two others) taught the searches along OTHER sequences (--hybrid-train,
                        measured with this run's settings) predicts per window of
                        --tune-window frames (only with --hybrid-train)

The rebuild schedule is swept over whole sequences, not searched in the tuner's windows: a
window (4-8 frames) starts with a build from scratch of its configuration, so every interval
longer than the window measures the same frames and the slow loss of a refitted tree (tens
of frames) never shows in it. The configurations that need a search get it once before the
rounds (METHODS and derive(): a method is its label, how its settings are found and the host
arguments it runs with). Every measurement is one `host --sequence` process over the scene
(the manifest records each frame's update_ms and render_ms); `--rounds` rounds run every
method once, the order rotated per round, so drift in the machine's load hits all alike.
Printed per method: medians over all frames of all rounds of update ms, render ms and their
sum, how many frames were built from scratch, and the median over rounds of (default
rebuild's summed frame time / this method's): the speed-up. The goals are checked on those
ratios. The load average is printed at the start and the end; --out keeps the raw figures as
JSON, --fig draws per-frame update + render, refit's render time relative to a fresh build
frame by frame (its degradation) and the schedule sweep.

--scene skinned generates the skinned/morphing glTF sequence (tools/scenes/blender_skinned.py,
120 frames: a tentacle of 9,216 vertices on 12 bones, a sphere breathing through morph
targets, orbiting boxes) with `blender -b` into build/anim_scenes/ (reused when present),
--scene skinned-detail the same with a tentacle of 147,456 vertices;
--scene stress-detail the rigid-bodies stress scene at 378,244 triangles
(tools/scenes/anim_stress.py --objects 64 --grid 160 --detail 4).

  /usr/bin/python3 -m tools.accel.anim_update --rounds 3 --frames 0:47
  nice -n 10 /usr/bin/python3 -m tools.accel.anim_update --scene scenes/animated-stress/scene.json \\
      --frames 0:119 --res 96x72 --rounds 3 --tune-iterations 8 --tune-window 8 \\
      --static-iterations 10 --out tools/accel/data/anim_update_animated-stress.json \\
      --fig tools/accel/figures/anim_update_animated-stress.png
  /usr/bin/python3 -m tools.accel.anim_update --scene skinned --frames 0:119 ...
  /usr/bin/python3 -m tools.accel.anim_update --replot tools/accel/data/anim_update_skinned.json \\
      --fig out.png
"""
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile

from tools.tttools import cli, host

ROOT = host.ROOT
REF = "default rebuild"
SCHEDULE = "refit, tuned schedule"
# the label an older JSON gives the schedule (an interval tuned by tuner_nm in its windows)
OLD_SCHEDULE = "refit, tuned interval"
HYBRID = "hybrid-predicted"
HYBRID_PARAMS = "updateMethod,refitInterval,refitSahGrowth,quality"
BUILDER = ["quality", "branchingFactor", "maxDepth", "sahBlockSize", "minLeafSize", "maxLeafSize",
           "travcost", "intcost", "static", "compact", "robust", "backend"]
# Sequences the tool generates when named as --scene (not committed: large, and
# deterministic, so regenerated identically): name -> (file under build/anim_scenes/NAME/,
# the generator command). skinned-detail is the skinned scene with a tentacle of 768 rings
# of 192 vertices (147,456 vertices on 12 bones) instead of 192 x 48. The committed scenes/animated-stress is the same generator at its
# defaults (1,240 triangles, a frame of a few ms); stress-detail is its bodies as level-4
# icospheres (5,120 triangles each) and a 160x160 cloth, 378,244 triangles every one of
# which moves, where the update is a real share of the frame.
GENERATED = {
    "skinned": ("skinned.gltf",
                lambda out: [shutil.which("blender") or "blender", "-b", "--factory-startup", "-P",
                             os.path.join(ROOT, "tools", "scenes", "blender_skinned.py"), "--",
                             "--out", out, "--frames", "120", "--fps", "24"]),
    "skinned-detail": ("skinned.gltf",
                       lambda out: [shutil.which("blender") or "blender", "-b", "--factory-startup",
                                    "-P", os.path.join(ROOT, "tools", "scenes", "blender_skinned.py"),
                                    "--", "--out", out, "--frames", "120", "--fps", "24",
                                    "--rings", "768", "--segments", "192"]),
    "stress-detail": ("scene.json",
                      lambda out: ["/usr/bin/python3", "-m", "tools.scenes.anim_stress", out,
                                   "--objects", "64", "--grid", "160", "--detail", "4"]),
}


def sets_of(config):
    """--set arguments (accel_embree.KEY=VALUE) of a configuration's JSON object."""
    out = []
    for k, v in config.items():
        if k == "counters":
            continue
        v = ("true" if v else "false") if isinstance(v, bool) else v
        out.append(f"{k}={v}")
    return out


def best_from_log(path, what):
    """The configuration JSON that ends the host's tuning summary line in the log at `path`."""
    with open(path) as f:
        lines = [ln for ln in f if ("tuning: best cost" in ln or "tuning along the sequence" in ln)]
    if not lines or ": {" not in lines[-1]:
        sys.exit(f"anim_update: {what}: no tuning summary in {path}")
    text = lines[-1]
    return json.loads(text[text.rfind(": {") + 2:])


def base_args(args, folder):
    return ["--sequence", args.frames, "--spp", str(args.spp), "--res", args.res,
            "--threads", str(args.threads), "--seed", "1", "--out-dir", folder]


def run_sequence(exe, scene, sets, args, folder, extra=()):
    """The manifest's frames of one `host --sequence` run."""
    cmd = base_args(args, folder) + list(extra)
    for s in sets:
        cmd += ["--set", "accel_embree." + s]
    host.run(exe, cmd + [scene], nice=args.nice, log=os.path.join(folder, "host.log"))
    with open(os.path.join(folder, "manifest.json")) as f:
        return [trim(fr) for fr in json.load(f)["frames"]]


def live_args(args):
    return ["--plugin", "tuner_nm", "--iterations", str(args.tune_iterations),
            "--tune-window", str(args.tune_window), "--no-db"]


KEEP = ("index", "time", "update", "update_ms", "render_ms", "sah_cost")


def trim(frame):
    """The manifest fields the figures and tables read (file names, jitter and the tuner's
    configurations per window left out), plus the tuning window's mode if there is one."""
    out = {k: frame[k] for k in KEEP if k in frame}
    if isinstance(frame.get("tune"), dict):
        out["tune"] = {k: frame["tune"][k] for k in ("window", "mode") if k in frame["tune"]}
    return out


def frame_ms(f):
    return f.get("update_ms", 0.0) + f["render_ms"]


def schedules(args):
    """The rebuild schedules the sweep runs: label -> accel_embree settings."""
    out = {}
    for n in args.intervals:
        out[f"every {n}"] = ["updateMethod=refit", f"refitInterval={n}"]
    for g in args.growths:
        out[f"SAH x{g:g}"] = ["updateMethod=refit", f"refitSahGrowth={g:g}"]
    return out


def sweep_schedules(exe, args, tmp):
    """Every schedule over the whole sequence, --sweep-rounds times (the order reversed every
    other round): {label: {"sets", "frame_ms" (the least summed frame time of its runs: the
    machine's load only adds time), "runs" (each run's sum), "rebuilt"}}, and the best label."""
    out = {}
    labels = list(schedules(args).items())
    for r in range(args.sweep_rounds):
        for k, sets in (labels if r % 2 == 0 else labels[::-1]):
            d = os.path.join(tmp, f"sweep{r}_" + k.replace(" ", "_"))
            os.makedirs(d)
            fr = run_sequence(exe, args.scene, sets, args, d)
            e = out.setdefault(k, {"sets": sets, "runs": [],
                                   "rebuilt": sum(f.get("update") == "rebuild" for f in fr)})
            e["runs"].append(sum(frame_ms(f) for f in fr))
            e["frame_ms"] = min(e["runs"])
    for k, e in out.items():
        print(f"schedule {k:10s}: {e['frame_ms']:10.1f} ms over the sequence (least of "
              f"{len(e['runs'])}), {e['rebuilt']} rebuilt", flush=True)
    if not out:
        sys.exit("anim_update: --intervals and --growths are both empty: no schedule to sweep")
    return out, min(out, key=lambda k: out[k]["frame_ms"])


def derive(exe, args, tmp):
    """What the methods need found once: the still tune's best, the schedule sweep, the best
    of a tuning along the sequence (a dict; METHODS read it; a search no chosen method needs
    is skipped)."""
    found = {"static": None, "sweep": {}, "schedule": None, "along": None}
    if SCHEDULE in args.methods:
        found["sweep"], found["schedule"] = sweep_schedules(exe, args, tmp)
    if "best static" in args.methods:
        found["static"] = still_tune(exe, args, tmp)
    if "tuned, replayed" in args.methods:
        d = os.path.join(tmp, "along")
        os.makedirs(d)
        run_sequence(exe, args.scene, [], args, d, live_args(args))
        found["along"] = best_from_log(os.path.join(d, "host.log"), "tuning along the sequence")
    if HYBRID in args.methods:
        found["hybrid_db"] = hybrid_train(exe, args, tmp)
    return found


def hybrid_args(args):
    return ["--hybrid", "--tune-window", str(args.tune_window), "--iterations",
            str(args.tune_iterations), "--tune-params", HYBRID_PARAMS]


def hybrid_train(exe, args, tmp):
    """Searches along every --hybrid-train sequence (each window searched) into one
    database, measured as this run measures: the model's warm start."""
    db = os.path.join(tmp, "hybrid_train.db")
    for i, scene in enumerate(args.hybrid_train):
        d = os.path.join(tmp, f"hybrid_train_{i}")
        os.makedirs(d)
        run_sequence(exe, scene, [], args, d, hybrid_args(args) + ["--epsilon", "1", "--db", db])
    return db


def still_tune(exe, args, tmp):
    """The best configuration of a still tune at the sequence's start time, rebuilt."""
    d = os.path.join(tmp, "static")
    os.makedirs(d)
    log = os.path.join(d, "host.log")
    # the still frame of an animated scene: the update parameters would only be noise there,
    # so the builder's parameters are named (the plan leaves motion-only ones out by itself
    # only for a scene that never moves)
    host.run(exe, ["--plugin", "tuner_nm", "--objective", "build+render", "--iterations",
                   str(args.static_iterations), "--tune-params", ",".join(BUILDER),
                   "--spp", str(args.spp), "--res", args.res,
                   "--threads", str(args.threads), "--no-db", "--out", os.path.join(d, "still.exr"),
                   args.scene], nice=args.nice, log=log)
    static = best_from_log(log, "still tune")
    static.update(updateMethod="rebuild", refitInterval=0, refitSahGrowth=0)
    return static


# The methods measured in the rounds, in table order: label -> function(found, args) giving
# (accel_embree settings, extra host arguments), `found` being derive()'s dict. A new way of
# choosing the configuration is one more entry here (and, if it needs a search first, one
# more key of derive()).
METHODS = {
    REF: lambda found, args: ([], []),
    "always refit": lambda found, args: (["updateMethod=refit"], []),
    SCHEDULE: lambda found, args: (found["sweep"][found["schedule"]]["sets"], []),
    "best static": lambda found, args: (sets_of(found["static"]), []),
    "tuned, replayed": lambda found, args: (sets_of(found["along"]), []),
    "tuned, live": lambda found, args: ([], live_args(args)),
    HYBRID: lambda found, args: ([], hybrid_args(args) + [
        "--epsilon", "0", "--warm-start", found["hybrid_db"], "--no-db", "--plugin",
        args.hybrid_predictor]),
}


def summarize(data):
    """Per method: medians, rebuilt frames, speed-up over default rebuild; the goals."""
    frames = data["runs"]
    rows = {}
    for k, runs in frames.items():
        every = [f for run in runs for f in run]
        speed = statistics.median(sum(frame_ms(f) for f in a) / sum(frame_ms(f) for f in b)
                                  for a, b in zip(frames[REF], runs))
        rows[k] = {"update_ms": statistics.median(f.get("update_ms", 0.0) for f in every),
                   "render_ms": statistics.median(f["render_ms"] for f in every),
                   "frame_ms": statistics.median(frame_ms(f) for f in every),
                   "rebuilt": sum(f.get("update") == "rebuild" for f in every),
                   "frames": len(every), "speedup": speed}
    g = {}
    if "tuned, live" in rows:
        g["tuned live >= 1.3x default rebuild"] = rows["tuned, live"]["speedup"] >= 1.3
    if HYBRID in rows:
        g["hybrid-predicted >= 1.3x default rebuild"] = rows[HYBRID]["speedup"] >= 1.3
    if "tuned, replayed" in rows and "tuned, live" in rows:
        g["tuned live within 5% of tuned best replayed"] = \
            rows["tuned, live"]["speedup"] >= rows["tuned, replayed"]["speedup"] / 1.05
    sched = SCHEDULE if SCHEDULE in rows else OLD_SCHEDULE
    if sched in rows:
        ti = rows[sched]["speedup"]
        g["tuned rebuild schedule beats always rebuild"] = ti > 1.0
        if "always refit" in rows:
            g["tuned rebuild schedule beats always refit"] = ti > rows["always refit"]["speedup"]
    return rows, g


def report(data):
    rows, goals = summarize(data)
    print(f"{data['scene']}: frames {data['frames']}, {data['res']}, {data['spp']} spp, "
          f"{data['threads']} threads, {data['rounds']} rounds (medians over every frame of every "
          f"round; wall time; speed-up: median over rounds of the summed frame-time ratio)")
    if data.get("schedule"):
        print(f"tuned schedule: {data['schedule']} (sweep, summed ms over the sequence: " +
              ", ".join(f"{k} {v['frame_ms']:.0f}" for k, v in data["sweep"].items()) + ")")
    print(f"{'method':24s} {'update ms':>10s} {'render ms':>10s} {'frame ms':>9s} "
          f"{'rebuilt':>9s} {'x default':>10s}")
    for k, r in rows.items():
        print(f"{k:24s} {r['update_ms']:10.3f} {r['render_ms']:10.2f} {r['frame_ms']:9.2f} "
              f"{r['rebuilt']:4d}/{r['frames']:<4d} {r['speedup']:10.3f}")
    for name, ok in goals.items():
        print(f"goal: {name}: {'met' if ok else 'MISSED'}")
    if not any("hybrid" in k for k in rows):
        print("not measured: hybrid-predicted per frame")
    return rows, goals


def plot(data, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    sweep = data.get("sweep")
    fig, axes = plt.subplots(1, 3 if sweep else 2, figsize=(17 if sweep else 12, 4.2))
    a, b = axes[0], axes[1]

    def per_frame(runs, fn):
        n = min(len(r) for r in runs)
        return ([runs[0][i]["index"] for i in range(n)],
                [statistics.median(fn(r[i]) for r in runs) for i in range(n)])

    for k, runs in data["runs"].items():
        a.plot(*per_frame(runs, frame_ms), label=k, lw=1.2)
    # refit's degradation: render time over the fresh build's, frame by frame and round by
    # round (the camera and the scene change along the sequence; the ratio keeps the tree)
    ref = data["runs"][REF]
    for k in ("always refit", SCHEDULE, OLD_SCHEDULE):
        if k not in data["runs"]:
            continue
        runs = data["runs"][k]
        n = min(len(r) for r in runs + ref)
        idx = [runs[0][i]["index"] for i in range(n)]
        ratio = [statistics.median(r[i]["render_ms"] / q[i]["render_ms"] for r, q in zip(runs, ref))
                 for i in range(n)]
        # the raw ratio is noisy on a loaded machine: drawn faint, with its running median
        # over 9 frames
        line, = b.plot(idx, ratio, lw=0.6, alpha=0.35)
        smooth = [statistics.median(ratio[max(0, i - 4):i + 5]) for i in range(n)]
        b.plot(idx, smooth, color=line.get_color(), lw=1.6, label=k + " (running median of 9)")
        rb = [i for i in range(n) if runs[0][i].get("update") == "rebuild"]
        if rb and k != "always refit":
            b.plot([idx[i] for i in rb], [smooth[i] for i in rb], "k|", ms=8,
                   label="rebuilt (round 1)")
    b.axhline(1.0, color="grey", lw=0.8)
    a.set(xlabel="frame", ylabel="update + render ms (median over rounds)",
          title=os.path.basename(os.path.dirname(data["scene"])) or data["scene"])
    b.set(xlabel="frame", ylabel="render ms / default rebuild's (median over rounds)",
          title="refit's render time as the refitted tree ages")
    a.set_yscale("log")
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    if sweep:
        c = axes[2]
        keys = list(sweep)
        reb = statistics.median(sum(frame_ms(f) for f in r) for r in ref)
        c.bar(range(len(keys)), [sweep[k]["frame_ms"] / reb for k in keys],
              color=["C2" if k == data["schedule"] else "C0" for k in keys])
        c.set_xticks(range(len(keys)))
        c.set_xticklabels(keys, rotation=45, fontsize=7, ha="right")
        for lbl, col in ((REF, "grey"), ("always refit", "C1")):
            if lbl in data["runs"]:
                c.axhline(statistics.median(sum(frame_ms(f) for f in r) for r in data["runs"][lbl])
                          / reb, color=col, lw=1, ls="--", label=lbl + " (rounds)")
        c.set(ylabel="sequence time / default rebuild's",
              title="rebuild schedule sweep (best of %d run(s) each; chosen: green)"
              % max(len(v.get("runs", [0])) for v in sweep.values()))
        c.legend(fontsize=7)
    fig.text(0.01, 0.005, f"{data['res']}, {data['spp']} spp, {data['threads']} threads, "
             f"{data['rounds']} interleaved rounds, loaded shared machine"
             + (f"; {data['note']}" if data.get("note") else ""), fontsize=7)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def generated_scene(name):
    """The path of the generated sequence `name` (GENERATED), written unless there already."""
    file, command = GENERATED[name]
    out = os.path.join(ROOT, "build", "anim_scenes", name, file)
    if os.path.exists(out):
        return out
    os.makedirs(os.path.dirname(out), exist_ok=True)
    cmd = command(out)
    if name.startswith("skinned") and not shutil.which("blender"):
        sys.exit(f"anim_update: --scene {name} needs Blender (apt-get install blender) to "
                 "generate the sequence; or give --scene PATH")
    p = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0 or not os.path.exists(out):
        sys.exit(f"anim_update: {' '.join(cmd)}: exit {p.returncode}\n{p.stdout[-2000:]}")
    return out


def int_list(text):
    return [int(x) for x in text.split(",") if x.strip()]


def float_list(text):
    return [float(x) for x in text.split(",") if x.strip()]


def main(argv=None):
    p = cli.parser(__doc__)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "animated-cornell", "scene.json"),
                   help="scene to play (default scenes/animated-cornell), or a generated "
                        "sequence: " + ", ".join(GENERATED))
    p.add_argument("--frames", default="0:47", help="frames A:B of the sequence (default 0:47)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--res", default="128x128")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--tune-iterations", type=int, default=12,
                   help="tuner_nm iterations of the tuning along the sequence (default 12)")
    p.add_argument("--tune-window", type=int, default=4,
                   help="frames per measurement of that tuning (default 4)")
    p.add_argument("--static-iterations", type=int, default=20,
                   help="tuner_nm iterations of the still tune (default 20)")
    p.add_argument("--intervals", type=int_list, default=[2, 4, 8, 16, 32, 64],
                   help="rebuild intervals of the schedule sweep (default 2,4,8,16,32,64)")
    p.add_argument("--growths", type=float_list, default=[1.1, 1.25, 1.5, 2.0],
                   help="SAH growth factors of the schedule sweep (default 1.1,1.25,1.5,2)")
    p.add_argument("--sweep-rounds", type=int, default=2,
                   help="runs of every schedule in the sweep, the least kept (default 2)")
    p.add_argument("--methods", type=lambda t: [x.strip() for x in t.split(";") if x.strip()],
                   default=list(METHODS),
                   help="the methods to measure, separated by ';' (their labels hold commas; "
                        "default: all: " + "; ".join(METHODS) + f"; \"{REF}\" is always measured)")
    p.add_argument("--hybrid-train", type=lambda t: [x for x in t.split(",") if x], default=[],
                   help="scene.json files (comma-separated, not --scene) whose searches teach "
                        "the hybrid-predicted model; without, that method is not measured")
    p.add_argument("--hybrid-predictor", default="predictor_rbf")
    p.add_argument("--nice", type=int, default=None, help="run the host under nice -n NICE")
    p.add_argument("--out", help="raw per-frame figures as JSON")
    p.add_argument("--fig", help="PNG: per-frame update + render, refit's render drift, the sweep")
    p.add_argument("--replot", help="a JSON of --out: print and draw it, measure nothing")
    args = p.parse_args(argv)
    if args.replot:
        try:
            with open(args.replot) as f:
                data = json.load(f)
            data["runs"][REF]
        except (OSError, ValueError, KeyError) as e:
            sys.exit(f"anim_update: {args.replot}: not a JSON of --out with a \"runs\" object "
                     f"holding \"{REF}\" ({e})")
        report(data)
        if args.fig:
            plot(data, args.fig)
        return 0
    if args.sweep_rounds < 1:
        sys.exit("anim_update: --sweep-rounds must be >= 1")
    if min(args.intervals, default=2) < 1 or min(args.growths, default=2) <= 1.0:
        sys.exit("anim_update: --intervals must be >= 1 and --growths > 1 (a schedule that "
                 "rebuilds)")
    unknown = [m for m in args.methods if m not in METHODS]
    if unknown:
        sys.exit(f"anim_update: --methods: unknown {'; '.join(unknown)} (known, separated "
                 f"by ';': {'; '.join(METHODS)})")
    args.methods = [REF] + [m for m in METHODS if m in args.methods and m != REF]
    if not args.hybrid_train and HYBRID in args.methods:
        args.methods.remove(HYBRID)  # nothing to learn from: said in the report
    if any(os.path.abspath(t) == os.path.abspath(args.scene) for t in args.hybrid_train):
        sys.exit("anim_update: --hybrid-train holds --scene: the model must not learn the "
                 "sequence it predicts")
    exe = host.find(args.host)
    name = args.scene
    if args.scene in GENERATED:
        args.scene = generated_scene(args.scene)
    elif not os.path.isfile(args.scene):
        sys.exit(f"anim_update: --scene {args.scene}: no such file (or one of "
                 f"{', '.join(GENERATED)})")
    print(f"load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory(prefix="tt_anim_update.") as tmp:
        found = derive(exe, args, tmp)
        print(f"best static: {found['static']}\ntuned schedule: {found['schedule']}\n"
              f"tuned best: {found['along']}", flush=True)
        configs = {k: fn(found, args) for k, fn in METHODS.items() if k in args.methods}
        labels = list(configs)
        frames = {k: [] for k in labels}
        for r in range(args.rounds):
            order = labels[r % len(labels):] + labels[:r % len(labels)]
            for k in order:
                folder = os.path.join(tmp, f"r{r}_{labels.index(k)}")
                os.makedirs(folder)
                sets, extra = configs[k]
                frames[k].append(run_sequence(exe, args.scene, sets, args, folder, extra))
    print(f"load average at end: {os.getloadavg()}")
    scene = name if name in GENERATED else args.scene
    if os.path.abspath(scene).startswith(ROOT + os.sep):
        scene = os.path.relpath(scene, ROOT)
    data = {"scene": scene, "frames": args.frames, "res": args.res,
            "spp": args.spp, "threads": args.threads, "rounds": args.rounds,
            "tune_iterations": args.tune_iterations, "tune_window": args.tune_window,
            "static_iterations": args.static_iterations,
            "configs": {k: {"set": v[0], "host": v[1]} for k, v in configs.items()},
            "sweep": found["sweep"], "schedule": found["schedule"], "methods": args.methods,
            "load": os.getloadavg(), "runs": frames}
    rows, goals = report(data)
    data["summary"] = rows
    data["goals"] = goals
    if args.out:
        tmp_out = args.out + ".tmp"
        with open(tmp_out, "w") as f:
            json.dump(data, f, separators=(",", ":"))
        os.replace(tmp_out, args.out)
    if args.fig:
        plot(data, args.fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
