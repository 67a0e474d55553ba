"""Equal-mutation comparison of the path tracer and PSSMLT (classic / sigma-binned) against
a path-traced reference, as in the thesis' Fig. 4.6 (rRMSE spread over seeds).

    /usr/bin/python3 -m tools.pssmlt.compare scenes/cornell-box/scene.json --res 128x128 \
        --ref-spp 512 --spp 16 --seeds 3 --out /tmp/cmp

Each method renders with `host` (--host, tools/tttools/host.py); the reference uses integrator_pt
with maxDepth/rrDepth equal to PSSMLT's maxDepth. Prints tunetrace's rRMSE (over
luminance, tools/common/images.py), render time and, for PSSMLT, the small-step acceptance.
"""
import json
import os
import sys

from tools.common import images  # image reading and the one rRMSE
from tools.tttools import cli, host

METHODS = {
    'pt': ['--plugin', 'integrator_pt'],
    'classic': ['--plugin', 'integrator_pssmlt'],
    'binned': ['--plugin', 'integrator_pssmlt', '--set', 'integrator_pssmlt.binning=true'],
}


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scene')
    ap.add_argument('--res', default='128x128')
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--depth', type=int, default=5)
    ap.add_argument('--ref-spp', type=int, default=512)
    ap.add_argument('--spp', type=int, default=16)
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--methods', default='pt,classic,binned')
    ap.add_argument('--set', action='append', default=[], help='extra --set for the PSSMLT runs')
    ap.add_argument('--out', default='/tmp/pssmlt_compare')
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    exe = host.find(args.host)
    kw = dict(res=args.res, threads=args.threads)
    d = str(args.depth)
    pt_depth = ['--set', f'integrator_pt.maxDepth={d}', '--set', f'integrator_pt.rrDepth={d}']
    ref = os.path.join(args.out, 'reference.exr')
    if not os.path.exists(ref):
        host.render(exe, args.scene, METHODS['pt'] + pt_depth + ['--spp', str(args.ref_spp), '--seed', '999'],
                    out=ref, stats=os.path.join(args.out, 'reference.json'), **kw)
    R = images.read_luminance(ref)
    rows = []
    for m in args.methods.split(','):
        extra = list(METHODS[m])
        extra += pt_depth if m == 'pt' else ['--set', f'integrator_pssmlt.maxDepth={d}']
        if m != 'pt':
            for s in args.set:
                extra += ['--set', s]
        for seed in range(1, args.seeds + 1):
            out = os.path.join(args.out, f'{m}_{seed}.exr')
            st, _ = host.render(exe, args.scene, extra + ['--spp', str(args.spp), '--seed', str(seed)],
                                out=out, stats=os.path.join(args.out, f'{m}_{seed}.json'), **kw)
            img = images.read_luminance(out)
            rrmse = images.rrmse(img, R)
            met = st.get('metrics', {})
            rows.append((m, seed, rrmse, st['render_ms'], met.get('small_step_acceptance', float('nan')),
                         float(img.mean()), float(R.mean())))
            print(f'{m:8s} seed {seed}: rRMSE {rrmse:.4f}  render {st["render_ms"]:.0f} ms  '
                  f'small-step acc {rows[-1][4]:.3f}  mean {img.mean():.5f} (ref {R.mean():.5f})', flush=True)
    with open(os.path.join(args.out, 'summary.json'), 'w') as f:
        json.dump([dict(zip(['method', 'seed', 'rrmse', 'render_ms', 'small_acc', 'mean', 'ref_mean'], r))
                   for r in rows], f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
