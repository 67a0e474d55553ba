"""Out-of-the-loop tuning of sigma-binned PSSMLT and its convergence chart (thesis Fig. 4.3).

Runs the user's command `host --plugin integrator_pssmlt --plugin tuner_nm SCENE` (the plugin's
tuning hint turns binning on; the host searches a1..a8, sigma1..sigma7 and sigma towards
small-step acceptance 0.234) with --no-db, keeps the --stats JSON and the tuned configuration
(`<out>/<name>_tuned.json`, the `--set` list compare_tuned.py passes on), and draws:
left, |small-step acceptance - 0.234| per iteration (dots) and the best so far (line), the
default configuration's cost dashed; right, the tuned bins on the Theta axis (edges A_i of
eq. 4.2-4.3) with their sigma_i, against the untuned bins (equal widths, all 0.01).

    T="/usr/bin/python3 -m tools.pssmlt.tune_convergence"   # from the repository root
    $T scenes/cornell-box/scene.json \
        --name cornell-box --host build-mlt2/host/host --res 64x64 --iterations 50 --tune-spp 5 \
        --out /tmp/pssmlt_tune --fig tools/pssmlt/figures/tuning_cornell-box.png
    # the rRMSE objective: each pass's own image against a path-traced reference
    $T ... --objective rrmse --reference ref_tune.exr
"""
import json
import os
import sys

import numpy as np

from tools.tttools import cli, figures, host

TUNED_KEYS = ['sigma'] + [f'a{i}' for i in range(1, 10)] + [f'sigma{i}' for i in range(1, 9)]


def edges(cfg):
    """A_0..A_M of eq. 4.2-4.3 (A_M = 1; all a = 0 -> equal widths)."""
    m = int(cfg['bins'])
    a = np.array([cfg[f'a{i}'] for i in range(1, m + 2)], float)
    s = a.sum()
    if s <= 0:
        return np.linspace(0, 1, m + 1)
    A = np.concatenate([[0.0], np.cumsum(a)[:m - 1] / s, [1.0]])
    return A


