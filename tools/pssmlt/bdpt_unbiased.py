"""BDPT against the path tracer on the real scenes the path tracer can sample: the image
mean per channel (relative difference and its standard error) and whether the per-pixel
differences are consistent with noise (mean z^2 over pixels, 1 when they are).

    /usr/bin/python3 -m tools.pssmlt.bdpt_unbiased --res 32x32 --pt-spp 256 --bdpt-spp 64 --seeds 8 \
        --out /tmp/bdpt_unbiased

Each method renders --seeds images (different seeds) of the scene's still camera with
maxDepth 5 (the path tracer without Russian roulette); a pixel's standard error comes from
the spread over seeds, the image mean's from the spread of the seeds' means. Scenes: the
scene.json wrappers of scenes/ and pbrt-v4's Cornell boxes, except caustic-glass (its only
light is a spot light behind glass: the path tracer cannot sample its caustic, so the two
images differ by design; see integrator_bdpt's README) and the volume variants (no media).
Results: <out>/unbiased.json and a table.
"""
import json
import os
import subprocess
import sys

import numpy as np

from tools.common import images
from tools.tttools import cli, host

ROOT = host.ROOT

SHARED = os.path.normpath(os.path.join(ROOT, '..', 'shared', 'scenes'))
SCENES = {
    'cornell-box': 'scenes/cornell-box/scene.json',
    'cornell-box-pbrt': os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box.pbrt'),
    'cornell-box-pbrt-specular': os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box-specular.pbrt'),
    'cornell-box-pbrt-silver': os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box-silver.pbrt'),
    'cornell-box-pbrt-envmap': os.path.join(SHARED, 'cornell-box-pbrt', 'cornell-box-environment-map.pbrt'),
    'specular-box': 'scenes/cornell-box-variants/specular-box/scene.json',
    'veach-mis': 'scenes/veach-mis/scene.json',
    'veach-ajar': 'scenes/veach-ajar/scene.json',
    'killeroos': 'scenes/killeroos/scene.json',
    'living-room': 'scenes/living-room/scene.json',
    'staircase': 'scenes/staircase/scene.json',
    'bathroom': 'scenes/bathroom/scene.json',
    'bmw-m6': 'scenes/bmw-m6/scene.json',
}
DEPTH = 5


def render(args, scene, method, spp, seed, out):
    p = (['--plugin', 'integrator_pt', '--set', f'integrator_pt.maxDepth={DEPTH}', '--set',
          f'integrator_pt.rrDepth={DEPTH}'] if method == 'pt' else
         ['--plugin', 'integrator_bdpt', '--set', f'integrator_bdpt.maxDepth={DEPTH}'])
    host.run(args.host, [scene, '--res', args.res, '--spp', str(spp), '--seed', str(seed), '--threads',
                         str(args.threads), '--no-db', '--quiet', '--out', out] + p, nice=args.nice,
             log=subprocess.DEVNULL)
    img = images.read_rgb(out).astype(np.float64)
    os.remove(out)
    png = os.path.splitext(out)[0] + '.png'
    if os.path.exists(png):
        os.remove(png)
    return img


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('scenes', nargs='*', help='names (default all): ' + ', '.join(SCENES))
    ap.add_argument('--res', default='32x32')
    ap.add_argument('--pt-spp', type=int, default=256)
    ap.add_argument('--bdpt-spp', type=int, default=64)
    ap.add_argument('--seeds', type=int, default=8)
    ap.add_argument('--threads', type=int, default=2)
    ap.add_argument('--nice', type=int, default=5)
    ap.add_argument('--out', default='/tmp/bdpt_unbiased')
    args = ap.parse_args(argv)
    names = args.scenes or list(SCENES)
    for n in names:
        if n not in SCENES:
            ap.error(f'unknown scene {n!r}')
    os.makedirs(args.out, exist_ok=True)
    args.host = host.find(args.host)
    resf = os.path.join(args.out, 'unbiased.json')
    res = json.load(open(resf)) if os.path.exists(resf) else {}
    for name in names:
        if name in res:
            continue
        scene = SCENES[name] if os.path.isabs(SCENES[name]) else os.path.join(ROOT, SCENES[name])
        imgs = {m: np.stack([render(args, scene, m, args.pt_spp if m == 'pt' else args.bdpt_spp, 100 + k,
                                    os.path.join(args.out, f'{name}_{m}_{k}.exr')) for k in range(args.seeds)])
                for m in ('pt', 'bdpt')}
        S = args.seeds
        mean = {m: v.mean(axis=(0, 1, 2)) for m, v in imgs.items()}                      # per channel
        se = {m: v.mean(axis=(1, 2)).std(axis=0, ddof=1) / np.sqrt(S) for m, v in imgs.items()}
        rel = (mean['bdpt'] - mean['pt']) / np.maximum(mean['pt'], 1e-12)
        rel_se = np.sqrt(se['bdpt'] ** 2 + se['pt'] ** 2) / np.maximum(mean['pt'], 1e-12)
        L = {m: images.luminance(v.mean(axis=0)) for m, v in imgs.items()}               # per pixel
        Lv = {m: np.stack([images.luminance(x) for x in v]).var(axis=0, ddof=1) / S for m, v in imgs.items()}
        var = Lv['pt'] + Lv['bdpt']
        ok = var > 1e-12 * np.maximum(L['pt'], 1e-12) ** 2
        z2 = float(np.mean((L['bdpt'] - L['pt'])[ok] ** 2 / var[ok])) if ok.any() else 0.0
        res[name] = dict(scene=SCENES[name], res=args.res, pt_spp=args.pt_spp, bdpt_spp=args.bdpt_spp, seeds=S,
                         mean_pt=mean['pt'].tolist(), mean_bdpt=mean['bdpt'].tolist(), rel_diff=rel.tolist(),
                         rel_se=rel_se.tolist(), pixel_z2=z2, pixels=int(ok.sum()))
        with open(resf + '.tmp', 'w') as f:
            json.dump(res, f, indent=1)
        os.replace(resf + '.tmp', resf)
        print(f'{name:26s} BDPT - PT per channel: ' + ' '.join(f'{100 * r:+.2f}%' for r in rel) +
              f' (se {100 * max(rel_se):.2f}%); pixels mean z^2 {z2:.2f}', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
