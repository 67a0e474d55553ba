"""rRMSE at equal mutations per pixel (thesis Fig. 4.6 as box plots): path tracer, classic
PSSMLT (sigma 0.01), untuned sigma-binning (defaults: equal-width bins, all sigma_i 0.01) and
tuned sigma-binning (the configuration found by tune_convergence.py, passed with --set),
against a high-spp integrator_pt reference (maxDepth = rrDepth = PSSMLT's maxDepth).

    C="/usr/bin/python3 -m tools.pssmlt.compare_tuned"   # from the repository root
    $C --host build-mlt2/host/host --res 96x96 --spp 16 --seeds 5 \
        --ref-spp 1024 --tuned-dir /tmp/pssmlt_tune --out /tmp/pssmlt_cmp \
        cornell-box=scenes/cornell-box/scene.json ...
    # + binning tuned towards rRMSE (tune_convergence.py --objective rrmse --out DIR)
    $C ... --rrmse-dir DIR --methods pt,classic,binned,tuned,rrmse
    $C --plot-only --out /tmp/pssmlt_cmp \
        --fig tools/pssmlt/figures/rrmse_equal_mutations.png NAME=SCENE ...

Every run is a separate `host` process; its CPU time (user+sys of the child) is recorded
next to the wall render_ms.  Results: <out>/<name>/results.json (appended per run, so a
killed batch can be resumed), and the figure.
"""
import json
import os
import sys

import numpy as np

from tools.common import images
from tools.tttools import cli, figures, host

LABELS = {'pt': 'path tracer', 'classic': 'PSSMLT classic', 'binned': 'binned untuned', 'tuned': 'binned tuned',
          'rrmse': 'binned rRMSE-tuned', 'rrmse200': 'binned rRMSE-tuned, 200 it.'}
SHORT = {'pt': 'PT', 'classic': 'classic', 'binned': 'untuned', 'tuned': 'acc.-tuned', 'rrmse': 'rRMSE-tuned',
         'rrmse200': 'rRMSE 200 it.'}


def do_scene(args, name, scene):
    exe = host.find(args.host)
    kw = dict(res=args.res, threads=args.threads)
    out = os.path.join(args.out, name)
    os.makedirs(out, exist_ok=True)
    d = str(args.depth)
    pt = ['--plugin', 'integrator_pt', '--set', f'integrator_pt.maxDepth={d}', '--set', f'integrator_pt.rrDepth={d}']
    mlt = ['--plugin', 'integrator_pssmlt', '--set', f'integrator_pssmlt.maxDepth={d}']
    ref = os.path.join(out, 'reference.exr')
    if not os.path.exists(ref):
        host.render(exe, scene, pt + ['--spp', str(args.ref_spp), '--seed', '999'], out=ref,
                    stats=os.path.join(out, 'reference.json'), **kw)
    R = images.read_luminance(ref)
    with open(os.path.join(args.tuned_dir, f'{name}_tuned.json')) as f:
        tj = json.load(f)
    tuned_set = tj['set']
    if args.tuned_run > 1:  # another tuning run's result (robustness of the tuned configuration)
        cfg = tj['runs'][args.tuned_run - 1]['best_config']
        keys = [s.split('=', 1)[0].split('.', 1)[1] for s in tuned_set]
        tuned_set = [f'integrator_pssmlt.{k}=' + (str(cfg[k]).lower() if isinstance(cfg[k], bool) else repr(cfg[k]))
                     for k in keys]
    methods = {
        'pt': pt,
        'classic': mlt,
        'binned': mlt + ['--set', 'integrator_pssmlt.binning=true'],
        'tuned': mlt + sum((['--set', s] for s in tuned_set), []),
    }
    if args.rrmse_dir:  # tuned with host --objective rrmse (tune_convergence.py --objective rrmse)
        with open(os.path.join(args.rrmse_dir, f'{name}_tuned.json')) as f:
            methods['rrmse'] = mlt + sum((['--set', s] for s in json.load(f)['set']), [])
    if args.rrmse200_dir:  # the same with a longer tuning run (--iterations 200)
        with open(os.path.join(args.rrmse200_dir, f'{name}_tuned.json')) as f:
            methods['rrmse200'] = mlt + sum((['--set', s] for s in json.load(f)['set']), [])
    resf = os.path.join(out, 'results.json')
    rows = json.load(open(resf)) if os.path.exists(resf) else []
    done = {(r['method'], r['seed'], r['spp']) for r in rows}
    for spp in args.spp:
        for seed in range(1, args.seeds + 1):
            for m in args.methods.split(','):
                if (m, seed, spp) in done:
                    continue
                img_path = os.path.join(out, f'{m}_{spp}_{seed}.exr')
                st, cpu = host.render(exe, scene, methods[m] + ['--spp', str(spp), '--seed', str(seed)],
                                      out=img_path, stats=os.path.join(out, f'{m}_{spp}_{seed}.json'), **kw)
                img = images.read_luminance(img_path)
                met = st.get('metrics', {})
                row = dict(method=m, seed=seed, spp=spp, rrmse=images.rrmse(img, R), render_ms=st['render_ms'], cpu_s=cpu,
                           small_acc=met.get('small_step_acceptance'), mean=float(img.mean()), ref_mean=float(R.mean()))
                rows.append(row)
                with open(resf, 'w') as f:
                    json.dump(rows, f, indent=1)
                print(f'{name:16s} {m:8s} spp {spp} seed {seed}: rRMSE {row["rrmse"]:.4f} render {row["render_ms"]:.0f} ms '
                      f'cpu {cpu:.2f} s acc {row["small_acc"] if row["small_acc"] is not None else float("nan"):.3f} '
                      f'mean {row["mean"]:.5f} (ref {row["ref_mean"]:.5f})', flush=True)
    return rows


