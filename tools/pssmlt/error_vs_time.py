"""rRMSE against CPU time (equal-time comparison): the path tracer, classic PSSMLT, binned
PSSMLT tuned towards small-step acceptance 0.234 and binned PSSMLT tuned towards rRMSE
(`host --objective rrmse`), each rendered at increasing samples resp. mutations per pixel.

    /usr/bin/python3 -m tools.pssmlt.error_vs_time --host build-h3/host/host --res 96x96 --mpp 4 8 16 32 64 128 \
        --seeds 3 --ref /tmp/cmp/cornell-box/reference.exr \
        --tuned acc=/tmp/tune/cornell-box_tuned.json --tuned rrmse=/tmp/tune_rrmse/cornell-box_tuned.json \
        --out /tmp/evt --fig tools/pssmlt/figures/error_vs_time_cornell-box.png \
        cornell-box=scenes/cornell-box/scene.json

Time is the CPU time (user + sys) of the whole `host` process (scene loading, BVH build,
PSSMLT's bootstrap and the passes), taken from getrusage of the child: the machine is shared
with other jobs, so wall times are contended and not comparable between runs, while CPU time
counts only the work of the process. Runs use --threads 1 (no idle-spin or scheduling cost of
a thread pool in the figure). Each method's curve is the median over seeds of rRMSE and of
CPU time at each sample count; the equal-time table interpolates log rRMSE linearly in
log CPU time between those medians (no extrapolation). Results: <out>/<name>/evt.json
(appended per run, so a killed batch resumes), the figure and the table on stdout.
"""
import json
import os
import sys

import numpy as np

from tools.common import images
from tools.tttools import cli, figures, host

LABELS = {'pt': 'path tracer', 'classic': 'PSSMLT classic', 'acc': 'binned, acceptance-tuned',
          'rrmse': 'binned, rRMSE-tuned', 'rrmse200': 'binned, rRMSE-tuned (200 it.)',
          'split': 'binned, one direction sigma (control)'}


def methods_for(args):
    d = str(args.depth)
    pt = ['--plugin', 'integrator_pt', '--set', f'integrator_pt.maxDepth={d}', '--set', f'integrator_pt.rrDepth={d}']
    mlt = ['--plugin', 'integrator_pssmlt', '--set', f'integrator_pssmlt.maxDepth={d}']
    m = {'pt': (pt, 'spp'), 'classic': (mlt, 'mpp')}
    for spec in args.tuned:
        key, path = spec.split('=', 1)
        with open(path) as f:
            sets = json.load(f)['set']
        m[key] = (mlt + sum((['--set', s] for s in sets), []), 'mpp')
    return m


def do_scene(args, name, scene):
    exe = host.find(args.host)
    kw = dict(res=args.res, threads=args.threads, nice=args.nice)
    out = os.path.join(args.out, name)
    os.makedirs(out, exist_ok=True)
    R = images.read_luminance(args.ref)
    methods = methods_for(args)
    resf = os.path.join(out, 'evt.json')
    rows = json.load(open(resf)) if os.path.exists(resf) else []
    done = {(r['method'], r['seed'], r['mpp']) for r in rows}
    for seed in range(1, args.seeds + 1):
        for mpp in args.mpp:
            for m in args.methods.split(','):
                if (m, seed, mpp) in done or m not in methods:
                    continue
                extra, _ = methods[m]
                img = os.path.join(out, f'{m}_{mpp}_{seed}.exr')
                st, cpu = host.render(exe, scene, extra + ['--spp', str(mpp), '--seed', str(seed)],
                                      out=img, stats=os.path.join(out, f'{m}_{mpp}_{seed}.json'), **kw)
                row = dict(method=m, seed=seed, mpp=mpp, rrmse=images.rrmse(images.read_luminance(img), R), cpu_s=cpu,
                           render_ms=st['render_ms'], build_ms=st.get('build_ms'))
                rows.append(row)
                with open(resf, 'w') as f:
                    json.dump(rows, f, indent=1)
                print(f'{name:14s} {m:8s} {mpp:4d}/px seed {seed}: rRMSE {row["rrmse"]:.4f} cpu {cpu:.2f} s '
                      f'render {row["render_ms"]:.0f} ms', flush=True)
    return rows


def curve(rows, m):
    """(mpp, median CPU s, median rRMSE) per sample count of method m."""
    pts = []
    for mpp in sorted({r['mpp'] for r in rows if r['method'] == m}):
        rs = [r for r in rows if r['method'] == m and r['mpp'] == mpp]
        pts.append((mpp, float(np.median([r['cpu_s'] for r in rs])), float(np.median([r['rrmse'] for r in rs])),
                    len(rs)))
    return pts