def tune(args, scene, seed):
    os.makedirs(args.out, exist_ok=True)
    stats = os.path.join(args.out, f'{args.name}_tune_s{seed}.json')
    cmd = ['--plugin', 'integrator_pssmlt', '--plugin', 'tuner_nm', scene,
           '--res', args.res, '--iterations', str(args.iterations), '--tune-spp', str(args.tune_spp),
           '--spp', str(args.tune_spp), '--seed', str(seed), '--threads', str(args.threads),
           '--set', f'integrator_pssmlt.maxDepth={args.depth}',
           '--no-db', '--quiet', '--out', os.path.join(args.out, f'{args.name}_tune_s{seed}.exr')]
    if args.objective:
        cmd += ['--objective', args.objective]
    if args.reference:
        cmd += ['--reference', args.reference]
    return host.run(host.find(args.host), cmd, stats=stats).stats


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scene')
    ap.add_argument('--name', required=True)
    ap.add_argument('--res', default='64x64')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--depth', type=int, default=5)
    ap.add_argument('--iterations', type=int, default=50)
    ap.add_argument('--tune-spp', type=int, default=5)
    ap.add_argument('--seeds', type=int, default=1, help='independent tuning runs (best of seed 1 is kept)')
    ap.add_argument('--objective', default=None, help="host --objective (default: the plugin's hint, "
                    "metric:small_step_acceptance:target=0.234)")
    ap.add_argument('--reference', default=None, help='host --reference (with --objective rrmse): the image '
                    'each tuning pass is compared with; render it with another seed than the evaluation reference')
    ap.add_argument('--out', default='/tmp/pssmlt_tune')
    ap.add_argument('--fig', default=None)
    args = ap.parse_args(argv)

    runs = [tune(args, args.scene, s) for s in range(1, args.seeds + 1)]
    t0 = runs[0]['tuning']
    best = t0['best_config']
    sets = [f'integrator_pssmlt.{k}={best[k]!r}' for k in ['binning', 'bins'] + TUNED_KEYS]
    sets = [s.replace('=True', '=true').replace('=False', '=false') for s in sets]
    with open(os.path.join(args.out, f'{args.name}_tuned.json'), 'w') as f:
        json.dump({'scene': args.scene, 'best_config': best, 'set': sets,
                   'best_cost': t0['best_cost'], 'default_cost': t0['default_cost'],
                   'runs': [{'default_cost': r['tuning']['default_cost'], 'best_cost': r['tuning']['best_cost'],
                             'costs': r['tuning']['costs'], 'best_config': r['tuning']['best_config'],
                             'tuning_ms': r['tuning']['tuning_ms']} for r in runs]}, f, indent=1)
    for i, r in enumerate(runs, 1):
        t = r['tuning']
        print(f'{args.name} seed {i}: default cost {t["default_cost"]:.4f} -> best {t["best_cost"]:.4f} '
              f'({t["iterations"]} iterations, {t["tuning_ms"]:.0f} ms)')
    print('tuned:', ' '.join(f'{k}={best[k]:.4g}' for k in TUNED_KEYS if k in best))
    if not args.fig:
        return 0

    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(8.4, 3.0), dpi=80)
    for i, r in enumerate(runs):
        c = np.array(r['tuning']['costs'], float)
        c[c >= 1e299] = np.nan
        it = np.arange(1, len(c) + 1)
        col = f'C{i}'
        ax.plot(it, c, '.', color=col, ms=4, alpha=0.6)
        ax.plot(it, np.fmin.accumulate(np.where(np.isnan(c), np.inf, c)), '-', color=col,
                label=f'seed {i + 1}' if len(runs) > 1 else 'best so far')
        ax.axhline(r['tuning']['default_cost'], color=col, ls='--', lw=0.8)
    ax.set_yscale('log')
    ax.set_xlabel('tuning iteration')
    ax.set_ylabel(t0['objective'].replace('metric:', ''), fontsize=7)
    ax.set_title(f'{args.name}: Nelder-Mead, {args.tune_spp} mut./px per iter.', fontsize=9)
    ax.legend(fontsize=7)
    dflt = dict(best)
    dflt.update({f'a{i}': 0.5 for i in range(1, 10)})
    dflt.update({f'sigma{i}': 0.01 for i in range(1, 9)})
    for j, r in enumerate(runs[1:], 2):
        cfg = r['tuning']['best_config']
        A = edges(cfg)
        sg = [cfg[f'sigma{i}'] for i in range(1, int(cfg['bins']) + 1)]
        bx.step(np.r_[A[:-1], 1.0], np.r_[sg, sg[-1]], where='post', color=f'C{j - 1}', lw=0.8, alpha=0.5,
                label=f'tuned, seed {j}')
    for cfg, lab, col, ls in [(dflt, 'untuned', 'gray', '--'), (best, 'tuned, seed 1 (used)', 'C0', '-')]:
        A = edges(cfg)
        m = int(cfg['bins'])
        sg = [cfg[f'sigma{i}'] for i in range(1, m + 1)]
        bx.step(np.r_[A[:-1], 1.0], np.r_[sg, sg[-1]], where='post', color=col, ls=ls, label=lab)
        for e in A[1:-1]:
            bx.axvline(e, color=col, ls=':', lw=0.6)
    bx.axhline(best['sigma'], color='k', lw=0.8, ls='-.', label=f'seed 1: sigma (other dims) {best["sigma"]:.3g}')
    bx.set_yscale('log')
    bx.set_xlabel(r'$\Theta = 1/(\alpha\,p)$ (bin edges $A_i$; $\Theta\geq 1$ in last bin)')
    bx.set_ylabel(r'bin $\sigma_i$')
    bx.set_title('tuned bins and sigmas', fontsize=9)
    bx.legend(fontsize=6, loc='best')
    figures.save(fig, args.fig)
    return 0


if __name__ == '__main__':
    sys.exit(main())