def table(name, rows):
    out = []
    for spp in sorted({r['spp'] for r in rows}):
        for m in LABELS:
            rs = [r for r in rows if r['method'] == m and r['spp'] == spp]
            if not rs:
                continue
            e = np.array([r['rrmse'] for r in rs])
            cpu = np.median([r['cpu_s'] for r in rs])
            acc = [r['small_acc'] for r in rs if r['small_acc'] is not None]
            out.append(f'| {name} | {spp} | {LABELS[m]} | {np.median(e):.3f} ({e.min():.3f}-{e.max():.3f}) | {len(e)} '
                       f'| {cpu:.2f} | {np.median(acc) if acc else float("nan"):.2f} |')
    return out


def paired(name, rows, base='classic'):
    """Per-seed ratio method / base (same seed, same mutation count): median, min-max and
    the number of seeds where the method has the lower error."""
    out = []
    for spp in sorted({r['spp'] for r in rows}):
        b = {r['seed']: r['rrmse'] for r in rows if r['method'] == base and r['spp'] == spp}
        for m in LABELS:
            if m == base:
                continue
            q = [(r['rrmse'] / b[r['seed']]) for r in rows if r['method'] == m and r['spp'] == spp and r['seed'] in b]
            if q:
                q = np.array(q)
                out.append(f'| {name} | {spp} | {LABELS[m]} | {np.median(q):.3f} ({q.min():.3f}-{q.max():.3f}) '
                           f'| {int((q < 1).sum())}/{len(q)} |')
    return out


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scenes', nargs='+', help='NAME=PATH')
    ap.add_argument('--res', default='96x96')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--depth', type=int, default=5)
    ap.add_argument('--ref-spp', type=int, default=1024)
    ap.add_argument('--spp', type=int, nargs='+', default=[16])
    ap.add_argument('--seeds', type=int, default=5)
    ap.add_argument('--methods', default='pt,classic,binned,tuned')
    ap.add_argument('--tuned-dir', default='/tmp/pssmlt_tune')
    ap.add_argument('--rrmse-dir', default=None, help='tune_convergence.py --objective rrmse output: '
                    'adds the method "rrmse" (use --methods ...,rrmse)')
    ap.add_argument('--rrmse200-dir', default=None, help='as --rrmse-dir, method "rrmse200" (a 200-iteration run)')
    ap.add_argument('--tuned-run', type=int, default=1, help='use the best configuration of this tuning run')
    ap.add_argument('--out', default='/tmp/pssmlt_cmp')
    ap.add_argument('--fig', default=None)
    ap.add_argument('--plot-only', action='store_true')
    args = ap.parse_args(argv)
    scenes = [s.split('=', 1) for s in args.scenes]
    allrows = {}
    for name, path in scenes:
        if args.plot_only:
            f = os.path.join(args.out, name, 'results.json')
            if os.path.exists(f):
                allrows[name] = json.load(open(f))
        else:
            allrows[name] = do_scene(args, name, path)
    print('| scene | mut./px | method | rRMSE median (min-max) | seeds | CPU s (median) | small-step acc. |')
    print('|---|---|---|---|---|---|---|')
    for name in allrows:
        print('\n'.join(table(name, allrows[name])))
    print('\n| scene | mut./px | method | rRMSE / classic, same seed: median (min-max) | seeds better than classic |')
    print('|---|---|---|---|---|')
    for name in allrows:
        print('\n'.join(paired(name, allrows[name])))
    if not args.fig or not allrows:
        return 0
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    spps = sorted({r['spp'] for rows in allrows.values() for r in rows})
    n = len(allrows)
    fig, axs = plt.subplots(len(spps), n, figsize=(2.3 * n, 2.6 * len(spps)), dpi=80, squeeze=False)
    for i, spp in enumerate(spps):
        for j, (name, rows) in enumerate(allrows.items()):
            ax = axs[i][j]
            ms = [m for m in LABELS if any(r['method'] == m and r['spp'] == spp for r in rows)]
            data = [[r['rrmse'] for r in rows if r['method'] == m and r['spp'] == spp] for m in ms]
            if not ms:
                ax.axis('off')
                continue
            bp = ax.boxplot(data, widths=0.6, patch_artist=True, whis=(0, 100))
            for k, patch in enumerate(bp['boxes']):
                patch.set_facecolor(f'C{list(LABELS).index(ms[k])}')
                patch.set_alpha(0.6)
            ax.set_xticks(range(1, len(ms) + 1))
            ax.set_xticklabels([SHORT[m] for m in ms], fontsize=7, rotation=30)
            ax.tick_params(axis='y', labelsize=7)
            ax.set_title(f'{name}\n{spp} mut./px, {len(data[0])} seeds', fontsize=8)
            if j == 0:
                ax.set_ylabel('rRMSE', fontsize=8)
    figures.save(fig, args.fig)
    return 0


if __name__ == '__main__':
    sys.exit(main())
