"""Parameter analysis of tuning-database rows (thesis 3.2, Figs. 3.3, 3.5-3.8, 3.10-3.12:
3.6 and 3.7 from explored rows, 3.8 and 3.10-3.12 from tuning runs).

Input, for every subcommand: a tuning database (--db, the SQLite file host writes) or a CSV
with the columns of tt_tunedb_export_csv (--csv; a CSV without a `config` column is read as
one column per parameter plus build_ms/render_ms). Rows can be filtered by plugin, mode,
scene, run and parameter values; only status-ok rows are used. convergence also reads host
--stats files (then one line per file).

  A="/usr/bin/python3 -m tools.tuning.analyze"   # from the repository root
  $A correlation --db t.db --mode explore -o corr.png --table corr.csv           # Fig. 3.5
  $A leafsize    --db t.db --where quality=1 -o leaf.png                         # Fig. 3.6
  $A leafsize    --db t.db --mode tune -o leaf_tuned.png                         # Fig. 3.10
  $A costs       --db t.db --mode tune --metric total -o costs.png               # Figs. 3.11/3.12
  $A blocksize   --db t.db --mode explore -o block.png                           # Fig. 3.7
  $A blocksize   --db t.db --mode tune -o block_tuned.png                        # Fig. 3.8
  $A convergence render.json total.json -o conv.png                              # Fig. 3.3
  $A convergence --db t.db --scene cornell -o conv.png                           # every run

Gathering the data: `host --explore N --objective build+render --set accel_embree.backend=custom
--db t.db scene.json` draws N random configurations (correlation, leaf size, block size
maps; the builder's parameters act only with backend custom, and with native they are left
at their configured values, host --describe accel_embree "activeWhen"); tuning runs
(`host --plugin tuner_nm ...`) give the converging distributions of Figs. 3.10-3.12.
Needs python3-numpy, python3-scipy and python3-matplotlib (Debian packages).
"""
import argparse
import csv
import json
import math
import os
import sys

from tools.tttools import db, figures

TIMES = ("render_ms", "build_ms", "total_ms")
METRICS = {"render": "render_ms", "build": "build_ms", "total": "total_ms", "cost": "cost"}


def die(msg):
    sys.exit(f"analyze: {msg}")


# ---------------------------------------------------------------- loading


def _parse_where(items):
    """--where name=value filters: value compared as text against the config's value."""
    out = []
    for w in items or []:
        if "=" not in w:
            die(f"--where {w}: expected NAME=VALUE")
        k, v = w.split("=", 1)
        out.append((k.strip(), v.strip()))
    return out


def _as_text(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float) and v.is_integer():
        return str(int(v))
    return str(v)


def load_rows(a):
    """Rows as dicts: scene, plugin, mode, run_id, objective, iteration, build_ms, render_ms,
    total_ms, cost, config (dict, key order of the space)."""
    rows = []
    if a.db:
        if not os.path.exists(a.db):
            die(f"{a.db}: no such database")
        for r in db.samples(a.db):
            if not db.ok(r):
                continue
            rows.append(dict(scene=r["scene"] or "", plugin=r["plugin"], mode=r["mode"],
                             run_id=r["run_id"], objective=r["objective"],
                             iteration=r["iteration"], build_ms=r["build_ms"],
                             render_ms=r["render_ms"], cost=r["cost"], config=r["config"],
                             tuner=r["tuner"]))
    else:
        with open(a.csv, newline="") as f:
            rd = csv.DictReader(f)
            if not rd.fieldnames:
                die(f"{a.csv}: empty CSV")
            has_config = "config" in rd.fieldnames
            fixed = {"build_ms", "render_ms", "total_ms", "cost", "status", "scene", "plugin",
                     "mode", "run_id", "objective", "iteration", "tuner"}
            for rec in rd:
                if rec.get("status", "0") not in ("0", ""):
                    continue
                if has_config:
                    config = json.loads(rec["config"])
                else:
                    config = {}
                    for k in rd.fieldnames:
                        if k in fixed or k.startswith("ind_"):
                            continue
                        v = rec[k]
                        try:
                            config[k] = float(v)
                        except ValueError:
                            config[k] = {"true": True, "false": False}.get(v.lower(), v)
                b = float(rec.get("build_ms") or 0)
                r = float(rec.get("render_ms") or 0)
                rows.append(dict(scene=rec.get("scene", ""), plugin=rec.get("plugin", ""),
                                 mode=rec.get("mode", ""), run_id=rec.get("run_id", ""),
                                 objective=rec.get("objective", ""),
                                 tuner=rec.get("tuner") or None,
                                 iteration=int(float(rec.get("iteration") or 0)),
                                 build_ms=b, render_ms=r,
                                 cost=float(rec.get("cost") or (b + r)), config=config))
    where = _parse_where(a.where)
    out = []
    for row in rows:
        if a.plugin and row["plugin"] != a.plugin:
            continue
        if a.mode and row["mode"] not in a.mode.split(","):
            continue
        if a.scene and a.scene not in row["scene"]:
            continue
        if a.run and row["run_id"] != a.run:
            continue
        if a.objective and row["objective"] != a.objective:
            continue
        if any(_as_text(row["config"].get(k)) != v for k, v in where):
            continue
        row["total_ms"] = row["build_ms"] + row["render_ms"]
        out.append(row)
    if not out:
        die("no rows match (check --db/--csv and the filters)")
    return out


