"""Spatial splits vs. a rotating thin cylinder (thesis 3.2.3, Fig. 3.13).

The scene is wrapped in a scene.json that imports it, keeps its still camera (the camera path
is removed) and adds the thesis' rotating thin cylinder with the scene option
"stress": {"cylinder": ...} (scenes/README.md, "Stress options"): an open cylinder of long thin
triangles, half the scene's bounding-box diagonal long, centred on the bounds, along +x turned
about --axis by theta. The K angles theta in 0..180 degrees are the K frames of ONE sequence
(host --sequence K --fps 1: frame f at time f, theta = 180 f / K, or 180 f / (K - 1) with
--include-180), rendered in one host process per configuration: at every frame the scene is
posed and the acceleration structure rebuilt at the configuration's build parameters (the
manifest's update_ms, a full build of the scene with the cylinder at theta) and the frame
rendered at 1 spp (render_ms). Configurations: binned SAH (accel_embree.quality=2, no spatial
splits) and SAH plus spatial splits (quality=3), for each requested backend (native Embree is
the plugin's default; --backends native,custom adds our own BVH builder). Runs are interleaved
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

from tools.scenes import scenelib as sl
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


def stress_scene(scene, out, angles, include_180, axis, radius):
    """The stress scene.json: `scene` (a copy of a scene.json, or a pbrt file imported), its camera path removed, the cylinder turning
    over the frames of a --fps 1 sequence. Returns the angle (degrees) of every frame."""
    span = angles - 1 if include_180 else angles
    cyl = {"axis": axis, "from": 0, "to": 180, "time": [0, max(span, 1)]}
    if radius:
        cyl["radius"] = radius
    if scene.endswith(".json"):
        # a copy (an imported scene.json may not import again, and wrappers do)
        wrapper = sl.load_scene(scene)
        src_dir, dst_dir = os.path.dirname(os.path.abspath(scene)), os.path.dirname(os.path.abspath(out))
        sl.rebase_files(wrapper, src_dir, dst_dir)
        if "import" in wrapper and not os.path.isabs(wrapper["import"]):
            wrapper["import"] = os.path.normpath(os.path.join(src_dir, wrapper["import"]))
    else:
        wrapper = {"version": 1, "import": os.path.abspath(scene)}
    wrapper.setdefault("camera", {})["path"] = []  # the still camera
    wrapper["stress"] = {"cylinder": cyl}
    wrapper["_comment"] = ("tools/tuning/cylinder_sweep.py: %s + the rotating thin cylinder of "
                           "thesis 3.2.3, frame f (at time f) at theta = 180 f / %d"
                           % (os.path.basename(scene), max(span, 1)))
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        json.dump(wrapper, f, indent=1)
    os.replace(tmp, out)
    return [180.0 * f / max(span, 1) for f in range(angles)]


def read_frames(manifest_path, angles):
    """(update_ms, render_ms) of every frame of a sequence's manifest.json."""
    with open(manifest_path) as f:
        m = json.load(f)
    frames = m.get("frames", [])
    if len(frames) != angles or any("update_ms" not in fr for fr in frames):
        raise SystemExit("cylinder_sweep: %s: expected %d frames with update_ms and render_ms, "
                         "got %d (is the scene animated?)" % (manifest_path, angles, len(frames)))
    return [(float(fr["update_ms"]), float(fr["render_ms"])) for fr in frames]


def run(a):
    os.makedirs(a.work, exist_ok=True)
    scene = os.path.join(a.work, "cylinder.json")
    thetas = stress_scene(a.scene, scene, a.angles, a.include_180, a.axis, a.radius)
    rows = []
    csv_path = os.path.join(a.work, "runs.csv")
    seq_dir = os.path.join(a.work, "seq")
    with open(csv_path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["backend", "quality", "theta", "rep", "build_ms", "render_ms"])
        for rep in range(a.reps):
            for be in a.backends:
                for q in (2, 3):
                    # one process renders every angle: the sequence rebuilds per frame
                    host.run(a.host, ["--quiet", "--no-db", "--spp", "1", "--res", a.res,
                                      "--threads", str(a.threads), "--sequence", str(a.angles),
                                      "--fps", "1", "--out-dir", seq_dir,
                                      "--set", "accel_embree.updateMethod=rebuild",
                                      "--set", "accel_embree.quality=%d" % q,
                                      "--set", "accel_embree.backend=%s" % be, scene],
                             capture=True)
                    frames = read_frames(os.path.join(seq_dir, "manifest.json"), a.angles)
                    for th, (build_ms, render_ms) in zip(thetas, frames):
                        row = [be, q, th, rep, build_ms, render_ms]
                        w.writerow(row)
                        rows.append(row)
            f.flush()
            print("rep %d/%d done" % (rep + 1, a.reps), file=sys.stderr)
    with open(os.path.join(a.work, "meta.json"), "w") as f:
        json.dump({"scene": a.scene, "res": a.res, "threads": a.threads, "reps": a.reps,
                   "angles": thetas, "backends": a.backends, "host": a.host,
                   "method": "one sequence per configuration (stress.cylinder)"}, f, indent=1)
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
    fig_.suptitle("%s:\n%s, 1 spp, %d thread(s), n=%d, mean and %.4g%% t-band; the angles are "
                  "the frames of one host --sequence per configuration" %
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
    p.add_argument("--radius", type=float, default=None,
                   help="cylinder radius as a fraction of its length (default 0.002)")
    p.add_argument("--axis", type=float, nargs=3, default=[0.0, 0.0, 1.0],
                   help="rotation axis (default 0 0 1)")
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
