"""Spatial splits vs. a rotating thin cylinder (issue 6, thesis Fig. 3.13).

A long thin cylinder (tools/scenes/generate.py cylinder) is inserted into a scene at K angles
theta in 0..180 degrees. For every angle the host builds and renders (1 spp, one thread) the
scene R times with binned SAH (accel_embree.quality=2, no spatial splits) and with SAH plus
spatial splits (quality=3), for each requested backend (native Embree is the plugin's
default; --backends native,custom adds our own BVH builder). Runs are interleaved
(repetition-major) so slow drift of the machine hits all configurations alike. The plot shows
the mean and a two-sided t-distribution confidence band (default 99.99 %) of build ms and
render ms vs. theta, split vs. no split, one column per backend.

  /usr/bin/python3 -m tools.tuning.cylinder_sweep --scene scenes/cornell-box/scene.json \\
      --angles 12 --reps 5 --res 128x128 --backends native,custom --work /tmp/cyl_cornell \\
      --fig tools/tuning/figures/cylinder_cornell-box.png
  /usr/bin/python3 -m tools.tuning.cylinder_sweep --summarize /tmp/cyl_cornell --fig ...  # re-plot
"""
import csv
import json
import math
import os
import statistics
import sys

from tools.scenes import generate
from tools.tttools import cli, host

ROOT = host.ROOT
QUAL = {2: "no split (quality=2)", 3: "spatial splits (quality=3)"}


def t_quantile(p, df):
    try:
        from scipy.stats import t
        return float(t.ppf(p, df))
    except ImportError:  # Cornish-Fisher expansion of the t quantile from the normal one
        from statistics import NormalDist
        z = NormalDist().inv_cdf(p)
        g1 = (z ** 3 + z) / 4
        g2 = (5 * z ** 5 + 16 * z ** 3 + 3 * z) / 96
        g3 = (3 * z ** 7 + 19 * z ** 5 + 17 * z ** 3 - 15 * z) / 384
        g4 = (79 * z ** 9 + 776 * z ** 7 + 1482 * z ** 5 - 1920 * z ** 3 - 945 * z) / 92160
        return z + g1 / df + g2 / df ** 2 + g3 / df ** 3 + g4 / df ** 4


def run(a):
    os.makedirs(a.work, exist_ok=True)
    thetas = [180.0 * i / a.angles for i in range(a.angles)] if not a.include_180 else \
        [180.0 * i / (a.angles - 1) for i in range(a.angles)]
    scenes = {}
    for th in thetas:
        out = os.path.join(a.work, "theta_%06.2f.json" % th)
        if not os.path.exists(out):
            generate.main(["cylinder", a.scene, out, "--theta", repr(th)] +
                          (["--radius", str(a.radius)] if a.radius else []))
        scenes[th] = out
    rows = []
    csv_path = os.path.join(a.work, "runs.csv")
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["backend", "quality", "theta", "rep", "build_ms", "render_ms"])
        for rep in range(a.reps):
            for th in thetas:
                for be in a.backends:
                    for q in (2, 3):
                        s = host.run(a.host, ["--quiet", "--no-db", "--spp", "1", "--res", a.res,
                                              "--threads", str(a.threads),
                                              "--out", os.path.join(a.work, "img.exr"),
                                              "--set", "accel_embree.quality=%d" % q,
                                              "--set", "accel_embree.backend=%s" % be, scenes[th]],
                                     stats=True, capture=True).stats
                        row = [be, q, th, rep, s["build_ms"], s["render_ms"]]
                        w.writerow(row)
                        rows.append(row)
            f.flush()
            print("rep %d/%d done" % (rep + 1, a.reps), file=sys.stderr)
    with open(os.path.join(a.work, "meta.json"), "w") as f:
        json.dump({"scene": a.scene, "res": a.res, "threads": a.threads, "reps": a.reps,
                   "angles": thetas, "backends": a.backends, "host": a.host}, f, indent=1)
    return a.work


def load(work):
    out = {}
    with open(os.path.join(work, "runs.csv")) as f:
        for r in csv.DictReader(f):
            k = (r["backend"], int(r["quality"]), float(r["theta"]))
            out.setdefault(k, {"build_ms": [], "render_ms": []})
            out[k]["build_ms"].append(float(r["build_ms"]))
            out[k]["render_ms"].append(float(r["render_ms"]))
    with open(os.path.join(work, "meta.json")) as f:
        meta = json.load(f)
    return out, meta


def band(xs, conf):
    n = len(xs)
    m = statistics.fmean(xs)
    if n < 2:
        return m, 0.0
    h = t_quantile(1 - (1 - conf) / 2, n - 1) * statistics.stdev(xs) / math.sqrt(n)
    return m, h


