"""Tuning gains over the default configuration, measured side by side (issue 6 results).

For every scene x objective x seed this runs one tuning run of the host with --verify N
(after tuning, the default and the best configuration alternate N times in the same
process), then reports per scene and objective the medians over the seeds of:
  - render gain = 1 - median over rounds of render_ms(best) / render_ms(default)
  - total gain  = 1 - median over rounds of (build+render)(best) / (build+render)(default)
  - iterations to best = the iteration at which the finally kept configuration was
    first measured (0 = the first proposal; -1 = the default was kept)
  - iterations to converge = the iteration after which the best tuning-time cost so far
    improved by less than 1 % in total (convergence.converged_at; -1: the default was
    never beaten by 1 %)
and the spread (min..max) over seeds. --figures DIR writes one convergence chart per scene
(thesis Fig. 3.3 style: best cost so far per seed, default dashed, one panel per objective). Nothing in the database is reused: every run gets its
own database file, so each run measures its own default.

  G="/usr/bin/python3 -m tools.tuning.gains"         # from the repository root
  $G --scene scenes/cornell-box/scene.json \\
      --scene ../shared/scenes/living-room/living-room.pbrt --seeds 5 --iterations 40 \\
      --res 128x128 --verify 7 --out-dir /tmp/gains
  $G --summarize /tmp/gains          # tables again from the stats files
  $G --summarize /tmp/gains --figures tools/tuning/figures --figure-prefix conv120_
"""
import glob
import json
import os
import statistics
import sys

from tools.tttools import cli, host
from tools.tuning.convergence import converged_at, plot_scene


def scene_name(path):
    base = os.path.splitext(os.path.basename(path))[0]
    return os.path.basename(os.path.dirname(path)) if base == "scene" else base


def run_one(a, scene, objective, seed, extra, tag):
    name = f"{scene_name(scene)}__{tag}__{objective.replace('+', '_')}__s{seed}"
    stats = os.path.join(a.out_dir, name + ".json")
    if os.path.exists(stats) and not a.force:
        return stats
    args = ["--quiet", "--plugin", a.tuner, "--tune", "accel_embree", "--objective",
            objective, "--iterations", str(a.iterations), "--verify", str(a.verify),
            "--tune-spp", str(a.tune_spp), "--spp", "1", "--res", a.res, "--threads",
            str(a.threads), "--seed", str(seed), "--db", os.path.join(a.out_dir, name + ".db"),
            "--out", os.path.join(a.out_dir, name + ".exr"), "--clock", a.clock]
    if a.tune_params:
        args += ["--tune-params", a.tune_params]
    try:
        r = host.run(a.host, args + extra + [scene], stats=stats, capture=True)
    except host.HostError as e:
        print(f"gains: {e}", file=sys.stderr)
        return None
    print(f"  {name}: {r.wall_s:.1f} s", flush=True)
    return stats


def converge_iteration(t):
    """Iteration at which the kept configuration was first measured (-1: the default)."""
    best = json.dumps(t["best_config"], sort_keys=True)
    if best == json.dumps(t["default_config"], sort_keys=True):
        return -1
    for h in t["history"]:
        if json.dumps(h["config"], sort_keys=True) == best:
            return h["iteration"]
    return -1


