"""post_taa speed figures (issue #19 goal 3): runs plugins/post_taa/tests/taa_bench several times (each run
interleaves every variant frame by frame and prints its per-variant medians), then prints
the median of the per-run medians and their range per variant, with the load average
before and after each run. On this shared machine take the figures of a quiet moment:
the load average is printed beside them.

  /usr/bin/python3 -m tools.taa.speed [--host BUILD/host/host: its build's taa_bench]
      [--runs 4] [--threads 2] [--weights label=FILE.ttw[@LEVEL],...] [--rounds 9]
      [--default LABEL (c6)] [--goal LABEL=MS ...]
      [--json OUT.json] [--png OUT.png] [--full]   (--full: also 1920x1080)

Goals (640x480, 2 threads, reprojection and colour mix included): network-12 <= 40 ms,
the default network <= 30 ms (the labels of the shipped files: c12, and the default's, c6)."""
import json
import os
import subprocess
import sys

import numpy as np

from tools.tttools import cli, host


def loadavg():
    return tuple(float(x) for x in open("/proc/loadavg").read().split()[:3])


def cpu_name():
    """The CPU's model name (/proc/cpuinfo), to say which machine the figures are from."""
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return "unknown"


def chart(path, rows, lo, hi, threads):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = [r for r in rows if r["size"] == "640x480"]
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    x = np.arange(len(rows))
    names = [f"{r['variant']} T{r['threads']}" for r in rows]
    wall = [r["median"]["wall"] for r in rows]
    err = [[w - min(r["runs"]["wall"]) for w, r in zip(wall, rows)],
           [max(r["runs"]["wall"]) - w for w, r in zip(wall, rows)]]
    ax[0].bar(x, wall, yerr=err, capsize=3, color="tab:blue")
    for i, r in enumerate(rows):
        for g in r.get("goals", []):
            ax[0].plot([i - 0.4, i + 0.4], [g] * 2, "r--", lw=1.2)
    ax[0].set_xticks(x, names, rotation=25, fontsize=8)
    ax[0].set_title(f"640x480 wall ms per frame (median, run range; red: goal)\n"
                    f"load average {lo:.1f}-{hi:.1f} on 2 cores", fontsize=9)
    bottom = np.zeros(len(rows))
    for part, col in (("reproj", "tab:green"), ("network", "tab:orange"), ("mix", "tab:purple")):
        v = np.array([r["median"][part] for r in rows])
        ax[1].bar(x, v, bottom=bottom, label=part if part != "reproj" else "reprojection + rejection",
                  color=col)
        bottom += v
    ax[1].plot(x, [r["median"]["cpu"] for r in rows], "k_", ms=18, label="process CPU")
    ax[1].set_xticks(x, names, rotation=25, fontsize=8)
    ax[1].set_title("CPU ms per frame (all threads), by stage", fontsize=9)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path + ".tmp.png", dpi=90)
    os.replace(path + ".tmp.png", path)
    plt.close(fig)


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--threads", default="2")
    ap.add_argument("--weights", default=None)
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--json", default=None)
    ap.add_argument("--full", action="store_true")
    ap.add_argument("--goal", action="append", default=[],
                    help="LABEL=MS: goal per 640x480 frame (default c12=40 and, with "
                         "--default LABEL, LABEL=30)")
    ap.add_argument("--default", default="c6",
                    help="label of the shipped default network (goal 30 ms; default c6, the "
                         "network post_taa loads without post_taa.weights)")
    ap.add_argument("--png", default=None, help="chart: 640x480 wall ms per variant (median, "
                    "range) beside the CPU ms split into reprojection / network / mix")
    a = ap.parse_args()
    exe = host.find(a.host)
    bench = host.build_path(exe, "plugins", "post_taa", "tests", "taa_bench")
    env = dict(os.environ, TT_SOURCE_ROOT=host.ROOT, TT_BENCH_THREADS=a.threads,
               TT_BENCH_ROUNDS=str(a.rounds), TT_PLUGIN_PATH=host.build_path(exe, "plugins"))
    if not a.full:
        env["TT_BENCH_QUICK"] = "1"
    if a.weights:
        env["TT_BENCH_WEIGHTS"] = a.weights
    runs = []
    for k in range(a.runs):
        before = loadavg()
        r = subprocess.run([bench], env=env,
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        after = loadavg()
        if r.returncode:
            sys.exit(f"speed.py: taa_bench failed:\n{r.stdout}")
        rows = {}
        for line in r.stdout.splitlines():
            if line.startswith("BENCH "):
                f = line.split()
                key = (f[1], f[2], int(f[3]))
                rows[key] = {"wall": float(f[4]), "cpu": float(f[5]), "reject": float(f[6]),
                             "reproj": float(f[7]), "network": float(f[8]), "mix": float(f[9])}
        runs.append({"load_before": before, "load_after": after, "rows": rows})
        print(f"run {k + 1}/{a.runs}: load {before[0]:.2f} -> {after[0]:.2f}", flush=True)
    keys = list(runs[0]["rows"])
    # a label can carry two goals: c12 is network-12 (<= 40) and, shipped as the default, <= 30
    goals = {"c12": [(40.0, "network-12")]}
    if a.default:
        goals.setdefault(a.default, []).append((30.0, "default"))
    for g in a.goal:
        lab, ms = g.split("=")
        goals[lab] = [(float(ms), "goal")]
    print(f"\nmedians of {a.runs} per-run medians ({a.rounds} interleaved rounds each), range in "
          "brackets; ms per frame; CPU = process CPU time, all threads\n")
    print("| variant | size | threads | wall ms | CPU ms | reproj + rejection CPU | network CPU | mix CPU | goal |")
    print("|---|---|---|---|---|---|---|---|---|")
    out = []
    for key in keys:
        vals = {m: [r["rows"][key][m] for r in runs if key in r["rows"]] for m in runs[0]["rows"][key]}
        med = {m: float(np.median(v)) for m, v in vals.items()}
        lab, size, th = key
        mine = goals.get(lab, []) if size == "640x480" and th == 2 else []
        gtxt = "; ".join(f"{name} <= {ms:.0f}: {'met' if med['wall'] <= ms else 'NOT met'}"
                         for ms, name in mine)
        goal = min((ms for ms, _ in mine), default=None)
        print(f"| {lab} | {size} | {th} | **{med['wall']:.1f}** ({min(vals['wall']):.1f}-"
              f"{max(vals['wall']):.1f}) | {med['cpu']:.1f} | {med['reproj']:.1f} | "
              f"{med['network']:.1f} | {med['mix']:.1f} | {gtxt} |")
        out.append({"variant": lab, "size": size, "threads": th, "median": med,
                    "runs": vals, "goal_ms": goal, "goals": [ms for ms, _ in mine]})
    loads = [r["load_before"][0] for r in runs] + [r["load_after"][0] for r in runs]
    print(f"\nload average (1 min) during the runs: {min(loads):.2f} - {max(loads):.2f}")
    if a.png:
        chart(a.png, out, min(loads), max(loads), a.threads)
    if a.json:  # atomic: a reader (the evidence page) never sees half a file
        with open(a.json + ".tmp", "w") as f:
            json.dump({"runs": a.runs, "rounds": a.rounds, "threads": a.threads, "cpu": cpu_name(),
                       "loads": [(r["load_before"], r["load_after"]) for r in runs], "rows": out},
                      f, indent=1)
        os.replace(a.json + ".tmp", a.json)


if __name__ == "__main__":
    main()