def summarize(work, fig, conf, title):
    data, meta = load(work)
    backends = meta["backends"]
    thetas = sorted({k[2] for k in data})
    print("scene %s, %s, %d reps, %.4g%% t-band (half-width)" %
          (meta["scene"], meta["res"], meta["reps"], 100 * conf))
    for be in backends:
        print("\nbackend=%s" % be)
        print("%7s | %22s %22s | %22s %22s | %s" % ("theta", "build q2", "build q3", "render q2",
                                                    "render q3", "q3/q2 build, render, total"))
        tot = {2: [0, 0], 3: [0, 0]}
        for th in thetas:
            cells, means = [], {}
            for metric in ("build_ms", "render_ms"):
                for q in (2, 3):
                    m, h = band(data[(be, q, th)][metric], conf)
                    means[(metric, q)] = m
                    cells.append("%9.3f +- %9.3f" % (m, h))
            for q in (2, 3):
                tot[q][0] += means[("build_ms", q)]
                tot[q][1] += means[("render_ms", q)]
            rb = means[("build_ms", 3)] / means[("build_ms", 2)]
            rr = means[("render_ms", 3)] / means[("render_ms", 2)]
            rt = (means[("build_ms", 3)] + means[("render_ms", 3)]) / \
                (means[("build_ms", 2)] + means[("render_ms", 2)])
            print("%7.1f | %s %s | %s %s | %.3f %.3f %.3f" % (th, *cells, rb, rr, rt))
        print("%7s | mean build q2 %.3f q3 %.3f ms, mean render q2 %.3f q3 %.3f ms" %
              ("all", tot[2][0] / len(thetas), tot[3][0] / len(thetas),
               tot[2][1] / len(thetas), tot[3][1] / len(thetas)))
    if not fig:
        return
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig_, axes = plt.subplots(2, len(backends), figsize=(4.2 * len(backends), 5.6),
                              squeeze=False, sharex=True)
    colors = {2: "tab:blue", 3: "tab:red"}
    for j, be in enumerate(backends):
        for i, metric in enumerate(("build_ms", "render_ms")):
            ax = axes[i][j]
            for q in (2, 3):
                ms, hs = zip(*[band(data[(be, q, th)][metric], conf) for th in thetas])
                ax.plot(thetas, ms, "o-", ms=3, color=colors[q], label=QUAL[q])
                ax.fill_between(thetas, [m - h for m, h in zip(ms, hs)],
                                [m + h for m, h in zip(ms, hs)], color=colors[q], alpha=0.2, lw=0)
            ax.set_ylim(bottom=0)  # the band of a noisy point can reach below 0 ms: clip the view
            ax.set_ylabel(metric.replace("_ms", " [ms]"))
            ax.grid(alpha=0.3)
            if i == 0:
                ax.set_title("backend=%s" % be, fontsize=10)
            else:
                ax.set_xlabel("cylinder angle theta [deg]")
            ax.set_xticks(range(0, 181, 45))
    axes[0][0].legend(fontsize=7)
    fig_.suptitle("%s:\n%s, 1 spp, %d thread(s), n=%d, mean and %.4g%% t-band" %
                  (title or os.path.basename(os.path.dirname(meta["scene"])), meta["res"],
                   meta["threads"], meta["reps"], 100 * conf), fontsize=9)
    fig_.tight_layout()
    fig_.savefig(fig, dpi=80)
    print("\nfigure -> %s" % fig)


def main():
    p = cli.parser(__doc__)
    p.add_argument("--scene", default=os.path.join(ROOT, "scenes/cornell-box/scene.json"))
    p.add_argument("--angles", type=int, default=12, help="K angles over 0..180 (180 excluded)")
    p.add_argument("--include-180", action="store_true", help="space K angles over 0..180 inclusive")
    p.add_argument("--reps", type=int, default=5)
    p.add_argument("--res", default="128x128")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--radius", type=float, default=None, help="cylinder radius (generator default if unset)")
    p.add_argument("--backends", default="native", help="comma list: native,custom")
    p.add_argument("--conf", type=float, default=0.9999)
    p.add_argument("--work", default="/tmp/cylinder_sweep")
    p.add_argument("--fig", default=None)
    p.add_argument("--title", default=None)
    p.add_argument("--summarize", metavar="WORK", help="only tabulate/plot an earlier run")
    a = p.parse_args()
    if a.summarize:
        summarize(a.summarize, a.fig, a.conf, a.title)
        return
    a.host = host.find(a.host)
    a.backends = a.backends.split(",")
    a.scene = os.path.abspath(a.scene)
    summarize(run(a), a.fig, a.conf, a.title)


if __name__ == "__main__":
    main()
