"""Side by side with pbrt-v3 (the thesis' renderer, 4.6): pbrt-v4's diffuse Cornell box
(../shared/scenes/cornell-box-pbrt/cornell-box.pbrt) rendered by pbrt-v3's `bdpt` and `mlt`
integrators and by tunetrace's integrator_bdpt and integrator_pssmlt mode=mmlt (and
integrator_pt), at the same resolution and samples (mutations) per pixel, single-threaded:
the image mean per channel (the renderers must agree within noise) and CPU seconds.

    /usr/bin/python3 -m tools.pssmlt.pbrt_v3_anchor --pbrt /tmp/pbrt-v3/pbrt --res 64 --spp 256 \
        --reference /tmp/ch4/refs/cornell-box.exr --out /tmp/pbrt_v3_anchor

pbrt-v3 is not part of tunetrace: build it yourself (README, "pbrt-v3 anchor"). The scene is
converted to pbrt-v3's syntax here (Film "image", Material "matte" "Kd", "point P", the light's
scale folded into L, WorldEnd); pbrt-v3 renders RGB (its default RGBSpectrum), as tunetrace
does, so the means compare directly, against --reference (tunetrace's BDPT at many more
samples, e.g. chapter4.py's refs/cornell-box.exr of the same resolution). pbrt-v3 has no seed
option, so a render's noise is estimated from its pixels' differences to the reference: the
image mean's standard error is sqrt(mean((image - reference)^2) / pixels) (the reference's own
noise and any bias included, so it is an upper bound). MLT's image mean is its bootstrap
estimate b, whose error does not shrink with mutations: pbrt-v3's default of 100000
bootstrap samples per depth is used for both.
"""
import json
import os
import re
import resource
import subprocess
import sys

import numpy as np

from tools.common import images
from tools.tttools import cli, host

ROOT = host.ROOT

SCENE = os.path.normpath(os.path.join(ROOT, '..', 'shared', 'scenes', 'cornell-box-pbrt', 'cornell-box.pbrt'))


def to_v3(text, res, spp, integrator, out_exr):
    """pbrt-v4's cornell-box.pbrt in pbrt-v3's syntax."""
    lines = text.split('\n')
    out, i = [], 0
    while i < len(lines):
        ln = lines[i]
        s = ln.strip()
        if s.startswith('Film '):
            while i + 1 < len(lines) and lines[i + 1].strip().startswith('"'):
                i += 1
            out.append(f'Film "image" "integer xresolution" [{res}] "integer yresolution" [{res}] '
                       f'"string filename" "{out_exr}"')
            out.append(f'Sampler "random" "integer pixelsamples" [{spp}]')
            out.append('PixelFilter "box"')
        elif s.startswith('Integrator '):
            out.append(integrator)
        elif s.startswith('Material "diffuse"'):
            nxt = lines[i + 1].strip() if i + 1 < len(lines) else ''
            m = re.match(r'"rgb reflectance"\s*\[(.*)\]', nxt)
            if not m:
                raise SystemExit(f'{SCENE}: unexpected material parameters {nxt!r}')
            out.append(f'Material "matte" "rgb Kd" [{m.group(1)}]')
            i += 1
        elif s.startswith('AreaLightSource'):
            m = re.search(r'"rgb L"\s*\[([^\]]*)\]\s*"float scale"\s*\[([^\]]*)\]', s)
            if not m:
                raise SystemExit(f'{SCENE}: unexpected light {s!r}')
            L = [float(x) * float(m.group(2)) for x in m.group(1).split()]
            out.append('AreaLightSource "diffuse" "rgb L" [%g %g %g]' % tuple(L))
        else:
            out.append(ln.replace('"point3 P"', '"point P"'))
        i += 1
    out.append('WorldEnd')
    return '\n'.join(out) + '\n'