def scene_label(path):
    """Short name of a scene file: its folder for scene.json, else the file stem."""
    base = os.path.basename(path or "")
    stem = os.path.splitext(base)[0]
    parent = os.path.basename(os.path.dirname(path or ""))
    return parent if stem in ("scene", "") and parent else (stem or "scene")


def by_scene(rows):
    groups = {}
    for r in rows:
        groups.setdefault(r["scene"], []).append(r)
    return groups


def encode(values):
    """Numeric codes of one parameter's values: numbers as they are, bools 0/1, other
    nominal values by order of first appearance. Returns (floats, labels or None)."""
    if all(isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return [float(v) for v in values], None
    labels = []
    for v in values:
        if v not in labels:
            labels.append(v)
    return [float(labels.index(v)) for v in values], labels


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _plain_log(axis):
    """Labels a log axis in plain numbers (0.6, 1, 2, 5, 10 rather than 6x10^-1): every
    decade, and the 2s and 5s between them."""
    from matplotlib.ticker import FuncFormatter

    def major(v, _):
        return f"{v:g}"

    def minor(v, _):
        lead = v / 10 ** math.floor(math.log10(v) + 1e-9) if v > 0 else 0
        return f"{v:g}" if round(lead) in (2, 5) and abs(lead - round(lead)) < 1e-6 else ""
    axis.set_major_formatter(FuncFormatter(major))
    axis.set_minor_formatter(FuncFormatter(minor))


def _save(fig, path, dpi=100):
    figures.save(fig, path, dpi=dpi)
    print(f"wrote {path}")
    return fig


# ---------------------------------------------------------------- correlation (Fig. 3.5)


def correlation(rows, method, alpha):
    """Correlation matrix of every parameter and the times. Returns (names, r, p) with
    NaN for constant variables."""
    import numpy as np
    from scipy import stats

    params = list(rows[0]["config"].keys())
    cols = []
    for k in params:
        cols.append(encode([r["config"].get(k) for r in rows])[0])
    for t in TIMES:
        cols.append([r[t] for r in rows])
    names = params + list(TIMES)
    x = np.array(cols, dtype=float)
    n = len(names)
    rr = np.full((n, n), np.nan)
    pp = np.full((n, n), np.nan)
    fn = stats.spearmanr if method == "spearman" else stats.pearsonr
    for i in range(n):
        for j in range(n):
            if np.ptp(x[i]) == 0 or np.ptp(x[j]) == 0 or len(rows) < 3:
                continue
            if i == j:
                rr[i, j], pp[i, j] = 1.0, 0.0
                continue
            res = fn(x[i], x[j])
            rr[i, j], pp[i, j] = float(res[0]), float(res[1])
    return names, rr, pp


def cmd_correlation(a):
    import numpy as np

    rows = load_rows(a)
    names, r, p = correlation(rows, a.method, a.alpha)
    n = len(names)
    if a.table:
        with open(a.table, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["variable"] + names + [f"p_{x}" for x in names])
            for i in range(n):
                w.writerow([names[i]] + [f"{v:.6g}" for v in r[i]] + [f"{v:.6g}" for v in p[i]])
    # text: each parameter against the three times
    print(f"{a.method} correlation over {len(rows)} rows "
          f"({len(by_scene(rows))} scene(s)); * = p < {a.alpha}")
    print(f"{'parameter':>16} " + " ".join(f"{t:>16}" for t in TIMES))
    for i in range(n - len(TIMES)):
        cells = []
        for t in TIMES:
            j = names.index(t)
            v, pv = r[i, j], p[i, j]
            cells.append(f"{'-':>16}" if math.isnan(v) else
                         f"{v:+.3f} (p={pv:.1e}){'*' if pv < a.alpha else ' '}".rjust(16))
        print(f"{names[i]:>16} " + " ".join(cells))
    if a.out:
        plt = _plt()
        shown = np.where(p < a.alpha, r, np.nan)  # blank: not significant (thesis Fig. 3.5)
        fig, ax = plt.subplots(figsize=(0.55 * n + 2.5, 0.5 * n + 1.5))
        im = ax.imshow(shown, cmap="RdBu_r", vmin=-1, vmax=1)
        ax.set_xticks(range(n), names, rotation=60, ha="right", fontsize=8)
        ax.set_yticks(range(n), names, fontsize=8)
        for i in range(n):
            for j in range(n):
                if not math.isnan(shown[i, j]):
                    ax.text(j, i, f"{100 * shown[i, j]:.0f}", ha="center", va="center",
                            fontsize=6, color="white" if abs(shown[i, j]) > 0.6 else "black")
        fig.colorbar(im, ax=ax, shrink=0.8, label=f"{a.method} r")
        ax.set_title(f"{a.method.capitalize()} correlation (blank: p ≥ {a.alpha}), "
                     f"{len(rows)} configurations", fontsize=9)
        return _save(fig, a.out, dpi=110)


# ---------------------------------------------------------------- leaf size (Figs. 3.6/3.10)


def grid_means(rows, xk, yk, metric, bins, lo, hi):
    """Mean of `metric` per (x bin, y bin) cell; NaN where a cell has no data."""
    import numpy as np
    edges = np.linspace(lo, hi + 1e-9, bins + 1)
    s = np.zeros((bins, bins))
    c = np.zeros((bins, bins))
    for r in rows:
        x, y = r["config"].get(xk), r["config"].get(yk)
        if x is None or y is None:
            continue
        i = min(max(np.searchsorted(edges, float(x), side="right") - 1, 0), bins - 1)
        j = min(max(np.searchsorted(edges, float(y), side="right") - 1, 0), bins - 1)
        s[j, i] += r[metric]
        c[j, i] += 1
    with np.errstate(invalid="ignore"):
        return s / np.where(c > 0, c, np.nan), edges


def cmd_leafsize(a):
    rows = load_rows(a)
    for k in ("minLeafSize", "maxLeafSize"):
        if k not in rows[0]["config"]:
            die(f"the rows have no {k} parameter (is this accel_embree?)")
    groups = by_scene(rows)
    plt = _plt()
    fig, axes = plt.subplots(len(groups), 3, figsize=(12, 3.6 * len(groups)), squeeze=False)
    print(f"leaf size map: {len(rows)} rows, {a.bins}x{a.bins} cells")
    for gi, (scene, rs) in enumerate(groups.items()):
        for mi, metric in enumerate(TIMES):
            g, edges = grid_means(rs, "minLeafSize", "maxLeafSize", metric, a.bins, 1, 32)
            ax = axes[gi][mi]
            import numpy as np
            finite = g[np.isfinite(g)]
            # colour range clipped at the 90th percentile: a few very slow cells (compact,
            # counters) would otherwise flatten the rest of the map
            vmax = float(np.percentile(finite, 90)) if finite.size else None
            im = ax.imshow(g, origin="lower", extent=(edges[0], edges[-1], edges[0], edges[-1]),
                           cmap="viridis_r", aspect="auto", vmax=vmax)
            fig.colorbar(im, ax=ax, label=f"mean {metric}")
            best = min(rs, key=lambda r: r[metric])
            ax.plot(best["config"]["minLeafSize"], best["config"]["maxLeafSize"], "r*", ms=10,
                    label=f"lowest {metric}: {best[metric]:.4g}")
            ax.legend(fontsize=7, loc="upper left")
            ax.set_xlabel("minLeafSize")
            ax.set_ylabel("maxLeafSize")
            ax.set_title(f"{scene_label(scene)}: {metric} ({len(rs)} rows)", fontsize=9)
            print(f"  {scene_label(scene)} {metric}: best {best[metric]:.4g} at "
                  f"min {best['config']['minLeafSize']}, max {best['config']['maxLeafSize']}")
    return _save(fig, a.out)


# ---------------------------------------------------------------- SAH costs (Figs. 3.11/3.12)


def cmd_costs(a):
    import numpy as np
    rows = load_rows(a)
    for k in ("travcost", "intcost"):
        if k not in rows[0]["config"]:
            die(f"the rows have no {k} parameter (is this accel_embree?)")
    metric = METRICS[a.metric]
    groups = by_scene(rows)
    plt = _plt()
    fig, axes = plt.subplots(1, len(groups), figsize=(4.6 * len(groups), 4), squeeze=False)
    print(f"intcost/travcost ({metric}): {len(rows)} rows")
    for gi, (scene, rs) in enumerate(groups.items()):
        ax = axes[0][gi]
        x = np.array([r["config"]["intcost"] for r in rs], float)
        y = np.array([r["config"]["travcost"] for r in rs], float)
        v = np.array([r[metric] for r in rs], float)
        # background: mean cost per cell (the heat map), points: every configuration
        if len(rs) >= 20:
            hb = ax.hexbin(x, y, C=v, gridsize=a.bins, reduce_C_function=np.mean,
                           cmap="viridis_r", alpha=0.5, xscale="log", yscale="log")
        sc = ax.scatter(x, y, c=v, s=14, cmap="viridis_r", edgecolors="k", linewidths=0.2)
        ax.set_xscale("log")
        ax.set_yscale("log")
        _plain_log(ax.xaxis)
        _plain_log(ax.yaxis)
        fig.colorbar(sc, ax=ax, label=metric)
        k = max(1, len(rs) // 10)  # the best tenth, circled: where the optima cluster
        top = sorted(rs, key=lambda r: r[metric])[:k]
        ax.plot([r["config"]["intcost"] for r in top], [r["config"]["travcost"] for r in top],
                "o", mfc="none", mec="red", ms=8, ls="none",
                label=f"lowest {metric}: best {k} of {len(rs)}")
        ax.legend(fontsize=7)
        ax.set_xlabel("intcost")
        ax.set_ylabel("travcost")
        ax.set_title(f"{scene_label(scene)} ({len(rs)} rows)", fontsize=9)
        best = min(rs, key=lambda r: r[metric])
        print(f"  {scene_label(scene)}: best {best[metric]:.4g} at intcost "
              f"{best['config']['intcost']:.3g}, travcost {best['config']['travcost']:.3g}")
    return _save(fig, a.out)


# ------------------------------------------------ sahBlockSize (Figs. 3.7 explored, 3.8 tuned)


def cmd_blocksize(a):
    import numpy as np
    from matplotlib.ticker import NullLocator
    rows = load_rows(a)
    if "sahBlockSize" not in rows[0]["config"]:
        die("the rows have no sahBlockSize parameter (is this accel_embree?)")
    groups = by_scene(rows)
    plt = _plt()
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    print(f"sahBlockSize: {len(rows)} rows (median and quartiles per value)")
    markers = "osD^v<>"
    sampled = set()
    for si, (scene, rs) in enumerate(groups.items()):
        vals = sorted({int(r["config"]["sahBlockSize"]) for r in rs})
        sampled.update(vals)
        for ax, metric in zip(axes, ("build_ms", "render_ms")):
            med, q1, q3 = [], [], []
            for b in vals:
                v = [r[metric] for r in rs if int(r["config"]["sahBlockSize"]) == b]
                med.append(np.median(v))
                q1.append(np.percentile(v, 25))
                q3.append(np.percentile(v, 75))
            # only the values the space has (powers of two): points with their quartiles,
            # nothing drawn between them
            ax.errorbar(vals, med, yerr=[np.subtract(med, q1), np.subtract(q3, med)],
                        fmt=markers[si % len(markers)], ls="none", capsize=3,
                        label=f"{scene_label(scene)} (n per value: "
                        f"{', '.join(str(sum(int(r['config']['sahBlockSize']) == b for r in rs)) for b in vals)})")
            ax.set_ylabel(f"{metric} (median, IQR)")
            best = vals[int(np.argmin(med))]
            print(f"  {scene_label(scene)} {metric}: lowest median at sahBlockSize {best} "
                  f"({min(med):.4g}); {len(vals)} values")
    axes[0].set_title("sahBlockSize: build time (top) and render time (bottom)")
    axes[1].set_xscale("log", base=2)
    axes[1].set_xticks(sorted(sampled), [str(b) for b in sorted(sampled)])
    axes[1].xaxis.set_minor_locator(NullLocator())
    axes[1].set_xlabel("sahBlockSize (the values sampled)")
    axes[0].legend(fontsize=8)
    return _save(fig, a.out)


# ---------------------------------------------------------------- convergence (Fig. 3.3)


def _runs_from_stats(paths):
    """(name, objective, tuner, history, verify, default_cost) per host --stats file; the
    tuning default is known for the run's objective only (default_cost)."""
    runs = []
    for path in paths:
        try:
            with open(path) as f:
                t = json.load(f).get("tuning")
        except (OSError, ValueError) as e:
            die(f"{path}: {e}")
        if not t:
            die(f"{path}: no \"tuning\" object (was a tuner loaded?)")
        hist = [h for h in t.get("history", []) if h.get("status") in (None, "ok", 0)]
        if not hist:
            die(f"{path}: no history")
        runs.append(dict(name=os.path.basename(path), objective=t.get("objective", "?"),
                         tuner=t.get("tuner") or t.get("mode", "tune"), history=hist,
                         verify=t.get("verify"), default_cost=t.get("default_cost")))
    return runs


def _runs_from_rows(rows):
    """The same per run_id of database/CSV rows (the default row is iteration -1)."""
    by = {}
    for r in rows:
        by.setdefault(r["run_id"] or "", []).append(r)
    runs = []
    for run_id, rs in by.items():
        rs.sort(key=lambda r: r["iteration"])
        if not any(r["mode"] in ("tune", "explore") for r in rs):
            continue
        tuner = next((r.get("tuner") for r in rs if r.get("tuner")), None)
        mode = next(r["mode"] for r in rs if r["mode"] in ("tune", "explore"))
        default = next((r for r in rs if r["iteration"] < 0), None)
        runs.append(dict(name=f"run {run_id}", objective=rs[0]["objective"] or "?",
                         tuner=tuner or mode, history=[r for r in rs if r["iteration"] >= 0],
                         verify=None, default_cost=None, default=default))
    if not runs:
        die("no tuning runs among the matching rows (rows of mode tune or explore; check "
            "--mode/--run)")
    return runs


def _tuning_default(run, key):
    """The default configuration's cost as the tuning run measured it (what the search
    started from), for panel `key` (render / total); None where the run did not measure it:
    a --stats file gives its objective's cost only."""
    d = run.get("default")
    if d is not None:
        return d["render_ms"] if key == "render" else d["render_ms"] + d["build_ms"]
    obj = {"render": "render", "total": "build+render"}[key]
    return run["default_cost"] if run["objective"] == obj else None


def cmd_convergence(a):
    """Render time and total time per iteration of tuning runs (host --stats files, or the
    runs of a tuning database/CSV, one per run_id), one panel each: every measured pass, the
    best so far (tools.tuning.convergence's, as gains.py draws it) and the tuning default:
    default vs tuned-for-render vs tuned-for-total."""
    from tools.tuning.convergence import best_so_far
    if a.stats and (a.db or a.csv):
        die("convergence: give host --stats files or --db/--csv, not both")
    if a.stats:
        runs = _runs_from_stats(a.stats)
    elif a.db or a.csv:
        runs = _runs_from_rows(load_rows(a))
    else:
        die("convergence: give host --stats files or --db/--csv")
    # one label per run: what it was tuned for and with which tuner; runs that would share a
    # label are told apart by their file or run id
    labels = [f"{r['tuner']}, tuned for {r['objective']}" for r in runs]
    for k, r in enumerate(runs):
        if labels.count(labels[k]) > 1:
            labels[k] += f" ({r['name']})"
    plt = _plt()
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for k, r in enumerate(runs):
        color = colors[k % len(colors)]
        hist = r["history"]
        for ax, key in zip(axes, ("render", "total")):
            xs = [h["iteration"] for h in hist]
            ys = [h["render_ms"] if key == "render" else h["render_ms"] + h["build_ms"]
                  for h in hist]
            ax.plot(xs, ys, "-", marker=".", ms=3, color=color, lw=0.6, alpha=0.45,
                    label=f"{labels[k]}: each pass")
            level = _tuning_default(r, key)
            start = level if level is not None else math.inf
            ax.plot(xs, best_so_far([(y, False) for y in ys], start), "-", color=color, lw=1.8,
                    label=f"{labels[k]}: best so far")
            if level is not None:
                ax.axhline(level, color=color, ls="--", lw=1.2,
                           label=f"{labels[k]}: default (as tuning measured it)")
        v = r["verify"]
        if v:
            print(f"{r['name']}: {labels[k]}: verify render ratio {v.get('render_ratio'):.4f}, "
                  f"total ratio {v.get('total_ratio'):.4f} over {v.get('rounds')} rounds")
        else:
            print(f"{r['name']}: {labels[k]}: {len(hist)} samples")
    for ax, title in zip(axes, ("render time", "build + render time")):
        ax.set_title(title)
        ax.set_xlabel("iteration")
        ax.set_ylabel("ms")
        ax.legend(fontsize=7)
    fig.suptitle("Tuning convergence (thesis Fig. 3.3)")
    return _save(fig, a.out)


def run(argv=None):
    """Parses `argv` (default: the command line), draws, and returns the matplotlib figure
    (None for correlation without -o): what the tests inspect."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n".join(__doc__.splitlines()[1:]))
    sub = ap.add_subparsers(dest="cmd", required=True)

    def data_args(p, required=True):
        src = p.add_mutually_exclusive_group(required=required)
        src.add_argument("--db", help="tuning database (SQLite)")
        src.add_argument("--csv", help="CSV (tt_tunedb_export_csv columns, or one per parameter)")
        p.add_argument("--plugin", default="accel_embree", help="rows of this plugin "
                       "(default accel_embree; '' for all)")
        p.add_argument("--mode", help="default, tune, explore (comma-separated)")
        p.add_argument("--scene", help="rows whose scene path contains this text")
        p.add_argument("--run", help="rows of this run_id")
        p.add_argument("--objective", help="rows measured for this objective")
        p.add_argument("--where", action="append", help="NAME=VALUE on the configuration "
                       "(repeatable), e.g. --where quality=1 --where compact=false")
        p.add_argument("-o", "--out", help="PNG to write")

    p = sub.add_parser("correlation", help="correlation matrix with p-values (Fig. 3.5)")
    data_args(p)
    p.add_argument("--method", choices=("spearman", "pearson"), default="spearman")
    p.add_argument("--alpha", type=float, default=0.01, help="p-value below which a cell is shown")
    p.add_argument("--table", help="CSV of r and p for every pair")
    p.set_defaults(fn=cmd_correlation)

    p = sub.add_parser("leafsize", help="min/max leaf size heat maps (Figs. 3.6, 3.10)")
    data_args(p)
    p.add_argument("--bins", type=int, default=8, help="cells per axis over [1, 32]")
    p.set_defaults(fn=cmd_leafsize)

    p = sub.add_parser("costs", help="intcost/travcost map (Figs. 3.11, 3.12)")
    data_args(p)
    p.add_argument("--metric", choices=sorted(METRICS), default="render")
    p.add_argument("--bins", type=int, default=12, help="hexagons across (with >= 20 rows)")
    p.set_defaults(fn=cmd_costs)

    p = sub.add_parser("blocksize", help="sahBlockSize: median and quartiles per sampled value (Fig. 3.8)")
    data_args(p)
    p.set_defaults(fn=cmd_blocksize)

    p = sub.add_parser("convergence", help="render/total time per iteration (Fig. 3.3)",
                       description="Render and build+render time per iteration of tuning "
                       "runs: host --stats files, or every run (run_id) of a database or CSV "
                       "(--db/--csv with the filters; --mode defaults to default,tune).")
    data_args(p, required=False)
    p.add_argument("stats", nargs="*", help="host --stats files of tuning runs (e.g. one "
                   "tuned for render, one for build+render), instead of --db/--csv")
    p.set_defaults(fn=cmd_convergence)

    a = ap.parse_args(argv)
    if a.plugin == "":
        a.plugin = None
    if a.cmd == "convergence" and (a.db or a.csv) and not a.mode:
        a.mode = "default,tune"
    if a.cmd != "correlation" and not a.out:
        ap.error(f"{a.cmd} needs -o/--out PNG")
    try:
        import numpy  # noqa: F401
        import matplotlib  # noqa: F401
        if a.cmd == "correlation":
            import scipy  # noqa: F401
    except ImportError as e:
        die(f"{e.name} is missing: install python3-numpy, python3-scipy, python3-matplotlib")
    return a.fn(a)


def main():
    run()


if __name__ == "__main__":
    main()
