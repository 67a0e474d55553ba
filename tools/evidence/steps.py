"""The quick evidence pass: every figure tool the docs rely on, run at quick settings (seconds
each) or on the committed data it was measured into, so a tool that rots fails the suite.

A step is a function step(ctx) that runs one tool as its users run it (`python3 -m tools...`) and returns the PNGs it wrote, relative to ctx.out.
Steps that re-plot committed data (hybrid, accel) write the real figures; steps that measure
(tuning, gains, cylinder, Theta, the PSSMLT tools, TAA speed, integrators) run at toy sizes, and the page labels
them so. The full-settings commands are in entries.py (what `run.py --full` prints)."""
import json
import math
import os
import shutil
import subprocess
import sys
import time

from tools.tttools import host as tthost

ROOT = tthost.ROOT
PY = "/usr/bin/python3"
CORNELL = os.path.join(ROOT, "scenes", "cornell-box", "scene.json")


class StepError(Exception):
    pass


class Ctx:
    def __init__(self, host, out, work, log):
        self.host, self.out, self.work, self.log = host, out, work, log

    def path(self, *parts):
        p = os.path.join(self.out, *parts)
        os.makedirs(os.path.dirname(p), exist_ok=True)
        return p

    def run(self, cmd, env=None, cwd=None):
        """Runs one command (a list) from the repository root; its output goes to the log.
        A non-zero exit is a StepError naming the command and the end of its output."""
        e = dict(os.environ)
        e.setdefault("MPLBACKEND", "Agg")
        e["PYTHONPATH"] = ROOT + (os.pathsep + e["PYTHONPATH"] if e.get("PYTHONPATH") else "")
        if env:
            e.update(env)
        self.log.write("$ " + " ".join(cmd) + "\n")
        self.log.flush()
        p = subprocess.run(cmd, cwd=cwd or ROOT, env=e, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True)
        self.log.write(p.stdout)
        self.log.flush()
        if p.returncode != 0:
            raise StepError(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stdout[-2000:]}")
        return p.stdout

    def host_args(self):
        return ["--host", self.host]


def _png(ctx, rel):
    p = os.path.join(ctx.out, rel)
    with open(p, "rb") as f:
        if f.read(8) != b"\x89PNG\r\n\x1a\n":
            raise StepError(f"{p}: not a PNG")
    return rel


# --- chapter 3 -------------------------------------------------------------------------------

HYBRID_DIR = os.path.join(ROOT, "tools", "hybrid", "figures", "session8")


def hybrid_figures(ctx):
    """Figs. 3.16-3.21 and leave-one-scene-out, redrawn by tools/hybrid/figures.py from the
    committed per-camera rows of the current evaluation (re-measuring takes hours)."""
    code = ("import json, sys\nfrom tools.hybrid import figures\n"
            "rows = json.load(open(sys.argv[1])); summary = json.load(open(sys.argv[2]))\n"
            "figures.draw(rows, summary, sys.argv[3])\n")
    d = ctx.path("hybrid", "x")
    ctx.run([PY, "-c", code, os.path.join(HYBRID_DIR, "rows.json"),
             os.path.join(HYBRID_DIR, "summary.json"), os.path.dirname(d)])
    return [_png(ctx, os.path.join("hybrid", n)) for n in sorted(os.listdir(os.path.dirname(d)))
            if n.endswith(".png")]


