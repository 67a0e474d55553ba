"""Tuning convergence plot (thesis Fig. 3.3): cost per iteration against the default.

Reads the `tuning` object of host --stats files, or the rows of one tuning run from the
tuning database, and draws for each run the measured cost of every iteration (hollow
markers: answered from the database), the best cost so far, and the default
configuration's cost as a horizontal line.

  C="/usr/bin/python3 -m tools.tuning.convergence"   # from the repository root
  $C run_render.json run_total.json -o convergence.png
  $C --db ~/.local/share/tunetrace/tuning.db --last 2 -o convergence.png
  $C run.json --summary                      # text only, no matplotlib needed
"""
import argparse
import json
import math
import sys

from tools.tttools import db

INFEASIBLE = 1e299  # TT_COST_INFEASIBLE is 1e300: anything this large was not measured


def runs_from_stats(paths):
    """One run per stats file: (label, default_cost, [(cost, cached)], best_cost)."""
    runs = []
    for path in paths:
        with open(path) as f:
            t = json.load(f).get("tuning")
        if not t:
            sys.exit(f"convergence: {path}: no \"tuning\" object (was a tuner loaded?)")
        hist = t.get("history", [])
        samples = [(h["cost"], bool(h.get("cached"))) for h in hist]
        label = f'{t["plugin"]} / {t["objective"]}'
        runs.append((label, t["default_cost"], samples, t["best_cost"]))
    return runs


def runs_from_db(path, last, plugin):
    """The `last` runs (by run_id, newest last) in the database, optionally of one plugin."""
    everything = db.samples(path)
    newest = {}  # run_id -> its newest row's id, over the plugin's rows
    for r in everything:
        if not plugin or r["plugin"] == plugin:
            newest[r["run_id"]] = max(newest.get(r["run_id"], r["id"]), r["id"])
    ids = sorted(newest, key=newest.get)[-last:] if last > 0 else []
    runs = []
    for run_id in ids:
        rows = sorted((r for r in everything if r["run_id"] == run_id),
                      key=lambda r: (r["iteration"], r["id"]))
        default = [r["cost"] for r in rows if r["iteration"] < 0]
        samples = [(r["cost"], False) for r in rows if r["iteration"] >= 0]
        feasible = [c for c, _ in samples if c < INFEASIBLE] + default
        # the database holds measurements only: cached iterations of that run are absent
        label = f"{rows[0]['plugin']} / {rows[0]['objective']} ({run_id})"
        runs.append((label, default[0] if default else math.nan, samples,
                     min(feasible) if feasible else math.nan))
    return runs


def best_so_far(samples, default):
    """Running minimum of the feasible costs, starting from the default."""
    out, best = [], default if default < INFEASIBLE else math.inf
    for cost, _ in samples:
        if cost < best:
            best = cost
        out.append(best)
    return out


def converged_at(samples, default, tol=0.01):
    """Iteration after which the best cost so far improved by less than `tol` (relative) in
    total: the first i with (best_so_far[i] - final) < tol * best_so_far[i]; -1 when the
    default was already within tol of the final best."""
    running = best_so_far(samples, default)
    if not running:
        return -1
    final = running[-1]
    start = default if default < INFEASIBLE else math.inf
    if start - final < tol * start:
        return -1
    for i, b in enumerate(running):
        if b - final < tol * b:
            return i
    return len(running) - 1


