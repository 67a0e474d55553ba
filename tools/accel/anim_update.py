"""Per-frame acceleration-structure update + render time along an animated sequence, per
way of choosing accel_embree's configuration (thesis 3.2.3's dynamic scenes, issue goals:
tuned >= 1.3x Embree's default rebuild, the tuned rebuild interval beating both always
rebuild and always refit):

  default rebuild       Embree's defaults, built from scratch every frame
  always refit          refit every frame (never rebuilt)
  refit, tuned interval refit with a rebuild every N frames, N tuned along the sequence
                        (tuner_nm over refitInterval, updateMethod=refit)
  best static           the configuration a still tune finds (build+render of one still
                        frame at the sequence's start time, the update parameters left out),
                        rebuilt every frame
  tuned, replayed       the best configuration of a tuning along the sequence (tuner_nm over
                        the whole space, update parameters included), replayed as fixed
  tuned, live           that tuning itself: the sequence with the search running in it, its
                        measurement windows included (what a user's one tuned run costs)

The three configurations that need a search get it once before the rounds (`--tune-*`
options). Every measurement is one `host --sequence` process over the scene (the manifest
records each frame's update_ms and render_ms); `--rounds` rounds run every configuration
once, the order rotated per round, so drift in the machine's load hits all alike. Printed per
configuration: medians over all frames of all rounds of update ms, render ms and their sum,
how many frames were built from scratch, and the median over rounds of (default rebuild's
summed frame time / this configuration's): the speed-up. The goals are checked on those
ratios. Hybrid prediction along a sequence is not measured (no predictor runs per frame yet).
The load average is printed at the start and the end; --out keeps the raw figures as JSON,
--fig draws per-frame update + render and refit's render-time drift.

  /usr/bin/python3 -m tools.accel.anim_update --rounds 3 --frames 0:47
  /usr/bin/python3 -m tools.accel.anim_update --scene scenes/animated-stress/scene.json \\
      --frames 0:119 --res 160x120 --out /tmp/anim_stress.json \\
      --fig tools/accel/figures/anim_update_animated-stress.png
  /usr/bin/python3 -m tools.accel.anim_update --replot /tmp/anim_stress.json --fig out.png
"""
import json
import os
import statistics
import sys
import tempfile

from tools.tttools import cli, host

ROOT = host.ROOT
REF = "default rebuild"
BUILDER = ["quality", "branchingFactor", "maxDepth", "sahBlockSize", "minLeafSize", "maxLeafSize",
           "travcost", "intcost", "static", "compact", "robust", "backend"]


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
        return json.load(f)["frames"]


def live_args(args):
    return ["--plugin", "tuner_nm", "--iterations", str(args.tune_iterations),
            "--tune-window", str(args.tune_window), "--no-db"]


def derive(exe, args, tmp):
    """The configurations a search finds, once: (best static, tuned interval, tuned best)."""
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
    d = os.path.join(tmp, "interval")
    os.makedirs(d)
    run_sequence(exe, args.scene, ["updateMethod=refit"], args, d,
                 live_args(args) + ["--tune-params", "refitInterval"])
    interval = best_from_log(os.path.join(d, "host.log"), "interval tune")["refitInterval"]
    d = os.path.join(tmp, "along")
    os.makedirs(d)
    run_sequence(exe, args.scene, [], args, d, live_args(args))
    along = best_from_log(os.path.join(d, "host.log"), "tuning along the sequence")
    return static, interval, along


def frame_ms(f):
    return f.get("update_ms", 0.0) + f["render_ms"]


def summarize(data):
    """Per configuration: medians, rebuilt frames, speed-up over default rebuild; the goals."""
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
    if "tuned, replayed" in rows and "tuned, live" in rows:
        g["tuned live within 5% of tuned best replayed"] = \
            rows["tuned, live"]["speedup"] >= rows["tuned, replayed"]["speedup"] / 1.05
    if "refit, tuned interval" in rows:
        ti = rows["refit, tuned interval"]["speedup"]
        g["tuned interval beats always rebuild"] = ti > 1.0
        g["tuned interval beats always refit"] = ti > rows["always refit"]["speedup"]
    return rows, g


def report(data):
    rows, goals = summarize(data)
    print(f"{data['scene']}: frames {data['frames']}, {data['res']}, {data['spp']} spp, "
          f"{data['threads']} threads, {data['rounds']} rounds (medians over every frame of every "
          f"round; wall time; speed-up: median over rounds of the summed frame-time ratio)")
    print(f"{'configuration':24s} {'update ms':>10s} {'render ms':>10s} {'frame ms':>9s} "
          f"{'rebuilt':>9s} {'x default':>10s}")
    for k, r in rows.items():
        print(f"{k:24s} {r['update_ms']:10.3f} {r['render_ms']:10.2f} {r['frame_ms']:9.2f} "
              f"{r['rebuilt']:4d}/{r['frames']:<4d} {r['speedup']:10.3f}")
    for name, ok in goals.items():
        print(f"goal: {name}: {'met' if ok else 'MISSED'}")
    print("not measured: hybrid-predicted per frame (no predictor runs along a sequence yet)")
    return rows, goals