def hybrid_speed_vs_roofline(ctx):
    """Speed against accuracy for hybrid tuning: per predictor and scene, the geometric mean
    over cameras x splits of the speed-up over the search against the fraction of the
    roofline (the search's best), one panel per objective, from the committed rows."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = json.load(open(os.path.join(HYBRID_DIR, "rows.json")))
    colors = {"nn": "#1f77b4", "rbf": "#2ca02c", "static": "#7f7f7f"}
    markers = "osD^v<>px*"
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    for ax, obj in zip(axes, ("render", "build+render")):
        sel = [r for r in rows if r["variant"] == "default" and r["objective"] == obj
               and r["protocol"].startswith("split")]
        scenes = sorted({r["scene"] for r in sel})
        for m in ("nn", "rbf", "static"):
            for si, s in enumerate(scenes):
                rs = [r for r in sel if r["model"] == m and r["scene"] == s
                      and r["speedup"] and r["roofline"] and r["speedup"] > 0 and r["roofline"] > 0]
                if not rs:
                    continue
                g = lambda k: math.exp(sum(math.log(r[k]) for r in rs) / len(rs))  # noqa: E731
                ax.scatter(g("roofline"), g("speedup"), color=colors[m], marker=markers[si % 10],
                           s=40, alpha=0.8, label=f"{m}" if si == 0 else None)
                if m == "nn":
                    ax.annotate(s, (g("roofline"), g("speedup")), fontsize=6, xytext=(3, 3),
                                textcoords="offset points")
        ax.axvline(1.0, color="k", lw=0.7, ls="--")
        ax.set_xlabel("fraction of the roofline (1: the search's best; geo-mean per scene)")
        ax.set_ylabel("speed-up over a 40-iteration search (geo-mean)")
        ax.set_title(f"hybrid tuning, {obj} time: speed vs accuracy", fontsize=10)
        ax.legend(fontsize=8)
    fig.tight_layout()
    p = ctx.path("hybrid", "speed_vs_roofline.png")
    fig.savefig(p, dpi=100)
    plt.close(fig)
    return [_png(ctx, "hybrid/speed_vs_roofline.png")]


REMEASURED = os.path.join(ROOT, "tools", "hybrid", "figures", "remeasured", "remeasure.json")


def hybrid_remeasured(ctx):
    """The re-measured rooflines (tools/hybrid/remeasure.py): the committed full run's chart
    redrawn from its JSON, and the tool itself at --quick settings on two scenes of the
    committed baseline (trained on veach-ajar, tested on one killeroos camera, 32x32)."""
    from tools.hybrid import remeasure
    pngs = []
    if os.path.exists(REMEASURED):
        with open(REMEASURED) as f:
            remeasure.draw(json.load(f), ctx.path("hybrid", "roofline_speed.png"))
        pngs.append(_png(ctx, "hybrid/roofline_speed.png"))
    w = os.path.join(ctx.work, "remeasure")
    shutil.rmtree(w, ignore_errors=True)
    db = os.path.join(w, "b.db")
    ctx.run([PY, "-m", "tools.hybrid.baseline"] + ctx.host_args() +
            ["--db", db, "--work", os.path.join(w, "w"), "--scenes", "killeroos,veach-ajar",
             "--restore", os.path.join(ROOT, "tools", "hybrid", "data", "baseline.sql.xz")])
    ctx.run([PY, "-m", "tools.hybrid.remeasure"] + ctx.host_args() +
            ["--db", db, "--work", os.path.join(w, "rm"), "--out", os.path.join(w, "out"),
             "--train-scenes", "veach-ajar", "--test-scenes", "killeroos", "--quick", "--nice", "0"])
    shutil.copyfile(os.path.join(w, "out", "roofline_speed.png"), ctx.path("quick", "hybrid_roofline_speed.png"))
    return pngs + [_png(ctx, "quick/hybrid_roofline_speed.png")]


def accel_render_split(ctx):
    """tools/accel/render_split.py on the committed render-bench output."""
    ctx.run([PY, "-m", "tools.accel.render_split",
             os.path.join(ROOT, "tools", "accel", "data", "render_bench_session9.txt"),
             "--mode", "t1 d3", "--out", ctx.path("accel", "render_split_t1d3.png")])
    return [_png(ctx, "accel/render_split_t1d3.png")]


ANIM_DATA = os.path.join(ROOT, "tools", "accel", "data")


def accel_anim_update(ctx):
    """tools/accel/anim_update.py: every committed sequence's figure redrawn from its JSON
    (anim_update_*.json: the real figures) and a toy measurement (animated-stress, 6 frames at
    16x16, one round, 2-iteration searches, a sweep of two schedules)."""
    pngs = []
    for name in sorted(os.listdir(ANIM_DATA)):
        if not (name.startswith("anim_update_") and name.endswith(".json")):
            continue
        png = os.path.join("accel", name[:-5] + ".png")
        ctx.run([PY, "-m", "tools.accel.anim_update", "--replot", os.path.join(ANIM_DATA, name),
                 "--fig", ctx.path(png)])
        pngs.append(_png(ctx, png))
    if not pngs:
        raise StepError(f"no anim_update_*.json in {ANIM_DATA}")
    ctx.run([PY, "-m", "tools.accel.anim_update"] + ctx.host_args() +
            ["--scene", os.path.join(ROOT, "scenes", "animated-stress", "scene.json"),
             "--frames", "0:5", "--res", "16x16", "--rounds", "1", "--tune-iterations", "2",
             "--tune-window", "2", "--static-iterations", "2", "--intervals", "2",
             "--growths", "1.5", "--fig", ctx.path("quick", "anim_update_animated-stress.png")])
    return pngs + [_png(ctx, "quick/anim_update_animated-stress.png")]


SEQ_HYBRID = os.path.join(ROOT, "tools", "hybrid", "figures")


def hybrid_sequence(ctx):
    """tools/hybrid/sequence.py: every committed fold (figures/sequence*/sequence.json: hybrid
    prediction along a test sequence the model never saw) redrawn from its JSON (the real
    figures; measuring a fold takes tens of minutes, its pipeline is tested by
    tools/tests/hybrid_sequence.py)."""
    pngs = []
    for d in sorted(os.listdir(SEQ_HYBRID)):
        js = os.path.join(SEQ_HYBRID, d, "sequence.json")
        if not (d.startswith("sequence") and os.path.isfile(js)):
            continue
        png = os.path.join("hybrid", d.replace("sequence", "sequence_hybrid", 1) + ".png")
        ctx.run([PY, "-m", "tools.hybrid.sequence", "--replot", js, "--fig", ctx.path(png)])
        pngs.append(_png(ctx, png))
    if not pngs:
        raise StepError(f"no sequence*/sequence.json in {SEQ_HYBRID}")
    return pngs


def tuning_analysis(ctx):
    """tools/tuning/analyze.py's five charts (Figs. 3.3, 3.5, 3.6, 3.8, 3.11) on a 12-sample
    exploration and two 6-iteration tuning runs of the Cornell box at 24x24."""
    w = os.path.join(ctx.work, "tuning")
    os.makedirs(w, exist_ok=True)
    db, tdb = os.path.join(w, "e.db"), os.path.join(w, "t.db")
    for f in (db, tdb):
        if os.path.exists(f):
            os.remove(f)
    common = ["--quiet", "--res", "24x24", "--spp", "1", "--threads", "2"]
    ctx.run([ctx.host, "--explore", "12", "--objective", "build+render", "--set",
             "accel_embree.backend=custom", "--db", db, "--out", os.path.join(w, "e.exr")]
            + common + [CORNELL])
    stats = []
    for mode in ("render", "build+render"):
        s = os.path.join(w, f"{mode}.json")
        ctx.run([ctx.host, "--plugin", "tuner_random", "--tune", "accel_embree", "--objective",
                 mode, "--iterations", "6", "--verify", "3", "--db", tdb,
                 "--out", os.path.join(w, "t.exr"), "--stats", s] + common + [CORNELL])
        stats.append(s)
    A = [PY, "-m", "tools.tuning.analyze"]
    ctx.run(A + ["correlation", "--db", db, "-o", ctx.path("quick", "tuning_correlation.png")])
    ctx.run(A + ["leafsize", "--db", db, "-o", ctx.path("quick", "tuning_leafsize.png")])
    ctx.run(A + ["costs", "--db", db, "--metric", "total", "-o", ctx.path("quick", "tuning_costs.png")])
    ctx.run(A + ["blocksize", "--db", db, "-o", ctx.path("quick", "tuning_blocksize.png")])
    ctx.run(A + ["convergence"] + stats + ["-o", ctx.path("quick", "tuning_convergence.png")])
    return [_png(ctx, f"quick/tuning_{n}.png")
            for n in ("correlation", "leafsize", "costs", "blocksize", "convergence")]


def cylinder_sweep(ctx):
    """tools/tuning/cylinder_sweep.py (Fig. 3.13): 2 angles, 1 repetition, 16x16."""
    w = os.path.join(ctx.work, "cylinder")
    shutil.rmtree(w, ignore_errors=True)
    ctx.run([PY, "-m", "tools.tuning.cylinder_sweep"] + ctx.host_args() +
            ["--scene", CORNELL, "--angles", "2", "--reps", "2", "--res", "16x16",
             "--backends", "native", "--work", w, "--fig", ctx.path("quick", "cylinder_cornell-box.png")])
    return [_png(ctx, "quick/cylinder_cornell-box.png")]


# --- chapter 4 -------------------------------------------------------------------------------

def theta_histogram(ctx):
    """tools/pssmlt/theta_histogram.py (Figs. 4.1/4.2) on a dump of a 16x16 PSSMLT render."""
    w = os.path.join(ctx.work, "theta")
    os.makedirs(w, exist_ok=True)
    dump = os.path.join(w, "theta.csv")
    ctx.run([ctx.host, "--quiet", "--no-db", "--plugin", "integrator_pssmlt", "--res", "16x16",
             "--spp", "2", "--threads", "2", "--out", os.path.join(w, "t.exr"), CORNELL],
            env={"TT_PSSMLT_THETA_DUMP": dump})
    ctx.run([PY, "-m", "tools.pssmlt.theta_histogram", dump,
             "--labels", "cornell-box", "-o", ctx.path("quick", "theta_cornell-box.png")])
    return [_png(ctx, "quick/theta_cornell-box.png")]


def pssmlt_tools(ctx):
    """Chapter 4's figure tools in their order, at 16x16: tune_convergence.py (Fig. 4.3),
    compare_tuned.py (Fig. 4.6 box plots; its reference serves the next two),
    error_vs_time.py (equal CPU time) and sigma_sweep.py (the 0.234 target)."""
    w = os.path.join(ctx.work, "pssmlt")
    shutil.rmtree(w, ignore_errors=True)
    tune = os.path.join(w, "tune")
    ctx.run([PY, "-m", "tools.pssmlt.tune_convergence", CORNELL, "--name", "cornell-box"]
            + ctx.host_args() + ["--res", "16x16", "--iterations", "4", "--tune-spp", "1",
                                 "--out", tune, "--fig", ctx.path("quick", "pssmlt_tuning_cornell-box.png")])
    cmp_dir = os.path.join(w, "cmp")
    ctx.run([PY, "-m", "tools.pssmlt.compare_tuned"] + ctx.host_args() +
            ["--res", "16x16", "--ref-spp", "32", "--spp", "2", "--seeds", "2", "--methods",
             "pt,classic,binned,tuned", "--tuned-dir", tune, "--out", cmp_dir,
             "--fig", ctx.path("quick", "pssmlt_equal_mutations.png"), f"cornell-box={CORNELL}"])
    ref = os.path.join(cmp_dir, "cornell-box", "reference.exr")
    ctx.run([PY, "-m", "tools.pssmlt.error_vs_time"] + ctx.host_args() +
            ["--res", "16x16", "--mpp", "1", "2", "--seeds", "1", "--methods", "pt,classic,acc",
             "--tuned", f"acc={os.path.join(tune, 'cornell-box_tuned.json')}", "--ref", ref,
             "--out", os.path.join(w, "evt"), "--fig", ctx.path("quick", "pssmlt_error_vs_time.png"),
             f"cornell-box={CORNELL}"])
    ctx.run([PY, "-m", "tools.pssmlt.sigma_sweep", CORNELL, "--ref", ref] + ctx.host_args() +
            ["--res", "16x16", "--spp", "1", "--seeds", "1", "--sigmas", "0.01,0.1",
             "--out", os.path.join(w, "sweep"), "--fig", ctx.path("quick", "pssmlt_sigma_sweep.png")])
    return [_png(ctx, f"quick/pssmlt_{n}.png")
            for n in ("tuning_cornell-box", "equal_mutations", "error_vs_time", "sigma_sweep")]


def tuning_gains(ctx):
    """tools/tuning/gains.py (Fig. 3.3 charts, verified gains): one seed, 3 iterations, 16x16."""
    w = os.path.join(ctx.work, "gains")
    shutil.rmtree(w, ignore_errors=True)
    ctx.run([PY, "-m", "tools.tuning.gains"] + ctx.host_args() +
            ["--scene", CORNELL, "--seeds", "1", "--iterations", "3", "--verify", "2",
             "--res", "16x16", "--out-dir", w, "--figures", os.path.dirname(ctx.path("quick", "x")),
             "--figure-prefix", "gains_"])
    return [_png(ctx, "quick/gains_cornell-box.png")]


# --- chapter 5 -------------------------------------------------------------------------------

TAA_SPEED = os.path.join(ROOT, "tools", "taa", "figures", "speed.json")


def taa_cpu_ms():
    """CPU ms per 640x480 frame (all threads, 2 threads, reprojection and colour mix included)
    per variant from the committed tools/taa/speed.py measurement (speed.json): process CPU
    time varies less with the shared machine's load than wall time does."""
    try:
        d = json.load(open(TAA_SPEED))
    except (OSError, ValueError) as e:
        raise StepError(f"{TAA_SPEED}: {e}")
    ms = {r["variant"].lower(): r["median"]["cpu"] for r in d.get("rows", [])
          if r.get("size") == "640x480" and int(r.get("threads", 0)) == 2}
    for m in ("c12", "c6", "vctaa"):
        if m not in ms:
            raise StepError(f"{TAA_SPEED}: rows: no 640x480 2-thread row for {m}")
    return ms