def at_time(pts, t):
    """log-log interpolation of rRMSE at CPU time t; None outside the measured range."""
    x = np.log([p[1] for p in pts])
    y = np.log([p[2] for p in pts])
    order = np.argsort(x)
    x, y = x[order], y[order]
    lt = np.log(t)
    if len(x) < 2 or lt < x[0] or lt > x[-1]:
        return None
    return float(np.exp(np.interp(lt, x, y)))


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scene', help='NAME=PATH')
    ap.add_argument('--res', default='96x96')
    ap.add_argument('--threads', type=int, default=1)
    ap.add_argument('--nice', type=int, default=5)
    ap.add_argument('--depth', type=int, default=5)
    ap.add_argument('--mpp', type=int, nargs='+', default=[4, 8, 16, 32, 64, 128])
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--methods', default='pt,classic,acc,rrmse')
    ap.add_argument('--tuned', action='append', default=[], help='KEY=tuned.json (tune_convergence.py output)')
    ap.add_argument('--ref', required=True, help='evaluation reference (EXR)')
    ap.add_argument('--times', type=float, nargs='*', default=None, help='CPU seconds of the equal-time table')
    ap.add_argument('--out', default='/tmp/pssmlt_evt')
    ap.add_argument('--fig', default=None)
    ap.add_argument('--plot-only', action='store_true')
    args = ap.parse_args(argv)
    name, path = args.scene.split('=', 1)
    if args.plot_only:
        rows = json.load(open(os.path.join(args.out, name, 'evt.json')))
    else:
        rows = do_scene(args, name, path)
    ms = [m for m in LABELS if any(r['method'] == m for r in rows)]
    curves = {m: curve(rows, m) for m in ms}
    print(f'\n{name}: medians over seeds')
    mpps = sorted({p[0] for c in curves.values() for p in c})
    print('| method | ' + ' | '.join(f'{k}/px' for k in mpps) + ' |')
    print('|---|' + '---|' * len(mpps))
    for m in ms:
        byk = {p[0]: p for p in curves[m]}
        print(f'| {LABELS[m]} | ' + ' | '.join(f'{byk[k][2]:.3f} @ {byk[k][1]:.2f} s' if k in byk else '-'
                                             for k in mpps) + ' |')
    lo = max(min(p[1] for p in c) for c in curves.values())
    hi = min(max(p[1] for p in c) for c in curves.values())
    times = args.times or ([float(f'{t:.2g}') for t in np.geomspace(lo, hi, 3)] if hi > lo else [])
    print(f'\n{name}: rRMSE at equal CPU time (log-log interpolation of the medians; "-" = outside '
          f'the measured range)')
    print('| scene | CPU s | ' + ' | '.join(LABELS[m] for m in ms) + ' |')
    print('|---|---|' + '---|' * len(ms))
    table = []
    for t in times:
        vals = {m: at_time(curves[m], t) for m in ms}
        table.append(dict(cpu_s=t, **{m: v for m, v in vals.items()}))
        print(f'| {name} | {t:g} | ' + ' | '.join('-' if vals[m] is None else f'{vals[m]:.3f}' for m in ms) + ' |')
    with open(os.path.join(args.out, name, 'equal_time.json'), 'w') as f:
        json.dump({'curves': curves, 'table': table}, f, indent=1)
    if not args.fig:
        return 0
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(4.6, 3.4), dpi=90)
    for k, m in enumerate(ms):
        col = f'C{k}'
        rs = [r for r in rows if r['method'] == m]
        ax.plot([r['cpu_s'] for r in rs], [r['rrmse'] for r in rs], '.', color=col, alpha=0.3, ms=3)
        c = curves[m]
        ax.plot([p[1] for p in c], [p[2] for p in c], '-o', color=col, ms=3, label=LABELS[m])
        for p in c[::2]:
            ax.annotate(str(p[0]), (p[1], p[2]), fontsize=5, color=col, xytext=(2, 2), textcoords='offset points')
    ax.set_xscale('log')
    ax.set_yscale('log')
    ax.set_xlabel('CPU s (user+sys of the host process, 1 thread)', fontsize=8)
    ax.set_ylabel('rRMSE', fontsize=8)
    nseeds = max(p[3] for c in curves.values() for p in c)
    ax.set_title(f'{name} ({args.res}): median of {nseeds} seeds; labels = spp / mut. per px', fontsize=8)
    ax.tick_params(labelsize=7)
    ax.legend(fontsize=7)
    ax.grid(True, which='both', lw=0.3, alpha=0.5)
    figures.save(fig, args.fig)
    return 0


if __name__ == '__main__':
    sys.exit(main())