def plot(data, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(12, 4.2))
    for k, runs in data["runs"].items():
        n = min(len(r) for r in runs)
        idx = [runs[0][i]["index"] for i in range(n)]
        a.plot(idx, [statistics.median(frame_ms(r[i]) for r in runs) for i in range(n)], label=k,
               lw=1.2)
        if k in (REF, "always refit", "refit, tuned interval"):
            b.plot(idx, [statistics.median(r[i]["render_ms"] for r in runs) for i in range(n)],
                   label=k, lw=1.2)
    a.set(xlabel="frame", ylabel="update + render ms (median over rounds)",
          title=os.path.basename(os.path.dirname(data["scene"])) + ": per-frame cost")
    b.set(xlabel="frame", ylabel="render ms (median over rounds)",
          title="render time as the refitted tree ages")
    a.set_yscale("log")
    a.legend(fontsize=7)
    b.legend(fontsize=7)
    fig.text(0.01, 0.005, f"{data['res']}, {data['spp']} spp, {data['threads']} threads, "
             f"{data['rounds']} interleaved rounds, loaded shared machine", fontsize=7)
    fig.tight_layout()
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=110)
    os.replace(tmp, path)


def main(argv=None):
    p = cli.parser(__doc__)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes", "animated-cornell", "scene.json"))
    p.add_argument("--frames", default="0:47", help="frames A:B of the sequence (default 0:47)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--res", default="128x128")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--tune-iterations", type=int, default=12,
                   help="tuner_nm iterations of the tunings along the sequence (default 12)")
    p.add_argument("--tune-window", type=int, default=4,
                   help="frames per measurement of those tunings (default 4)")
    p.add_argument("--static-iterations", type=int, default=20,
                   help="tuner_nm iterations of the still tune (default 20)")
    p.add_argument("--nice", type=int, default=None, help="run the host under nice -n NICE")
    p.add_argument("--out", help="raw per-frame figures as JSON")
    p.add_argument("--fig", help="PNG: per-frame update + render, refit's render drift")
    p.add_argument("--replot", help="a JSON of --out: print and draw it, measure nothing")
    args = p.parse_args(argv)
    if args.replot:
        with open(args.replot) as f:
            data = json.load(f)
        report(data)
        if args.fig:
            plot(data, args.fig)
        return 0
    exe = host.find(args.host)
    print(f"load average at start: {os.getloadavg()}")
    with tempfile.TemporaryDirectory(prefix="tt_anim_update.") as tmp:
        static, interval, along = derive(exe, args, tmp)
        print(f"best static: {static}\ntuned interval: {interval}\ntuned best: {along}")
        configs = {REF: [], "always refit": ["updateMethod=refit"],
                   "refit, tuned interval": ["updateMethod=refit", f"refitInterval={interval}"],
                   "best static": sets_of(static), "tuned, replayed": sets_of(along),
                   "tuned, live": None}
        labels = list(configs)
        frames = {k: [] for k in labels}
        for r in range(args.rounds):
            order = labels[r % len(labels):] + labels[:r % len(labels)]
            for k in order:
                folder = os.path.join(tmp, f"r{r}_{labels.index(k)}")
                os.makedirs(folder)
                live = configs[k] is None
                frames[k].append(run_sequence(exe, args.scene, [] if live else configs[k], args,
                                              folder, live_args(args) if live else ()))
    print(f"load average at end: {os.getloadavg()}")
    data = {"scene": os.path.relpath(args.scene, ROOT), "frames": args.frames, "res": args.res,
            "spp": args.spp, "threads": args.threads, "rounds": args.rounds,
            "tune_iterations": args.tune_iterations, "tune_window": args.tune_window,
            "static_iterations": args.static_iterations,
            "configs": {k: (v if v is not None else "live tuner_nm search") for k, v in configs.items()},
            "load": os.getloadavg(), "runs": frames}
    rows, goals = report(data)
    data["summary"] = rows
    data["goals"] = goals
    if args.out:
        tmp_out = args.out + ".tmp"
        with open(tmp_out, "w") as f:
            json.dump(data, f, indent=1)
        os.replace(tmp_out, args.out)
    if args.fig:
        plot(data, args.fig)
    return 0


if __name__ == "__main__":
    sys.exit(main())
