"""Is small-step acceptance 0.234 the right target?  Classic PSSMLT with one sigma for all
dims, swept over sigma: rRMSE (against a reference from compare_tuned.py) vs the measured
small-step acceptance, at equal mutations per pixel, several seeds.

    /usr/bin/python3 -m tools.pssmlt.sigma_sweep scenes/cornell-box/scene.json \
        --ref /tmp/pssmlt_cmp/cornell-box/reference.exr --host build-mlt2/host/host --res 96x96 \
        --spp 16 --seeds 3 --out /tmp/pssmlt_sweep --fig tools/pssmlt/figures/sigma_sweep.png
"""
import json
import os
import sys

import numpy as np

from tools.common import images
from tools.tttools import cli, host


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scene')
    ap.add_argument('--ref', required=True)
    ap.add_argument('--name', default='scene')
    ap.add_argument('--res', default='96x96')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--depth', type=int, default=5)
    ap.add_argument('--spp', type=int, default=16)
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--sigmas', default='0.001,0.003,0.01,0.03,0.06,0.1,0.2')
    ap.add_argument('--out', default='/tmp/pssmlt_sweep')
    ap.add_argument('--fig', default=None)
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    exe = host.find(args.host)
    R = images.read_luminance(args.ref)
    rows = []
    for sg in [float(s) for s in args.sigmas.split(',')]:
        for seed in range(1, args.seeds + 1):
            p = os.path.join(args.out, f'{args.name}_{sg}_{seed}')
            st, cpu = host.render(exe, args.scene, ['--plugin', 'integrator_pssmlt', '--set',
                                  f'integrator_pssmlt.maxDepth={args.depth}', '--set',
                                  f'integrator_pssmlt.sigma={sg}', '--spp', str(args.spp), '--seed',
                                  str(seed)], out=p + '.exr', stats=p + '.json', res=args.res,
                                  threads=args.threads)
            e = images.rrmse(images.read_luminance(p + '.exr'), R)
            acc = st['metrics']['small_step_acceptance']
            rows.append(dict(sigma=sg, seed=seed, rrmse=e, small_acc=acc, cpu_s=cpu))
            print(f'sigma {sg:.3g} seed {seed}: small-step acc {acc:.3f} rRMSE {e:.4f}', flush=True)
    with open(os.path.join(args.out, f'{args.name}_sweep.json'), 'w') as f:
        json.dump(rows, f, indent=1)
    if args.fig:
        import matplotlib
        matplotlib.use('Agg')
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(4.2, 3.0), dpi=80)
        sg = sorted({r['sigma'] for r in rows})
        acc = [np.median([r['small_acc'] for r in rows if r['sigma'] == s]) for s in sg]
        e = [[r['rrmse'] for r in rows if r['sigma'] == s] for s in sg]
        med = [np.median(x) for x in e]
        ax.errorbar(acc, med, yerr=[np.subtract(med, [min(x) for x in e]), np.subtract([max(x) for x in e], med)],
                    fmt='o-', ms=4, capsize=2)
        for a, m, s in zip(acc, med, sg):
            ax.annotate(f'{s:g}', (a, m), fontsize=7, xytext=(3, 3), textcoords='offset points')
        ax.axvline(0.234, color='gray', ls='--', lw=0.8)
        ax.set_xlabel('small-step acceptance (median)')
        ax.set_ylabel(f'rRMSE, {args.spp} mut./px (median, range)')
        ax.set_title(f'{args.name}: classic PSSMLT, sigma swept (labels)', fontsize=9)
        fig.tight_layout()
        fig.savefig(args.fig)
    return 0


if __name__ == '__main__':
    sys.exit(main())
