#!/usr/bin/python3
"""Chapter 4's evidence on the thesis' own base: BDPT references, Fig. 4.6 (ours against
original at equal mutations and at equal CPU time, with mean path lengths), Figs. 4.8/4.9
(equal-sample crops) and rRMSE against CPU time for the path tracer, BDPT, PSSMLT over the
path tracer, multiplexed MLT "original" and multiplexed MLT "ours".

    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 reference            # BDPT references
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 tune                 # "ours": tuned binning
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 fig46                # equal mutations
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 evt                  # error against CPU time
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 crops                # Figs. 4.8 / 4.9
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 caustic caustic-glass  # light PT cannot build
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 speed                # BDPT vs PT samples/s
    /usr/bin/python3 -m tools.pssmlt.chapter4 --out /tmp/ch4 plot --figures tools/pssmlt/figures

Every step takes scene names (default: all of SCENES) and keeps what it has done in
<out>/<step>/..., so a killed run resumes. `--quick` shrinks everything (16x16, few samples,
one repetition) for the test suite; the full settings are the defaults below.

The methods (all maxDepth 5, the thesis' and pbrt's MLT default):
  pt        integrator_pt (rrDepth 5: no roulette, as the MLT methods)
  bdpt      integrator_bdpt
  pssmlt    integrator_pssmlt mode=pssmlt, classic (PSSMLT over the path tracer)
  original  integrator_pssmlt mode=mmlt, classic: sigma 0.01, large steps 0.3 (the thesis'
            "original", pbrt-v3's MLTIntegrator defaults)
  ours      integrator_pssmlt mode=mmlt, sigma-binning (M = 7, alpha = 4 pi) tuned by tuner_nm
            towards small-step acceptance 0.234 (the plugin's tuning hint), 50 iterations of
            5 mutations per pixel, large steps 0.1 (the thesis' 4.7)
The MLT methods use `--bootstrap` samples per path depth (pbrt-v3's 100000 are sized for
images of a million pixels; at 64x64 they would cost more than the mutations) and 1000 chains.

Time is the CPU time (user + sys) of the whole `host` process from getrusage (the machine is
shared; wall time is not comparable between runs), with --threads 1. Errors are tunetrace's
rRMSE (tools/common/images.py) against the BDPT reference of the same resolution.
"""
import json
import os
import sys

import numpy as np

from tools.common import images  # image reading and the one rRMSE
from tools.tttools import cli, host

ROOT = host.ROOT

SHARED = os.path.normpath(os.path.join(ROOT, '..', 'shared', 'scenes'))
# name -> scene path (relative to the repository root or absolute), what it is for
SCENES = {
    'bathroom': ('scenes/bathroom/scene.json', "the thesis' contemporary bathroom: light through blinds, glass, mirror"),
    'caustic-glass': ('scenes/caustic-glass/scene.json', 'a spot light through a glass object: the focused caustic'),
    'veach-ajar': ('scenes/veach-ajar/scene.json', 'light through a door gap'),
    'cornell-box': (os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box.pbrt'),
                    "pbrt-v4's diffuse Cornell box: the thesis' failure case"),
    'cornell-specular': (os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box-specular.pbrt'),
                         "pbrt-v4's Cornell box with a glass and a metal sphere"),
}
METHODS = ['pt', 'bdpt', 'pssmlt', 'original', 'ours']
LABELS = {'pt': 'path tracer', 'bdpt': 'BDPT', 'pssmlt': 'PSSMLT over PT', 'original': 'MMLT original',
          'ours': 'MMLT ours (tuned binning)'}
DEPTH = 5
TUNED_KEYS = ['sigma'] + [f'a{i}' for i in range(1, 10)] + [f'sigma{i}' for i in range(1, 9)]


def settings(args):
    """Full or quick settings (the test suite runs --quick)."""
    if args.quick:
        return dict(res='16x16', ref_spp=64, tune_iterations=4, tune_spp=2, mpp=[4, 8], reps=2,
                    counts=[1, 2, 4], seeds=1, bootstrap=1000, chains=64, crop_mpp=4)
    return dict(res=args.res, ref_spp=args.ref_spp, tune_iterations=50, tune_spp=5, mpp=args.mpp, reps=args.reps,
                counts=args.counts, seeds=args.seeds, bootstrap=args.bootstrap, chains=1000, crop_mpp=args.crop_mpp)


def scene_path(name):
    p = SCENES[name][0]
    return p if os.path.isabs(p) else os.path.join(ROOT, p)


def host_run(args, scene, extra, out, stats):
    """Runs host; returns (its --stats JSON, CPU seconds of the process)."""
    return host.render(args.host, scene, extra, out=out, stats=stats, res=settings(args)['res'],
                       nice=args.nice)