def taa_speed_vs_rmse(ctx):
    """Speed against accuracy for TAA: CPU ms per frame (committed speed.json) against the
    geometric mean RMSE over the committed test set (tools/taa/figures/test_set.json), c12,
    c6 and VCTAA."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = json.load(open(os.path.join(ROOT, "tools", "taa", "figures", "test_set.json")))
    fig, ax = plt.subplots(figsize=(6.5, 4.2))
    for m, ms in taa_cpu_ms().items():
        r = [sq["methods"][m]["rmse"] for sq in d["sequences"] if m in sq["methods"]]
        if not r:
            raise StepError(f"test_set.json: no {m} rows")
        g = math.exp(sum(math.log(x) for x in r) / len(r))
        ax.scatter(ms, g, s=60)
        ax.annotate(f"{m} ({g:.4f})", (ms, g), xytext=(5, 5), textcoords="offset points")
    ax.set_xlabel("CPU ms per 640x480 frame, 2 threads (tools/taa/figures/speed.json)")
    ax.set_ylabel("RMSE, geo-mean of the test set's 6 sequences")
    ax.set_title("TAA: speed against accuracy on the test set", fontsize=10)
    fig.tight_layout()
    fig.savefig(ctx.path("taa", "speed_vs_rmse.png"), dpi=100)
    plt.close(fig)
    return [_png(ctx, "taa/speed_vs_rmse.png")]


def taa_darkening(ctx):
    """tools/taa/darkening.py (VCTAA's darkening, both resolves) redrawn from the committed
    evaluation tools/taa/figures/darkening_eval.json (no rendering)."""
    ctx.run([PY, "-m", "tools.taa.darkening",
             os.path.join(ROOT, "tools", "taa", "figures", "darkening_eval.json"),
             "--out", ctx.path("taa", "darkening.png")])
    return [_png(ctx, "taa/darkening.png")]


def taa_speed(ctx):
    """tools/taa/speed.py (Table 5.2): one run of one round of taa_bench (wall times on a
    loaded machine: the tool runs, the figures are not results)."""
    ctx.run([PY, "-m", "tools.taa.speed"] + ctx.host_args() +
            ["--runs", "1", "--rounds", "1", "--json", os.path.join(ctx.work, "speed.json"),
             "--png", ctx.path("quick", "taa_speed.png")])
    return [_png(ctx, "quick/taa_speed.png")]


# --- integrators (error against time) --------------------------------------------------------

def integrator_error_vs_time(ctx):
    """tools/charts/error_vs_time.py: rRMSE against render time, 16x16, maxDepth 1 and 3."""
    w = os.path.join(ctx.work, "evt")
    shutil.rmtree(w, ignore_errors=True)
    ctx.run([PY, "-m", "tools.charts.error_vs_time"] + ctx.host_args() +
            ["--res", "16x16", "--depths", "1,3", "--ref-spp", "64", "--max-spp", "8",
             "--threads", "2", "--out", w])
    shutil.copyfile(os.path.join(w, "error_vs_time.png"), ctx.path("quick", "error_vs_time_cornell.png"))
    return [_png(ctx, "quick/error_vs_time_cornell.png")]


def integrator_sampler_choice(ctx):
    """tools/charts/sampler_choice.py --summarize: the default-sampler charts (integrator_pt,
    integrator_bdpt) redrawn from the committed renders' JSON (no rendering; a JSON that no
    longer reads or a tool that rots fails)."""
    pngs = []
    src = os.path.join(ROOT, "tools", "charts")
    # (integrator, file stem, folder under tools/charts, name of the page's PNG): the choices,
    # then BDPT's held-out check (scenes no default was chosen on)
    for ig, stem, sub, png in (("integrator_pt", "sampler_choice", "", "sampler_choice"),
                               ("integrator_bdpt", "sampler_choice_integrator_bdpt", "",
                                "sampler_choice_integrator_bdpt"),
                               ("integrator_bdpt", "sampler_choice_integrator_bdpt", "heldout",
                                "sampler_heldout_integrator_bdpt")):
        if not os.path.exists(os.path.join(src, sub, stem + ".json")):
            continue
        w = os.path.join(ctx.work, "sampler_" + png)
        shutil.rmtree(w, ignore_errors=True)
        os.makedirs(w)
        shutil.copyfile(os.path.join(src, sub, stem + ".json"), os.path.join(w, stem + ".json"))
        ctx.run([PY, "-m", "tools.charts.sampler_choice", "--integrator", ig, "--summarize",
                 "--out", w])
        shutil.copyfile(os.path.join(w, stem + ".png"), ctx.path("charts", png + ".png"))
        pngs.append(_png(ctx, f"charts/{png}.png"))
    if not pngs:
        raise StepError(f"no sampler_choice*.json in {src}")
    return pngs


QUICK = [hybrid_figures, hybrid_speed_vs_roofline, hybrid_remeasured, accel_render_split,
         accel_anim_update, hybrid_sequence, tuning_analysis,
         tuning_gains, cylinder_sweep, theta_histogram, pssmlt_tools, taa_speed_vs_rmse, taa_darkening, taa_speed,
         integrator_error_vs_time, integrator_sampler_choice]


def run_quick(host, out, work, log_path, only=None):
    """Runs the quick steps; returns {step name: {"ok", "seconds", "pngs", "error"}}."""
    results = {}
    with open(log_path, "w") as log:
        ctx = Ctx(host, out, work, log)
        for step in QUICK:
            if only and step.__name__ not in only:
                continue
            t0 = time.time()
            try:
                pngs = step(ctx)
                results[step.__name__] = {"ok": True, "pngs": pngs, "error": None}
            except Exception as e:  # noqa: BLE001 (a broken tool fails its step, not the pass)
                results[step.__name__] = {"ok": False, "pngs": [], "error": str(e)}
            results[step.__name__]["seconds"] = round(time.time() - t0, 1)
            r = results[step.__name__]
            print(f"evidence: {step.__name__}: {'ok' if r['ok'] else 'FAILED'} ({r['seconds']} s)"
                  + ("" if r["ok"] else f"\n{r['error']}"), file=sys.stderr, flush=True)
    return results