def timed(cmd, cwd=None):
    """CPU seconds of pbrt-v3 running `cmd` (its output dropped)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    subprocess.run(cmd, check=True, cwd=cwd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def mean_se(path, ref):
    """Per-channel image mean and an upper bound of its standard error (pixel differences to
    the reference, treated as independent noise)."""
    px = images.read_rgb(path).astype(np.float64)
    if px.shape != ref.shape:
        raise SystemExit(f'{path}: {px.shape[1]}x{px.shape[0]}, the reference is {ref.shape[1]}x{ref.shape[0]}')
    n = px.shape[0] * px.shape[1]
    return px.mean(axis=(0, 1)), np.sqrt(((px - ref) ** 2).mean(axis=(0, 1)) / n)


def main(argv=None):
    ap = cli.parser(__doc__)
    ap.add_argument('--pbrt', required=True, help='the pbrt-v3 executable')
    ap.add_argument('--res', type=int, default=64)
    ap.add_argument('--spp', type=int, default=256, help='samples (BDPT, PT) and mutations (MLT) per pixel')
    ap.add_argument('--bootstrap', type=int, default=100000)
    ap.add_argument('--reference', required=True, help='EXR of the same scene and resolution (high spp)')
    ap.add_argument('--chains', type=int, default=1000)
    ap.add_argument('--out', default='/tmp/pbrt_v3_anchor')
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    with open(SCENE) as f:
        text = f.read()
    ref = images.read_rgb(args.reference).astype(np.float64)
    rmean = ref.mean(axis=(0, 1))
    exe = host.find(args.host)
    d = 5
    mlt_v3 = (f'Integrator "mlt" "integer maxdepth" [{d}] "integer mutationsperpixel" [{args.spp}] '
              f'"integer bootstrapsamples" [{args.bootstrap}] "integer chains" [{args.chains}] '
              '"float largestepprobability" [0.3] "float sigma" [0.01]')
    runs = [
        ('pbrt-v3 bdpt', 'v3', f'Integrator "bdpt" "integer maxdepth" [{d}]'),
        ('pbrt-v3 mlt', 'v3', mlt_v3),
        ('tunetrace bdpt', 'tt', ['--plugin', 'integrator_bdpt', '--set', f'integrator_bdpt.maxDepth={d}']),
        ('tunetrace mmlt', 'tt', ['--plugin', 'integrator_pssmlt', '--set', 'integrator_pssmlt.mode=mmlt',
                                  '--set', f'integrator_pssmlt.maxDepth={d}',
                                  '--set', f'integrator_pssmlt.bootstrapSamples={args.bootstrap}',
                                  '--set', f'integrator_pssmlt.chains={args.chains}']),
        ('tunetrace pt', 'tt', ['--plugin', 'integrator_pt', '--set', f'integrator_pt.maxDepth={d}',
                                '--set', f'integrator_pt.rrDepth={d}']),
    ]
    rows = []
    for label, kind, spec in runs:
        exr = os.path.join(args.out, label.replace(' ', '_') + '.exr')
        if kind == 'v3':
            pb = os.path.join(args.out, label.replace(' ', '_') + '.pbrt')
            with open(pb, 'w') as f:
                f.write(to_v3(text, args.res, args.spp, spec, exr))
            cpu = timed([args.pbrt, '--nthreads', '1', '--quiet', pb], cwd=os.path.dirname(SCENE))
        else:
            cpu = host.run(exe, [SCENE, '--res', f'{args.res}x{args.res}', '--spp', str(args.spp), '--threads', '1',
                                 '--no-db', '--quiet', '--out', exr] + spec, log=subprocess.DEVNULL).cpu_s
        m, se = mean_se(exr, ref)
        rel = (m - rmean) / rmean
        rows.append(dict(run=label, mean=m.tolist(), se=se.tolist(), rel_to_reference=rel.tolist(), cpu_s=cpu,
                         rrmse=images.rrmse(images.luminance(images.read_rgb(exr)), images.luminance(ref))))
        print(f'{label:16s} mean R {m[0]:.4f} G {m[1]:.4f} B {m[2]:.4f}; vs reference ' +
              ' '.join(f'{100 * r:+.2f}%' for r in rel) + f' (se {100 * max(se / rmean):.2f}%); '
              f'rRMSE {rows[-1]["rrmse"]:.3f}; CPU {cpu:.2f} s', flush=True)
    with open(os.path.join(args.out, 'anchor.json'), 'w') as f:
        json.dump(dict(res=args.res, spp=args.spp, reference=args.reference, reference_mean=rmean.tolist(), rows=rows),
                  f, indent=1)
    return 0


if __name__ == '__main__':
    sys.exit(main())
