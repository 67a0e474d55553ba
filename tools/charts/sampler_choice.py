"""Which primary-sample generator an integrator (integrator_pt by default, or --integrator
integrator_bdpt) should use by default, by measurement: time to equal error for the
`independent`, `halton` and `sobol` samplers (or those --samplers names) on several scenes.

Per scene:
  1. a high-spp reference, rendered once with the independent sampler (unbiased whatever the
     other samplers do) with the measured integrator, as two halves of REF_SPP/2 with seeds 0 and 1, averaged. The halves'
     difference estimates the reference's own noise, which is subtracted from every error
     below (err^2 - noise^2), so a sampler whose error approaches the reference's noise is
     not penalised for the reference's grain;
  2. for every seed (100, 101, ...) and spp (4, 16, 64 by default), one render per sampler,
     the samplers round-robin in a rotating order (interleaved, so machine load drifts hit
     every sampler alike); each render's rRMSE against the reference (tunetrace's one
     definition, tools/common/images.py = the C tt_rrmse) and its CPU time (host
     `--clock cpu`: the render's CPU seconds, scene load and accel build excluded);
  3. per sampler and spp the root mean square of the errors over seeds (the expected
     squared error; a median would hide rare fireflies) and the median CPU time; then a
     fit err = c * spp^-a (least squares in log-log over the spp points) and the CPU
     seconds per spp k (median of time / spp at the largest spp), so the time to reach an
     error E is k * (c / E)^(1/a).
     The speed-up of a sampler over `independent` is independent's time over its time at
     the error independent reaches at the middle and the largest spp (equal error, not
     equal spp). At equal spp it is the error ratio^2 x time ratio when both converge at
     a = 0.5; the fit also credits a sampler that converges faster than that.

Every render uses the plugin's defaults except the sampler (maxDepth etc. as `host
--describe INTEGRATOR` says, or --depth), 1 thread (CPU time, not wall, is compared), the
box filter. Writes OUT/sampler_choice.json and OUT/sampler_choice.png (error vs CPU time per
sampler per scene; OUT/sampler_choice_INTEGRATOR.* for an integrator other than
integrator_pt) and prints a table; renders and the reference go to --work (kept:
an existing reference is reused). --summarize recomputes the figures, table and chart from
the renders an earlier run stored in OUT/sampler_choice.json, rendering nothing.

Usage (from the repository root, after `ninja -C build`):
  /usr/bin/python3 -m tools.charts.sampler_choice [--host PATH] [--res 64x64]
      [--integrator integrator_pt] [--samplers independent,halton,sobol]
      [--scenes cornell-box,cornell-pbrt,veach-ajar,killeroos] [--spps 4,16,64] [--seeds 6]
      [--ref-spp 1024] [--depth N] [--nice 10] [--out tools/charts] [--work /tmp/tt_sampler]
      [--summarize]
Needs: python3-matplotlib, python3-numpy, python3-openimageio (Debian 12 packages).
"""
import json
import math
import os
import statistics
import tempfile

import numpy as np

from tools.common import images
from tools.tttools import cli, figures, host

ROOT = host.ROOT
SHARED = os.path.join(os.path.dirname(ROOT), "shared", "scenes")
SAMPLERS = ("independent", "halton", "sobol")
INTEGRATORS = ("integrator_pt", "integrator_bdpt")
# Scenes that render in seconds at 64x64 on one core; the pbrt files come from ../shared.
SCENES = {
    "cornell-box": os.path.join(ROOT, "scenes", "cornell-box", "scene.json"),
    "cornell-pbrt": os.path.join(SHARED, "cornell-box-pbrt", "cornell-box.pbrt"),
    "cornell-specular": os.path.join(SHARED, "cornell-box-pbrt", "cornell-box-specular.pbrt"),
    "caustic-glass": os.path.join(ROOT, "scenes", "caustic-glass", "scene.json"),
    "veach-ajar": os.path.join(ROOT, "scenes", "veach-ajar", "scene.json"),
    "killeroos": os.path.join(ROOT, "scenes", "killeroos", "scene.json"),
    # held out: no default was chosen on these (plugins/integrator_bdpt/README.md)
    "veach-mis": os.path.join(ROOT, "scenes", "veach-mis", "scene.json"),
}


def render(args, scene, sampler, spp, seed, out, threads=1):
    """One render; returns its CPU seconds (host --clock cpu render_ms, all threads)."""
    ig = args.integrator
    extra = ["--spp", str(spp), "--seed", str(seed), "--clock", "cpu", "--plugin", ig,
             "--set", f"{ig}.sampler={sampler}"]
    if args.depth is not None:
        extra += ["--set", f"{ig}.maxDepth={args.depth}"]
    st, _ = host.render(args.host, scene, extra, out=out, stats=out + ".json", res=args.res,
                        threads=threads, nice=args.nice)
    return st["render_ms"] / 1000.0