def load_rows(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return json.load(f)


def save_rows(path, rows):
    tmp = path + '.tmp'
    with open(tmp, 'w') as f:
        json.dump(rows, f, indent=1)
    os.replace(tmp, path)


def method_args(args, name, method):
    """host arguments of a method on a scene (`ours` needs the tune step's result)."""
    s = settings(args)
    d = str(DEPTH)
    mlt = ['--plugin', 'integrator_pssmlt', '--set', f'integrator_pssmlt.maxDepth={d}',
           '--set', f'integrator_pssmlt.bootstrapSamples={s["bootstrap"]}',
           '--set', f'integrator_pssmlt.chains={s["chains"]}']
    if method == 'pt':
        return ['--plugin', 'integrator_pt', '--set', f'integrator_pt.maxDepth={d}', '--set', f'integrator_pt.rrDepth={d}']
    if method == 'bdpt':
        return ['--plugin', 'integrator_bdpt', '--set', f'integrator_bdpt.maxDepth={d}']
    if method == 'pssmlt':
        return mlt + ['--set', 'integrator_pssmlt.mode=pssmlt']
    if method == 'original':
        return mlt + ['--set', 'integrator_pssmlt.mode=mmlt']
    if method == 'ls01':
        return mlt + ['--set', 'integrator_pssmlt.mode=mmlt', '--set', 'integrator_pssmlt.largeStepProbability=0.1']
    if method in ('ours', 'ours-bins'):
        tuned = os.path.join(args.out, 'tune', f'{name}.json' if method == 'ours' else f'{name}_bins.json')
        if not os.path.exists(tuned):
            raise SystemExit(f'{tuned}: missing: run the tune step first')
        with open(tuned) as f:
            sets = json.load(f)['set']
        return mlt + ['--set', 'integrator_pssmlt.mode=mmlt'] + sum((['--set', x] for x in sets), [])
    raise ValueError(method)


# ---- steps ----

def step_reference(args, names):
    """BDPT at --ref-spp (seed 999, both threads): <out>/refs/NAME.exr and NAME.json."""
    s = settings(args)
    d = os.path.join(args.out, 'refs')
    os.makedirs(d, exist_ok=True)
    for name in names:
        exr = os.path.join(d, f'{name}.exr')
        meta = os.path.join(d, f'{name}.json')
        if os.path.exists(exr) and os.path.exists(meta):
            continue
        extra = method_args(args, name, 'bdpt') + ['--spp', str(s['ref_spp']), '--seed', '999',
                                                   '--threads', str(args.ref_threads)]
        st, cpu = host_run(args, scene_path(name), extra, exr, os.path.join(d, f'{name}.stats.json'))
        save_rows(meta, dict(scene=SCENES[name][0], spp=s['ref_spp'], res=s['res'], cpu_s=cpu,
                             command=' '.join(['host', SCENES[name][0], '--res', s['res']] + extra)))
        print(f'reference {name}: {s["ref_spp"]} spp, {cpu:.1f} CPU s', flush=True)


def step_tune(args, names):
    """`ours`: host --plugin integrator_pssmlt --plugin tuner_nm with mode=mmlt and large steps
    0.1; the best configuration as a --set list in <out>/tune/NAME.json."""
    s = settings(args)
    d = os.path.join(args.out, 'tune')
    os.makedirs(d, exist_ok=True)
    for name, variant in [(n, v) for n in names for v in ([''] + (['_bins'] if args.controls else []))]:
        res = os.path.join(d, f'{name}{variant}.json')
        if os.path.exists(res):
            continue
        # _bins (control): the bins only; the other dimensions keep sigma 0.01
        params = ['--tune-params', ','.join([f'a{i}' for i in range(1, 9)] + [f'sigma{i}' for i in range(1, 8)])] \
            if variant else []
        extra = params + ['--plugin', 'integrator_pssmlt', '--plugin', 'tuner_nm', '--iterations', str(s['tune_iterations']),
                 '--tune-spp', str(s['tune_spp']), '--spp', str(s['tune_spp']), '--seed', '1', '--threads', '1',
                 '--set', f'integrator_pssmlt.maxDepth={DEPTH}', '--set', 'integrator_pssmlt.mode=mmlt',
                 '--set', 'integrator_pssmlt.largeStepProbability=0.1',
                 '--set', f'integrator_pssmlt.bootstrapSamples={s["bootstrap"]}',
                 '--set', f'integrator_pssmlt.chains={s["chains"]}']
        st, cpu = host_run(args, scene_path(name), extra, os.path.join(d, f'{name}{variant}.exr'),
                           os.path.join(d, f'{name}{variant}.stats.json'))
        t = st['tuning']
        best = t['best_config']
        keys = ['binning', 'bins', 'largeStepProbability'] + TUNED_KEYS
        sets = ['integrator_pssmlt.mode=mmlt'] + [f'integrator_pssmlt.{k}={best[k]!r}' for k in keys]
        sets = [x.replace('=True', '=true').replace('=False', '=false') for x in sets]
        if best.get('mode') != 'mmlt':
            raise SystemExit(f'{name}: the tuning run was not in mode mmlt: {best.get("mode")!r}')
        save_rows(res, dict(scene=SCENES[name][0], set=sets, best_config=best, best_cost=t['best_cost'],
                            default_cost=t['default_cost'], costs=t['costs'], tuning_ms=t['tuning_ms'], cpu_s=cpu))
        print(f'tune {name}{variant}: |acceptance - 0.234| {t["default_cost"]:.4f} -> {t["best_cost"]:.4f} ({cpu:.1f} CPU s)',
              flush=True)


def render_row(args, name, method, count, seed, d, R):
    """One render of `count` samples (mutations) per pixel; its row."""
    img = os.path.join(d, f'{method}_{count}_{seed}.exr')
    extra = method_args(args, name, method) + ['--spp', str(count), '--seed', str(seed), '--threads', '1']
    st, cpu = host_run(args, scene_path(name), extra, img, os.path.join(d, f'{method}_{count}_{seed}.json'))
    m = st.get('metrics', {})
    row = dict(scene=name, method=method, count=count, seed=seed, cpu_s=cpu,
               rrmse=images.rrmse(images.read_luminance(img), R), render_ms=st['render_ms'],
               rays=st.get('rays'), samples=st.get('samples'))
    for k in ('small_step_acceptance', 'mean_path_length', 'rays_per_mutation', 'bootstrap_ms'):
        if k in m:
            row[k] = m[k]
    if not args.keep_images:
        os.remove(img)
        png = os.path.splitext(img)[0] + '.png'
        if os.path.exists(png):
            os.remove(png)
    return row


def reference_of(args, name):
    p = os.path.join(args.out, 'refs', f'{name}.exr')
    if not os.path.exists(p):
        raise SystemExit(f'{p}: missing: run the reference step first')
    return images.read_luminance(p)


def step_runs(args, names, step, methods, counts, seeds):
    """Renders methods x counts x seeds per scene; rows in <out>/<step>/NAME.json."""
    for name in names:
        d = os.path.join(args.out, step, name)
        os.makedirs(d, exist_ok=True)
        resf = os.path.join(args.out, step, f'{name}.json')
        rows = load_rows(resf)
        done = {(r['method'], r['count'], r['seed']) for r in rows}
        R = reference_of(args, name)
        for seed in seeds:
            for count in counts:
                for m in methods:
                    if (m, count, seed) in done:
                        continue
                    row = render_row(args, name, m, count, seed, d, R)
                    rows.append(row)
                    save_rows(resf, rows)
                    print(f'{step} {name:16s} {m:8s} {count:4d}/px seed {seed}: rRMSE {row["rrmse"]:.4f} '
                          f'cpu {row["cpu_s"]:.2f} s', flush=True)


CONTROLS = ['ls01', 'ours-bins']
LABELS.update({'ls01': 'MMLT classic, large steps 0.1', 'ours-bins': 'MMLT, only the bins tuned (sigma 0.01)'})


def step_fig46(args, names):
    s = settings(args)
    step_runs(args, names, 'fig46', ['original', 'ours'], s['mpp'], range(1, s['reps'] + 1))
    if args.controls:  # the controls at the first mutation count: what makes "ours" differ
        step_runs(args, names, 'fig46', CONTROLS, s['mpp'][:1], range(1, s['reps'] + 1))


def step_evt(args, names):
    s = settings(args)
    counts = s['counts']
    for m in args.methods.split(','):
        # PT and BDPT also at 2x and 4x the largest count, so their curves span the MLT methods' time
        c = counts + ([2 * counts[-1], 4 * counts[-1]] if m in ('pt', 'bdpt') else [])
        step_runs(args, names, 'evt', [m], c, range(1, s['seeds'] + 1))


def step_crops(args, names):
    """Equal-sample renders (crop_mpp, seed 1) of ours and original, kept as EXR."""
    s = settings(args)
    for name in names:
        d = os.path.join(args.out, 'crops', name)
        os.makedirs(d, exist_ok=True)
        for m in ('original', 'ours'):
            img = os.path.join(d, f'{m}.exr')
            if os.path.exists(img):
                continue
            extra = method_args(args, name, m) + ['--spp', str(s['crop_mpp']), '--seed', '1', '--threads', '1']
            host_run(args, scene_path(name), extra, img, os.path.join(d, f'{m}.json'))


def step_caustic(args, names):
    """Is the focused caustic there? On each scene (meant for caustic-glass): a long path-traced
    render (pt at 4096 spp, seed 7) defines the light the path tracer cannot build: the pixels
    where the BDPT reference is more than 1.5x the path tracer's (and above 1% of the
    reference's 99th percentile). Every method renders once at `--caustic-count` samples resp.
    mutations per pixel; <out>/caustic/NAME.json gets, per method, the light in those pixels
    relative to the reference's (1: all of it, 0: none) and the CPU time."""
    quick = args.quick
    if quick:
        args.caustic_count = min(args.caustic_count, 8)
    d0 = os.path.join(args.out, 'caustic')
    for name in names:
        d = os.path.join(d0, name)
        os.makedirs(d, exist_ok=True)
        resf = os.path.join(d0, f'{name}.json')
        R = images.read_luminance(os.path.join(args.out, 'refs', f'{name}.exr'))
        runs = [('pt', 64 if quick else 4096, 7)] + [(m, args.caustic_count, 1) for m in METHODS]
        cpu = {}
        for m, count, seed in runs:
            img = os.path.join(d, f'{m}_{count}_{seed}.exr')
            if not os.path.exists(img):
                extra = method_args(args, name, m) + ['--spp', str(count), '--seed', str(seed), '--threads', '1']
                _, cpu[(m, count)] = host_run(args, scene_path(name), extra, img, os.path.join(d, f'{m}_{count}_{seed}.json'))
            else:
                cpu[(m, count)] = None
        P = images.read_luminance(os.path.join(d, f'pt_{runs[0][1]}_7.exr'))
        mask = (R > 1.5 * P) & (R > 0.01 * np.percentile(R, 99))
        out = dict(scene=name, pixels=int(mask.sum()), count=args.caustic_count, pt_long_spp=runs[0][1],
                   reference_light_in_mask=float(R[mask].sum()), pt_long_fraction=float(P[mask].sum() / max(R[mask].sum(), 1e-30)),
                   methods={})
        for m in METHODS:
            L = images.read_luminance(os.path.join(d, f'{m}_{args.caustic_count}_1.exr'))
            st = load_rows(os.path.join(d, f'{m}_{args.caustic_count}_1.json'))
            out['methods'][m] = dict(fraction=float(L[mask].sum() / max(R[mask].sum(), 1e-30)),
                                     rrmse_in_mask=float(np.sqrt(np.mean((L[mask] - R[mask]) ** 2 / (R[mask] ** 2 + images.RRMSE_EPS))))
                                     if mask.any() else None,
                                     render_ms=st.get('render_ms'), cpu_s=cpu.get((m, args.caustic_count)))
        prev = load_rows(resf) if os.path.exists(resf) else {}
        for m, v in out['methods'].items():  # keep the CPU time of the run that rendered it
            if v['cpu_s'] is None and isinstance(prev, dict):
                v['cpu_s'] = prev.get('methods', {}).get(m, {}).get('cpu_s')
        save_rows(resf, out)
        print(f'caustic {name}: {out["pixels"]} pixels hold light the path tracer cannot build (long PT has '
              f'{100 * out["pt_long_fraction"]:.0f}% of it); at {args.caustic_count}/px: ' +
              ', '.join(f'{m} {100 * v["fraction"]:.0f}%' for m, v in out['methods'].items()), flush=True)


def step_speed(args, names):
    """BDPT's samples per second against the path tracer's, interleaved rounds of the same
    number of samples with the render's own CPU clock (host --clock cpu), one thread:
    <out>/speed/NAME.json rows with samples/s and rays per sample."""
    spp = 2 if args.quick else 16
    rounds = 1 if args.quick else 3
    d = os.path.join(args.out, 'speed')
    os.makedirs(d, exist_ok=True)
    for name in names:
        resf = os.path.join(d, f'{name}.json')
        rows = load_rows(resf)
        for k in range(len({r['round'] for r in rows}), rounds):
            for m in ('pt', 'bdpt'):
                extra = method_args(args, name, m) + ['--spp', str(spp), '--seed', str(k + 1), '--threads', '1',
                                                      '--clock', 'cpu']
                st, cpu = host_run(args, scene_path(name), extra, os.path.join(d, f'{name}_{m}.exr'),
                                   os.path.join(d, f'{name}_{m}.stats.json'))
                rows.append(dict(scene=name, method=m, round=k, samples=st['samples'], render_cpu_ms=st['render_ms'],
                                 rays=st['rays'], samples_per_s=st['samples'] / (st['render_ms'] * 1e-3),
                                 rays_per_sample=st['rays'] / st['samples']))
            save_rows(resf, rows)
        med = {m: float(np.median([r['samples_per_s'] for r in rows if r['method'] == m])) for m in ('pt', 'bdpt')}
        rps = {m: float(np.median([r['rays_per_sample'] for r in rows if r['method'] == m])) for m in ('pt', 'bdpt')}
        print(f'speed {name:16s} samples/s PT {med["pt"]:.0f} BDPT {med["bdpt"]:.0f} (PT / BDPT {med["pt"] / med["bdpt"]:.2f}x); '
              f'rays per sample PT {rps["pt"]:.1f} BDPT {rps["bdpt"]:.1f}', flush=True)


# ---- analysis ----

def curve(rows, method):
    """(count, median CPU s, median rRMSE, n) per count of a method."""
    pts = []
    for c in sorted({r['count'] for r in rows if r['method'] == method}):
        rs = [r for r in rows if r['method'] == method and r['count'] == c]
        pts.append((c, float(np.median([r['cpu_s'] for r in rs])), float(np.median([r['rrmse'] for r in rs])), len(rs)))
    return pts


def at_time(pts, t):
    """log-log interpolation of rRMSE at CPU time t; None outside the measured range."""
    if len(pts) < 2:
        return None
    x = np.log([p[1] for p in pts])
    y = np.log([p[2] for p in pts])
    o = np.argsort(x)
    x, y = x[o], y[o]
    lt = np.log(t)
    if lt < x[0] or lt > x[-1]:
        return None
    return float(np.exp(np.interp(lt, x, y)))


def ours_vs_original_equal_time(rows):
    """Fig. 4.6 at equal CPU time: per seed and per count of `original`, ours' rRMSE at
    original's CPU time (log-log interpolation along ours' curve of the same seed, no
    extrapolation) relative to original's: (ours - original) / original."""
    out = []
    for seed in sorted({r['seed'] for r in rows}):
        o = sorted([r for r in rows if r['method'] == 'original' and r['seed'] == seed], key=lambda r: r['count'])
        u = [(r['count'], r['cpu_s'], r['rrmse']) for r in rows if r['method'] == 'ours' and r['seed'] == seed]
        for r in o:
            v = at_time(sorted(u), r['cpu_s'])
            if v is not None:
                out.append(dict(seed=seed, count=r['count'], cpu_s=r['cpu_s'], original=r['rrmse'], ours=v,
                                rel_diff=(v - r['rrmse']) / r['rrmse']))
    return out


RATIOS = [('bdpt', 'pt'), ('original', 'pt'), ('original', 'bdpt'), ('original', 'pssmlt'), ('ours', 'original')]


def pair_ratio(a, b):
    """rRMSE of curve a over curve b at equal CPU time: at 4 log-spaced times over the range
    both curves cover (interpolated, no extrapolation); None without an overlap."""
    if not a or not b:
        return None
    lo, hi = max(a[0][1], b[0][1]), min(a[-1][1], b[-1][1])
    if not hi > lo:
        return None
    ts = np.geomspace(lo, hi, 4)
    r = [at_time(a, t) / at_time(b, t) for t in ts]
    return dict(cpu_s=[float(t) for t in ts], ratio=[float(x) for x in r])


def summarize(args, names):
    """Fig. 4.6 and equal-time tables as a dict (also written to <out>/summary.json)."""
    out = {'scenes': {}}
    for name in names:
        sc = {}
        rows = load_rows(os.path.join(args.out, 'fig46', f'{name}.json'))
        eq = []
        for c in sorted({r['count'] for r in rows}):
            by = {m: {r['seed']: r for r in rows if r['method'] == m and r['count'] == c} for m in ('original', 'ours')}
            seeds = sorted(set(by['original']) & set(by['ours']))
            if not seeds:
                continue
            rel = [(by['ours'][k]['rrmse'] - by['original'][k]['rrmse']) / by['original'][k]['rrmse'] for k in seeds]
            e = dict(mpp=c, reps=len(seeds), rel_diff=rel, rel_diff_median=float(np.median(rel)))
            for m in ('original', 'ours'):
                rs = [by[m][k] for k in seeds]
                e[m] = {k: float(np.median([r[k] for r in rs])) for k in
                        ('rrmse', 'cpu_s', 'mean_path_length', 'rays_per_mutation', 'small_step_acceptance')
                        if all(k in r for r in rs)}
            for m in CONTROLS:
                cs = {r['seed']: r for r in rows if r['method'] == m and r['count'] == c}
                ks = sorted(set(cs) & set(by['original']))
                if ks:
                    rel_c = [(cs[k]['rrmse'] - by['original'][k]['rrmse']) / by['original'][k]['rrmse'] for k in ks]
                    e[m] = dict(rrmse=float(np.median([cs[k]['rrmse'] for k in ks])), rel_diff=rel_c,
                                rel_diff_median=float(np.median(rel_c)),
                                small_step_acceptance=float(np.median([cs[k].get('small_step_acceptance', 0) for k in ks])))
            eq.append(e)
        sc['equal_mutations'] = eq
        erows = load_rows(os.path.join(args.out, 'evt', f'{name}.json'))
        curves = {m: curve(erows, m) for m in METHODS if any(r['method'] == m for r in erows)}
        sc['curves'] = curves
        # equal CPU time: at times every method's curve covers
        lo = max((p[0][1] for p in curves.values() if p), default=None)
        hi = min((p[-1][1] for p in curves.values() if p), default=None)
        table = []
        if lo and hi and hi > lo:
            for t in np.geomspace(lo, hi, 4):
                table.append(dict(cpu_s=float(t), **{m: at_time(p, t) for m, p in curves.items()}))
        sc['equal_time'] = table
        sc['ours_vs_original_equal_time'] = ours_vs_original_equal_time(erows)
        sc['ratios'] = {f'{a}/{b}': pair_ratio(curves.get(a), curves.get(b)) for a, b in RATIOS}
        tf = os.path.join(args.out, 'tune', f'{name}.json')
        if os.path.exists(tf):
            with open(tf) as f:
                t = json.load(f)
            sc['tuning'] = dict(cpu_s=t['cpu_s'], default_cost=t['default_cost'], best_cost=t['best_cost'], set=t['set'])
        cf = os.path.join(args.out, 'caustic', f'{name}.json')
        if os.path.exists(cf):
            with open(cf) as f:
                sc['caustic'] = json.load(f)
        srows = load_rows(os.path.join(args.out, 'speed', f'{name}.json'))
        if srows:
            sc['speed'] = {m: dict(samples_per_s=float(np.median([r['samples_per_s'] for r in srows if r['method'] == m])),
                                   rays_per_sample=float(np.median([r['rays_per_sample'] for r in srows if r['method'] == m])))
                           for m in ('pt', 'bdpt')}
        out['scenes'][name] = sc
    return out


def step_plot(args, names):
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    summ = summarize(args, names)
    figs = args.figures or os.path.join(args.out, 'figures')
    os.makedirs(figs, exist_ok=True)
    with open(os.path.join(figs, 'ch4_summary.json'), 'w') as f:
        json.dump(summ, f, indent=1)
    # Fig. 4.6: relative rRMSE differences ours vs original per scene and mutation count
    data, labels = [], []
    colors = []
    short = {'ls01': 'classic, large\nsteps 0.1', 'ours-bins': 'bins only\ntuned'}
    for name in names:
        for e in summ['scenes'][name]['equal_mutations']:
            data.append(100.0 * np.array(e['rel_diff']))
            labels.append(f'{name}\n{e["mpp"]} mpp')
            colors.append('C0')
            for m in CONTROLS:
                if m in e:
                    data.append(100.0 * np.array(e[m]['rel_diff']))
                    labels.append(f'{name}\n{short[m]}')
                    colors.append('C7')
    tdata, tlabels = [], []
    for name in names:
        et = summ['scenes'][name]['ours_vs_original_equal_time']
        if et:
            tdata.append(100.0 * np.array([e['rel_diff'] for e in et]))
            tlabels.append(f'{name}\n{len(et)} pts')
    if data:
        fig, axs = plt.subplots(1, 2, figsize=(max(4, 1.0 * len(data)) + max(2.5, 1.1 * len(tdata)), 4.2), dpi=90,
                                gridspec_kw=dict(width_ratios=[max(1, len(data)), max(1, len(tdata))]))
        ax = axs[0]
        bp = ax.boxplot(data, labels=labels, showfliers=True, patch_artist=True)
        for box, c in zip(bp['boxes'], colors):
            box.set_facecolor('white' if c == 'C0' else '0.85')
        ax.axhline(0, color='k', lw=0.8)
        ax.set_ylabel('rRMSE: (ours - original) / original  [%]')
        ax.set_title('Fig. 4.6 on MMLT: tuned sigma-binning ("ours") vs classic ("original"), equal mutations\n'
                     '(below 0: ours better; grey: controls)', fontsize=8)
        ax.tick_params(axis='x', labelsize=6)
        ax = axs[1]
        if tdata:
            ax.boxplot(tdata, labels=tlabels, showfliers=True)
            ax.axhline(0, color='k', lw=0.8)
        ax.set_title('equal CPU time (ours interpolated at\noriginal\'s CPU s, per seed and count)', fontsize=8)
        ax.tick_params(axis='x', labelsize=6)
        fig.tight_layout()
        fig.savefig(os.path.join(figs, 'ch4_fig46.png'))
        plt.close(fig)
    # error against CPU time, one panel per scene
    present = [n for n in names if summ['scenes'][n]['curves']]
    if present:
        cols = min(3, len(present))
        rows_ = (len(present) + cols - 1) // cols
        fig, axes = plt.subplots(rows_, cols, figsize=(3.6 * cols, 3.0 * rows_), dpi=90, squeeze=False)
        for ax, name in zip(axes.flat, present):
            for i, (m, pts) in enumerate(summ['scenes'][name]['curves'].items()):
                ax.loglog([p[1] for p in pts], [p[2] for p in pts], 'o-', ms=3, color=f'C{METHODS.index(m)}',
                          label=LABELS[m])
            ax.set_title(name, fontsize=9)
            ax.set_xlabel('CPU s (1 thread, whole process)', fontsize=7)
            ax.set_ylabel('rRMSE vs BDPT reference', fontsize=7)
            ax.tick_params(which='both', labelsize=6)
            ax.grid(True, which='both', lw=0.3)
        for ax in list(axes.flat)[len(present):]:
            ax.axis('off')
        axes.flat[0].legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(os.path.join(figs, 'ch4_error_vs_time.png'))
        plt.close(fig)
    # the same, one chart per scene (what a user picks an integrator by)
    for name in present:
        fig, ax = plt.subplots(figsize=(4.6, 3.4), dpi=100)
        for m, pts in summ['scenes'][name]['curves'].items():
            ax.loglog([p[1] for p in pts], [p[2] for p in pts], 'o-', ms=3, color=f'C{METHODS.index(m)}', label=LABELS[m])
        ax.set_title(f'{name}: rRMSE against CPU time ({settings(args)["res"]}, maxDepth {DEPTH})', fontsize=8)
        ax.set_xlabel('CPU s (1 thread, whole process: load, bootstrap, render)', fontsize=7)
        ax.set_ylabel('rRMSE vs BDPT reference (median of seeds)', fontsize=7)
        ax.tick_params(which='both', labelsize=6)
        ax.grid(True, which='both', lw=0.3)
        ax.legend(fontsize=6)
        fig.tight_layout()
        fig.savefig(os.path.join(figs, f'ch4_error_vs_time_{name}.png'))
        plt.close(fig)
    # Figs. 4.8 / 4.9: crops, reference / original / ours, same exposure
    for name in names:
        d = os.path.join(args.out, 'crops', name)
        ref = os.path.join(args.out, 'refs', f'{name}.exr')
        if not (os.path.exists(os.path.join(d, 'ours.exr')) and os.path.exists(ref)):
            continue
        imgs = [images.read_rgb(p) for p in (ref, os.path.join(d, 'original.exr'), os.path.join(d, 'ours.exr'))]
        scale = 1.0 / max(1e-6, float(np.percentile(images.luminance(imgs[0]), 99)))
        fig, axes = plt.subplots(1, 3, figsize=(7.5, 2.8), dpi=110)
        R = images.luminance(imgs[0])
        for ax, im, t in zip(axes, imgs, ['BDPT reference', 'MMLT original', 'MMLT ours']):
            disp = np.clip((im * scale) ** (1 / 2.2), 0, 1)
            ax.imshow(disp, interpolation='nearest')
            err = '' if t.startswith('BDPT') else f'\nrRMSE {images.rrmse(images.luminance(im), R):.3f}'
            ax.set_title(t + err, fontsize=7)
            ax.axis('off')
        fig.suptitle(f'{name}: equal mutations ({settings(args)["crop_mpp"]} per pixel)', fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(figs, f'ch4_crops_{name}.png'))
        plt.close(fig)
    # the focused caustic: reference, long path tracer, every method at the same count
    for name in names:
        c = summ['scenes'][name].get('caustic')
        if not c:
            continue
        d = os.path.join(args.out, 'caustic', name)
        panels = [('BDPT reference', os.path.join(args.out, 'refs', f'{name}.exr'))]
        panels.append((f'path tracer {c["pt_long_spp"]} spp\n{100 * c["pt_long_fraction"]:.0f}% of the caustic',
                       os.path.join(d, f'pt_{c["pt_long_spp"]}_7.exr')))
        panels += [(f'{LABELS[m]}\n{c["count"]}/px: {100 * c["methods"][m]["fraction"]:.0f}%', os.path.join(d, f'{m}_{c["count"]}_1.exr'))
                   for m in METHODS]
        ims = [images.read_rgb(p) for _, p in panels]
        R = images.luminance(ims[0])
        P = images.luminance(ims[1])
        mask = (R > 1.5 * P) & (R > 0.01 * np.percentile(R, 99))
        scale = 1.0 / max(1e-6, float(np.percentile(R, 99)))
        fig, axes = plt.subplots(1, len(panels), figsize=(1.7 * len(panels), 2.2), dpi=110)
        for ax, (t, _), im in zip(axes, panels, ims):
            ax.imshow(np.clip((im * scale) ** (1 / 2.2), 0, 1), interpolation='nearest')
            ax.contour(mask.astype(float), levels=[0.5], colors='r', linewidths=0.5)
            ax.set_title(t, fontsize=5.5)
            ax.axis('off')
        fig.suptitle(f'{name}: light the path tracer cannot build (red outline: reference > 1.5x a long path-traced '
                     f'render); % = light inside the outline relative to the reference', fontsize=6)
        fig.tight_layout()
        fig.savefig(os.path.join(figs, f'ch4_caustic_{name}.png'))
        plt.close(fig)
    print_tables(summ)
    with open(os.path.join(figs, 'ch4_tables.md'), 'w') as f:
        f.write(markdown_tables(summ) + '\n')


def markdown_tables(summ):
    """The README's tables: Fig. 4.6 (equal mutations), equal CPU time, speed."""
    out = ['| scene | mut./px | reps | rRMSE original | rRMSE ours | (ours - original) / original, median (min..max) | '
           'CPU s orig. / ours | path length orig. / ours | small-step acceptance orig. / ours |',
           '|---|---|---|---|---|---|---|---|---|']
    for name, sc in summ['scenes'].items():
        for e in sc['equal_mutations']:
            o, u, r = e['original'], e['ours'], e['rel_diff']
            out.append(f'| {name} | {e["mpp"]} | {e["reps"]} | {o["rrmse"]:.3f} | {u["rrmse"]:.3f} | '
                       f'{100 * e["rel_diff_median"]:+.0f}% ({100 * min(r):+.0f}..{100 * max(r):+.0f}%) | '
                       f'{o["cpu_s"]:.2f} / {u["cpu_s"]:.2f} | {o["mean_path_length"]:.2f} / {u["mean_path_length"]:.2f} | '
                       f'{o["small_step_acceptance"]:.2f} / {u["small_step_acceptance"]:.2f} |')
    ctl = [(n, e) for n, sc in summ['scenes'].items() for e in sc['equal_mutations'] if any(m in e for m in CONTROLS)]
    if ctl:
        out += ['', '| scene | mut./px | ' + ' | '.join(f'{LABELS[m]}: rRMSE, vs original (acceptance)' for m in CONTROLS) + ' |',
                '|---|---|' + '---|' * len(CONTROLS)]
        for n, e in ctl:
            cells = [f'{e[m]["rrmse"]:.3f}, {100 * e[m]["rel_diff_median"]:+.0f}% ({e[m]["small_step_acceptance"]:.2f})'
                     if m in e else '-' for m in CONTROLS]
            out.append(f'| {n} | {e["mpp"]} | ' + ' | '.join(cells) + ' |')
    et = [(n, sc['ours_vs_original_equal_time']) for n, sc in summ['scenes'].items() if sc.get('ours_vs_original_equal_time')]
    if et:
        out += ['', '| scene | points (seeds x counts) | (ours - original) / original at equal CPU time, median (min..max) | '
                'ours better | tuning CPU s (not included) |', '|---|---|---|---|---|']
        for n, rows in et:
            r = [x['rel_diff'] for x in rows]
            tune = summ['scenes'][n].get('tuning', {}).get('cpu_s')
            out.append(f'| {n} | {len(r)} | {100 * float(np.median(r)):+.0f}% ({100 * min(r):+.0f}..{100 * max(r):+.0f}%) | '
                       f'{sum(x < 0 for x in r)}/{len(r)} | {"-" if tune is None else f"{tune:.1f}"} |')
    out += ['', '| scene | CPU s | ' + ' | '.join(LABELS[m] for m in METHODS) + ' |',
            '|---|---|' + '---|' * len(METHODS)]
    for name, sc in summ['scenes'].items():
        for row in sc['equal_time']:
            vals = [row.get(m) for m in METHODS]
            best = min(v for v in vals if v is not None) if any(v is not None for v in vals) else None
            cells = [('-' if v is None else (f'**{v:.3f}**' if v == best else f'{v:.3f}')) for v in vals]
            out.append(f'| {name} | {row["cpu_s"]:.2f} | ' + ' | '.join(cells) + ' |')
    out += ['', '| scene | ' + ' | '.join(f'{LABELS[a]} / {LABELS[b]}' for a, b in RATIOS) + ' |',
            '|---|' + '---|' * len(RATIOS)]
    for name, sc in summ['scenes'].items():
        cells = []
        for a, b in RATIOS:
            v = sc.get('ratios', {}).get(f'{a}/{b}')
            cells.append('-' if not v else f'{v["ratio"][0]:.2f} .. {v["ratio"][-1]:.2f} ({v["cpu_s"][0]:.2f}-{v["cpu_s"][-1]:.2f} s)')
        out.append(f'| {name} | ' + ' | '.join(cells) + ' |')
    ca = [(n, sc['caustic']) for n, sc in summ['scenes'].items() if 'caustic' in sc]
    if ca:
        out += ['', '| scene | pixels | count/px | path tracer, long render | ' + ' | '.join(LABELS[m] for m in METHODS) + ' |',
                '|---|---|---|---|' + '---|' * len(METHODS)]
        for n, c in ca:
            cells = [f'{100 * c["methods"][m]["fraction"]:.0f}%' + (f' ({c["methods"][m]["cpu_s"]:.1f} s)'
                     if c['methods'][m].get('cpu_s') else '') for m in METHODS]
            out.append(f'| {n} | {c["pixels"]} | {c["count"]} | {100 * c["pt_long_fraction"]:.0f}% ({c["pt_long_spp"]} spp) | ' + ' | '.join(cells) + ' |')
    sp = [(n, sc['speed']) for n, sc in summ['scenes'].items() if 'speed' in sc]
    if sp:
        out += ['', '| scene | PT samples/s | BDPT samples/s | PT / BDPT | rays per sample PT / BDPT |', '|---|---|---|---|---|']
        for n, v in sp:
            out.append(f'| {n} | {v["pt"]["samples_per_s"]:.0f} | {v["bdpt"]["samples_per_s"]:.0f} | '
                       f'{v["pt"]["samples_per_s"] / v["bdpt"]["samples_per_s"]:.2f}x | '
                       f'{v["pt"]["rays_per_sample"]:.1f} / {v["bdpt"]["rays_per_sample"]:.1f} |')
    return '\n'.join(out)


def print_tables(summ):
    for name, sc in summ['scenes'].items():
        for e in sc['equal_mutations']:
            o, u = e['original'], e['ours']
            print(f'{name:16s} {e["mpp"]:4d} mpp x{e["reps"]}: rRMSE original {o.get("rrmse", 0):.4f} ours '
                  f'{u.get("rrmse", 0):.4f} (median rel. diff {100 * e["rel_diff_median"]:+.1f}%), CPU s '
                  f'{o.get("cpu_s", 0):.2f} / {u.get("cpu_s", 0):.2f}, path length {o.get("mean_path_length", 0):.2f} / '
                  f'{u.get("mean_path_length", 0):.2f}, acceptance {o.get("small_step_acceptance", 0):.3f} / '
                  f'{u.get("small_step_acceptance", 0):.3f}')
        for row in sc['equal_time']:
            vals = ' '.join(f'{m} {v:.4f}' if v else f'{m} -' for m, v in row.items() if m != 'cpu_s')
            print(f'{name:16s} at {row["cpu_s"]:.2f} CPU s: {vals}')


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('step', choices=['reference', 'tune', 'fig46', 'evt', 'crops', 'caustic', 'speed', 'plot', 'all'])
    ap.add_argument('scenes', nargs='*', help='scene names (default: all): ' + ', '.join(SCENES))
    ap.add_argument('--out', default='/tmp/tt_chapter4')
    ap.add_argument('--figures', default=None, help='folder of the figures and summary (default <out>/figures)')
    ap.add_argument('--res', default='64x64')
    ap.add_argument('--ref-spp', type=int, default=4096)
    ap.add_argument('--ref-threads', type=int, default=2)
    ap.add_argument('--reps', type=int, default=5, help='fig46: repetitions (seeds) per mutation count')
    ap.add_argument('--mpp', type=int, nargs='+', default=[100, 200], help='fig46: mutations per pixel')
    ap.add_argument('--counts', type=int, nargs='+', default=[4, 16, 64, 128],
                    help='evt: samples resp. mutations per pixel (PT and BDPT also 2x and 4x the largest)')
    ap.add_argument('--seeds', type=int, default=3, help='evt: seeds per count')
    ap.add_argument('--crop-mpp', type=int, default=200, help='crops: mutations per pixel')
    ap.add_argument('--caustic-count', type=int, default=128, help='caustic: samples resp. mutations per pixel')
    ap.add_argument('--bootstrap', type=int, default=20000, help='MLT bootstrap samples (per depth in mmlt)')
    ap.add_argument('--methods', default=','.join(METHODS), help='evt: which methods')
    ap.add_argument('--nice', type=int, default=5)
    ap.add_argument('--keep-images', action='store_true')
    ap.add_argument('--quick', action='store_true', help='tiny settings for the test suite')
    ap.add_argument('--controls', action='store_true',
                    help='tune and fig46: also the controls (classic with large steps 0.1; only the bins tuned)')
    args = ap.parse_args(argv)
    names = args.scenes or list(SCENES)
    for n in names:
        if n not in SCENES:
            ap.error(f'unknown scene {n!r} (known: {", ".join(SCENES)})')
    args.host = host.find(args.host)
    steps = ['reference', 'tune', 'fig46', 'evt', 'crops', 'caustic', 'speed', 'plot'] if args.step == 'all' else [args.step]
    for st in steps:
        globals()['step_' + st](args, names)
    return 0


if __name__ == '__main__':
    sys.exit(main())