def plot_scene(groups, out, title):
    """Fig. 3.3-style grid: one panel per objective, for every run (seed) the best cost so
    far against the iteration (solid) and that run's default cost (dashed, same colour).
    `groups` maps an objective to a list of (seed, default_cost, [(cost, cached)])."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    objs = sorted(groups)
    fig, axes = plt.subplots(1, len(objs), figsize=(6 * len(objs), 4.2), squeeze=False)
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for ax, obj in zip(axes[0], objs):
        for k, (seed, default, samples) in enumerate(sorted(groups[obj])):
            color = colors[k % len(colors)]
            xs = [i for i, (c, _) in enumerate(samples) if c < INFEASIBLE]
            ax.plot(xs, [samples[i][0] for i in xs], ".", ms=2, color=color, alpha=0.25)
            ax.plot(range(len(samples)), best_so_far(samples, default), "-", color=color,
                    label=f"seed {seed}")
            if default < INFEASIBLE:
                ax.axhline(default, color=color, ls="--", lw=0.9)
            c = converged_at(samples, default)
            if c >= 0:
                ax.plot([c], [best_so_far(samples, default)[c]], "v", color=color, ms=6)
        feas = [c for _, d, sm in groups[obj] for c, _ in sm if c < INFEASIBLE] + \
               [d for _, d, _ in groups[obj] if d < INFEASIBLE]
        if feas:
            lo = min(feas)
            hi = sorted(feas)[int(0.9 * (len(feas) - 1))]  # clip the worst 10 % of passes
            ax.set_ylim(0.95 * lo, max(hi, max(d for _, d, _ in groups[obj])) * 1.05)
        ax.set_xlabel("iteration")
        ax.set_ylabel(f"{obj} cost (ms)")
        ax.set_title(f"{title}: {obj}")
        ax.legend(fontsize=7, title="best so far; dashed: default; v: converged (1 %)",
                  title_fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def summary(runs):
    """One line per run: iterations, default, best, gain and when the best was reached."""
    lines = []
    for label, default, samples, best in runs:
        running = best_so_far(samples, default)
        reached = next((i for i, b in enumerate(running) if b <= best), None)
        gain = 100.0 * (1.0 - best / default) if default and default < INFEASIBLE else math.nan
        cached = sum(1 for _, c in samples if c)
        lines.append(f"{label}: iterations {len(samples)}, cached {cached}, default {default:.6g}, "
                     f"best {best:.6g}, gain {gain:.1f}%, best reached at iteration "
                     f"{reached if reached is not None else 'default'}")
    return "\n".join(lines)


def plot(runs, out):
    """Draws the Fig. 3.3-style chart into `out`."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.5))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, (label, default, samples, _) in enumerate(runs):
        color = colors[k % len(colors)]
        xs = [i for i, (c, _) in enumerate(samples) if c < INFEASIBLE]
        measured = [(i, samples[i][0]) for i in xs if not samples[i][1]]
        cached = [(i, samples[i][0]) for i in xs if samples[i][1]]
        if measured:
            ax.plot(*zip(*measured), "o", ms=3, color=color, alpha=0.6)
        if cached:
            ax.plot(*zip(*cached), "o", ms=4, mfc="none", color=color, alpha=0.6)
        ax.plot(range(len(samples)), best_so_far(samples, default), "-", color=color,
                label=f"{label}: best so far")
        if default < INFEASIBLE:
            ax.axhline(default, color=color, ls="--", lw=1, label=f"{label}: default")
    ax.set_xlabel("iteration")
    ax.set_ylabel("cost (ms for time objectives)")
    ax.set_title("Tuning convergence")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=120)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("stats", nargs="*", help="host --stats JSON files")
    ap.add_argument("--db", help="read runs from this tuning database instead")
    ap.add_argument("--last", type=int, default=1, help="with --db: the N most recent runs")
    ap.add_argument("--plugin", help="with --db: only runs tuning this plugin")
    ap.add_argument("-o", "--out", help="PNG to write")
    ap.add_argument("--summary", action="store_true", help="print one line per run")
    a = ap.parse_args()
    if bool(a.db) == bool(a.stats):
        ap.error("give stats files or --db, not both and not neither")
    runs = runs_from_db(a.db, a.last, a.plugin) if a.db else runs_from_stats(a.stats)
    if not runs:
        sys.exit("convergence: no tuning runs found")
    if a.summary or not a.out:
        print(summary(runs))
    if a.out:
        plot(runs, a.out)


if __name__ == "__main__":
    main()