def write_exr(path, rgb):
    """Writes an RGB float image atomically."""
    import OpenImageIO as oiio
    tmp = path + f".tmp-{os.getpid()}.exr"
    spec = oiio.ImageSpec(rgb.shape[1], rgb.shape[0], 3, "float")
    o = oiio.ImageOutput.create(tmp)
    if o is None or not o.open(tmp, spec) or not o.write_image(np.ascontiguousarray(rgb)):
        raise IOError(f"{tmp}: {oiio.geterror()}")
    o.close()
    os.replace(tmp, path)


def reference(args, name, scene):
    """(reference RGB, its rRMSE noise) for a scene: two independent halves averaged; the
    noise of the mean is rRMSE(half A, half B) / 2 (var(A - B) = 4 var(mean))."""
    ig = getattr(args, "integrator", "integrator_pt")
    # Each integrator's own reference (BDPT's includes light paths the path tracer misses).
    d = os.path.join(args.work, name) if ig == "integrator_pt" else os.path.join(args.work, ig, name)
    os.makedirs(d, exist_ok=True)
    ref = os.path.join(d, f"ref_{args.ref_spp}spp_{args.res}.exr")
    halves = [os.path.join(d, f"ref_half{s}_{args.ref_spp}spp_{args.res}.exr") for s in (0, 1)]
    for seed, h in enumerate(halves):
        if not os.path.exists(h):
            t = render(args, scene, "independent", args.ref_spp // 2, seed, h, threads=2)
            print(f"{name}: reference half {seed}: {args.ref_spp // 2} spp, {t:.1f} CPU s", flush=True)
    a, b = images.read_rgb(halves[0]), images.read_rgb(halves[1])
    r = 0.5 * (a + b)
    if not os.path.exists(ref):
        write_exr(ref, r)
    lum_r = images.luminance(r)
    la, lb = images.luminance(a), images.luminance(b)
    noise = float(np.sqrt(np.mean((la - lb) ** 2 / (lum_r ** 2 + images.RRMSE_EPS)))) / 2.0
    return r, noise


def load(path):
    """A sampler_choice.json written by an earlier run; SystemExit naming the file and what is
    wrong when it is missing or not one."""
    try:
        with open(path) as f:
            doc = json.load(f)
        for key in ("spps", "seeds", "res", "ref_spp", "max_depth", "scenes"):
            doc[key]
        doc.setdefault("integrator", "integrator_pt")
        doc.setdefault("samplers", list(SAMPLERS))
        if "independent" not in doc["samplers"]:
            raise ValueError("its samplers lack 'independent', the one every speed-up is against")
        for n, r in doc["scenes"].items():
            for s in doc["samplers"]:
                for spp in doc["spps"]:
                    r["samplers"][s]["renders"][str(spp)][0]["rrmse"]
    except (OSError, ValueError) as e:
        raise SystemExit(f"--summarize: {path}: {e}") from None
    except (KeyError, IndexError, TypeError) as e:
        raise SystemExit(f"--summarize: {path}: not a sampler_choice.json with renders "
                         f"(missing {e})") from None
    return doc


def fit(spps, errs):
    """Least-squares err = c * spp^-a in log-log; returns (c, a)."""
    x = np.log(np.asarray(spps, float))
    y = np.log(np.asarray(errs, float))
    slope, icpt = np.polyfit(x, y, 1)
    return float(math.exp(icpt)), float(-slope)


def time_to(c, a, k, err):
    """CPU seconds to reach rRMSE `err` with err = c * spp^-a and k CPU s per spp."""
    return k * (c / err) ** (1.0 / a)


def measure_scene(args, name, scene, spps, seeds):
    ref, noise = reference(args, name, scene)
    print(f"{name}: reference noise rRMSE {noise:.4f} (subtracted in quadrature)", flush=True)
    samplers = args.samplers
    raw = {s: {spp: [] for spp in spps} for s in samplers}
    fd, tmp = tempfile.mkstemp(suffix=".exr", dir=args.work)
    os.close(fd)
    try:
        turn = 0
        for seed in seeds:
            for spp in spps:
                k = turn % len(samplers)
                order = samplers[k:] + samplers[:k]
                turn += 1
                for s in order:
                    t = render(args, scene, s, spp, seed, tmp)
                    e = images.rrmse(images.read_rgb(tmp), ref)
                    raw[s][spp].append({"seed": seed, "cpu_s": t, "rrmse": e})
            print(f"{name}: seed {seed} done", flush=True)
    finally:
        for p in (tmp, tmp + ".json"):
            if os.path.exists(p):
                os.remove(p)
    return summarize(scene, noise, raw, spps)


def summarize(scene, noise, raw, spps):
    """The figures of one scene from its renders raw[sampler][spp] = [{seed, cpu_s, rrmse}]."""
    res = {"scene": scene, "reference_noise": noise, "samplers": {}}
    samplers = [s for s in SAMPLERS if s in raw]
    for s in samplers:
        pts = []
        for spp in spps:
            # The error is the root mean square over seeds (the expected squared error that
            # "equal error" means): a median would hide a sampler's rare fireflies.
            e_rms = math.sqrt(statistics.mean(r["rrmse"] ** 2 for r in raw[s][spp]))
            e_cor = math.sqrt(max(e_rms ** 2 - noise ** 2, 1e-12))
            t_med = statistics.median(r["cpu_s"] for r in raw[s][spp])
            pts.append({"spp": spp, "rrmse": e_rms, "rrmse_corrected": e_cor, "cpu_s": t_med})
        c, a = fit(spps, [p["rrmse_corrected"] for p in pts])
        k = statistics.median(r["cpu_s"] / spps[-1] for r in raw[s][spps[-1]])
        res["samplers"][s] = {"points": pts, "fit_c": c, "fit_a": a, "cpu_s_per_spp": k,
                              "renders": {str(spp): raw[s][spp] for spp in spps}}
    ind = res["samplers"]["independent"]
    targets = {str(spp): ind["points"][i]["rrmse_corrected"] for i, spp in enumerate(spps)
               if i >= len(spps) - 2}
    res["equal_error_targets"] = targets
    for s in samplers:
        r = res["samplers"][s]
        r["speedup_vs_independent"] = {
            spp: time_to(ind["fit_c"], ind["fit_a"], ind["cpu_s_per_spp"], e)
            / time_to(r["fit_c"], r["fit_a"], r["cpu_s_per_spp"], e) for spp, e in targets.items()}
        # Equal-spp estimate: (err ratio)^2 x (time ratio), valid when both converge at a = 0.5.
        r["equal_spp_ratio"] = {
            str(p["spp"]): (q["rrmse_corrected"] / p["rrmse_corrected"]) ** 2 * q["cpu_s"] / p["cpu_s"]
            for p, q in zip(r["points"], ind["points"])}
    return res


def chart(results, path, res, spps, integrator):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    n = len(results)
    cols = 2 if n == 4 else min(n, 3)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(4.2 * cols, 3.6 * rows), squeeze=False)
    for ax, (name, r) in zip(axes.flat, results.items()):
        for s, style in zip(SAMPLERS, ("o-", "s-", "^-")):
            if s not in r["samplers"]:
                continue
            q = r["samplers"][s]
            t = [p["cpu_s"] for p in q["points"]]
            e = [p["rrmse_corrected"] for p in q["points"]]
            sp = q["speedup_vs_independent"][str(spps[-1])]
            ax.loglog(t, e, style, label=f"{s} (a={q['fit_a']:.2f}, {sp:.2f}x)")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel("CPU s per render (1 thread)")
        ax.set_ylabel("rRMSE (ref. noise removed)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[n:]:
        ax.axis("off")
    fig.suptitle(f"{integrator} samplers: error vs CPU time ({res}, spp {','.join(map(str, spps))}; "
                 "x = time to equal error vs independent)", fontsize=9)
    figures.save(fig, path, dpi=110)
    plt.close(fig)


def main():
    ap = cli.parser(__doc__)
    ap.add_argument("--scenes", default="cornell-box,cornell-pbrt,veach-ajar,killeroos",
                    help="comma-separated names from: " + ", ".join(SCENES))
    ap.add_argument("--integrator", default="integrator_pt", help="one of " + ", ".join(INTEGRATORS))
    ap.add_argument("--samplers", default=",".join(SAMPLERS),
                    help="comma-separated, from " + ", ".join(SAMPLERS) + "; must include independent")
    ap.add_argument("--res", default="64x64")
    ap.add_argument("--spps", default="4,16,64")
    ap.add_argument("--seeds", type=int, default=6, help="renders per sampler and spp")
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--depth", type=int, default=None, help="maxDepth (default: the plugin's)")
    ap.add_argument("--nice", type=int, default=None, help="run the host under nice -n NICE")
    ap.add_argument("--out", default=os.path.join(ROOT, "tools", "charts"))
    ap.add_argument("--work", default="/tmp/tt_sampler")
    ap.add_argument("--summarize", action="store_true",
                    help="render nothing: recompute the figures, table and chart from the renders "
                         "stored in OUT/sampler_choice.json")
    args = ap.parse_args()
    if not args.summarize:
        args.host = host.find(args.host)
    if args.integrator not in INTEGRATORS:
        raise SystemExit(f"--integrator: unknown integrator '{args.integrator}' "
                         f"(known: {', '.join(INTEGRATORS)})")
    args.samplers = [s.strip() for s in args.samplers.split(",") if s.strip()]
    bad = [s for s in args.samplers if s not in SAMPLERS]
    if bad or "independent" not in args.samplers or len(set(args.samplers)) != len(args.samplers):
        raise SystemExit(f"--samplers: expected distinct names from {', '.join(SAMPLERS)} "
                         f"including independent, got '{','.join(args.samplers)}'")
    names = [n.strip() for n in args.scenes.split(",") if n.strip()]
    for n in ([] if args.summarize else names):  # --summarize renders nothing: no scene needed
        if n not in SCENES:
            raise SystemExit(f"--scenes: unknown scene '{n}' (known: {', '.join(SCENES)})")
        if not os.path.exists(SCENES[n]):
            raise SystemExit(f"--scenes: {n}: {SCENES[n]} does not exist")
    try:
        spps = sorted(int(s) for s in args.spps.split(","))
    except ValueError:
        raise SystemExit(f"--spps: expected comma-separated integers, got '{args.spps}'") from None
    if len(spps) < 2 or spps[0] < 1 or args.seeds < 1 or args.ref_spp < 2 * spps[-1]:
        raise SystemExit("--spps: at least two values >= 1; --seeds >= 1; --ref-spp >= 2x the largest spp")
    stem = "sampler_choice" + ("" if args.integrator == "integrator_pt" else "_" + args.integrator)
    jpath = os.path.join(args.out, stem + ".json")
    if args.summarize:
        doc = load(jpath)
        spps = doc["spps"]
        args.integrator = doc["integrator"]
        doc["scenes"] = {n: summarize(r["scene"], r["reference_noise"],
                                      {s: {spp: q["renders"][str(spp)] for spp in spps}
                                       for s, q in r["samplers"].items()}, spps)
                         for n, r in doc["scenes"].items()}
        results, seeds, depth, args.res = doc["scenes"], doc["seeds"], doc["max_depth"], doc["res"]
        args.ref_spp = doc["ref_spp"]
    else:
        seeds = list(range(100, 100 + args.seeds))
        defaults = host.default_config(args.host, args.integrator)
        depth = args.depth if args.depth is not None else defaults.get("maxDepth")
        results = {n: measure_scene(args, n, SCENES[n], spps, seeds) for n in names}
        doc = {"integrator": args.integrator, "samplers": args.samplers, "res": args.res, "spps": spps, "seeds": seeds, "ref_spp": args.ref_spp,
               "max_depth": depth, "threads": 1, "clock": "cpu", "scenes": results}
    os.makedirs(args.out, exist_ok=True)
    tmp = jpath + f".tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        json.dump(doc, f, indent=1)
    os.replace(tmp, jpath)
    png = os.path.join(args.out, stem + ".png")
    chart(results, png, args.res, spps, args.integrator)

    print(f"\n{args.integrator}, {args.res}, maxDepth {depth}, 1 thread; rRMSE: RMS over {len(seeds)} seeds, the "
          f"reference's noise removed; CPU s: median; reference {args.ref_spp} spp (independent)")
    print("| scene | sampler | " + " | ".join(f"rRMSE @{s}" for s in spps)
          + f" | CPU s @{spps[-1]} | fit a | " + " | ".join(
              f"speed-up at independent's error @{s}" for s in spps[-2:])
          + f" | err^2 x time ratio @{spps[-1]} |")
    print("|---|---|" + "---|" * (len(spps) + 5))
    for n, r in results.items():
        for s in [s for s in SAMPLERS if s in r["samplers"]]:
            q = r["samplers"][s]
            print(f"| {n} | {s} | " + " | ".join(f"{p['rrmse_corrected']:.4f}" for p in q["points"])
                  + f" | {q['points'][-1]['cpu_s']:.2f} | {q['fit_a']:.2f} | "
                  + " | ".join(f"{q['speedup_vs_independent'][str(s2)]:.2f}x" for s2 in spps[-2:])
                  + f" | {q['equal_spp_ratio'][str(spps[-1])]:.2f}x |")
    print(f"\nwrote {jpath} and {png}")


if __name__ == "__main__":
    main()