def summarize(paths):
    groups = {}
    for p in paths:
        with open(p) as f:
            d = json.load(f)
        t = d["tuning"]
        v = t.get("verify")
        if not v:
            continue
        base = os.path.basename(p)[:-5].split("__")
        key = (base[0], base[1], t["objective"])
        samples = [(h["cost"], bool(h.get("cached"))) for h in t.get("history", [])]
        groups.setdefault(key, []).append(dict(
            seed=d.get("seed", base[-1]), samples=samples, default_cost=t["default_cost"],
            conv1=converged_at(samples, t["default_cost"]),
            render_gain=1 - v["render_ratio"], total_gain=1 - v["total_ratio"],
            conv=converge_iteration(t), iterations=t["iterations"],
            d_render=v["default"]["median_render_ms"], d_total=v["default"]["median_total_ms"],
            b_render=v["best"]["median_render_ms"], b_total=v["best"]["median_total_ms"],
            tune_gain=1 - t["best_cost"] / t["default_cost"], rounds=v["rounds"],
            best=t["best_config"]))
    lines = ["| scene | start | tuned for | runs | default render / total ms | render gain, median "
             "(min..max) | total gain, median (min..max) | gain seen while tuning | "
             "iterations to best, median (range) | converged (1 %), median (range) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    pct = lambda x: f"{100 * x:+.1f}%"
    for (scene, tag, obj), rs in sorted(groups.items()):
        rg = [r["render_gain"] for r in rs]
        tg = [r["total_gain"] for r in rs]
        cv = [r["conv"] for r in rs]
        c1 = [r["conv1"] for r in rs]
        lines.append(
            f"| {scene} | {tag} | {obj} | {len(rs)} | "
            f"{statistics.median(r['d_render'] for r in rs):.1f} / "
            f"{statistics.median(r['d_total'] for r in rs):.1f} | "
            f"{pct(statistics.median(rg))} ({pct(min(rg))}..{pct(max(rg))}) | "
            f"{pct(statistics.median(tg))} ({pct(min(tg))}..{pct(max(tg))}) | "
            f"{pct(statistics.median(r['tune_gain'] for r in rs))} | "
            f"{statistics.median(cv):g} ({min(cv)}..{max(cv)}) | "
            f"{statistics.median(c1):g} ({min(c1)}..{max(c1)}) |")
    return "\n".join(lines), groups


def figures(groups, out_dir, prefix):
    """One convergence chart per scene and start tag, both objectives side by side."""
    os.makedirs(out_dir, exist_ok=True)
    by_scene = {}
    for (scene, tag, obj), rs in groups.items():
        by_scene.setdefault((scene, tag), {})[obj] = [
            (r["seed"], r["default_cost"], r["samples"]) for r in rs]
    written = []
    for (scene, tag), g in sorted(by_scene.items()):
        out = os.path.join(out_dir, f"{prefix}{scene}" + ("" if tag == "native" else f"_{tag}")
                           + ".png")
        n = max(len(v[0][2]) for v in g.values())
        plot_scene(g, out, f"{scene} ({n} iterations)")
        written.append(out)
    return written


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--scene", action="append", default=[])
    ap.add_argument("--objective", action="append", default=[],
                    help="render and/or build+render (default both)")
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--iterations", type=int, default=40)
    ap.add_argument("--verify", type=int, default=7)
    ap.add_argument("--tune-spp", type=int, default=1)
    ap.add_argument("--res", default="128x128")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--tuner", default="tuner_nm")
    ap.add_argument("--set", action="append", default=[], help="extra --set for the host "
                    "(e.g. accel_embree.backend=custom)")
    ap.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                    help="what the host's build and render times measure (cpu: the process's "
                    "CPU time, for a shared machine; with --threads 1)")
    ap.add_argument("--tune-params", help="the host's --tune-params (default: every parameter "
                    "of the target's space)")
    ap.add_argument("--tag", default="native", help="label of the starting configuration")
    ap.add_argument("--out-dir", default="gains")
    ap.add_argument("--force", action="store_true", help="rerun runs whose stats exist")
    ap.add_argument("--summarize", metavar="DIR", help="only print the tables of DIR")
    ap.add_argument("--figures", metavar="DIR", help="write a convergence chart per scene")
    ap.add_argument("--figure-prefix", default="convergence_", help="file name prefix of the "
                    "charts (default convergence_)")
    a = ap.parse_args()
    if a.summarize:
        table, groups = summarize(sorted(glob.glob(os.path.join(a.summarize, "*.json"))))
        print(table)
        if a.figures:
            for p in figures(groups, a.figures, a.figure_prefix):
                print(p)
        return
    if not a.scene:
        ap.error("give at least one --scene")
    a.host = host.find(a.host)
    os.makedirs(a.out_dir, exist_ok=True)
    extra = [x for s in a.set for x in ("--set", s)]
    paths = []
    for scene in a.scene:
        for obj in a.objective or ["render", "build+render"]:
            for seed in range(1, a.seeds + 1):
                p = run_one(a, scene, obj, seed, extra, a.tag)
                if p:
                    paths.append(p)
    table, groups = summarize(paths)
    print(table)
    if a.figures:
        for p in figures(groups, a.figures, a.figure_prefix):
            print(p)


if __name__ == "__main__":
    main()
