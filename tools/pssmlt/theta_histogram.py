#!/usr/bin/python3
"""Theta landscape of a scene (thesis Fig. 4.1/4.2) from integrator_pssmlt's dump.

integrator_pssmlt writes, when TT_PSSMLT_THETA_DUMP=FILE is set, a CSV histogram of
Theta = 1/(alpha * pdf) over the BSDF directions its proposals sampled (200 bins on [0, 1)
and one for Theta >= 1, delta lobes included), with the alpha and the bin edges A_i in a
comment line. This plots one or more dumps (e.g. one per alpha, or per scene variant) and
marks the sigma-bin edges, to choose alpha and M per scene.

    TT_PSSMLT_THETA_DUMP=theta.csv host --plugin integrator_pssmlt scene.json --spp 4
    /usr/bin/python3 -m tools.pssmlt.theta_histogram theta.csv [more.csv ...] -o theta.png
"""
import argparse
import sys


def read_dump(path):
    """Returns (meta dict, list of (lo, hi, count)) of one dump."""
    meta, rows = {}, []
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            if line.startswith('#'):
                for tok in line[1:].split():
                    if '=' in tok:
                        k, v = tok.split('=', 1)
                        meta[k] = v
                continue
            if line.startswith('theta_lo'):
                continue
            lo, hi, n = line.split(',')
            rows.append((float(lo), float(hi), int(n)))
    if not rows:
        raise ValueError(f'{path}: no histogram rows')
    return meta, rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('dumps', nargs='+', help='CSV files written through TT_PSSMLT_THETA_DUMP')
    ap.add_argument('-o', '--out', default='theta_histogram.png', help='output image (png/pdf/svg)')
    ap.add_argument('--labels', nargs='*', help='legend labels, one per dump (default: file names)')
    ap.add_argument('--log', action='store_true', help='logarithmic count axis')
    args = ap.parse_args(argv)
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 4.2))
    labels = args.labels or args.dumps
    for i, path in enumerate(args.dumps):
        meta, rows = read_dump(path)
        finite = [r for r in rows if r[1] != float('inf')]
        over = sum(r[2] for r in rows if r[1] == float('inf'))
        total = sum(r[2] for r in rows) or 1
        xs = [0.5 * (lo + hi) for lo, hi, _ in finite]
        ys = [n / total for _, _, n in finite]
        alpha = float(meta.get('alpha', 'nan'))
        lab = f'{labels[i] if i < len(labels) else path} (alpha={alpha:.3g}, Theta>=1: {100.0 * over / total:.1f}%)'
        ax.step(xs, ys, where='mid', label=lab)
        edges = [float(e) for e in meta.get('edges', '').split(';') if e]
        if len(args.dumps) == 1 and meta.get('binning') == '1':
            for e in edges[1:-1]:
                ax.axvline(e, color='grey', lw=0.8, ls='--')
        print(f'{path}: {total} directions, {100.0 * over / total:.2f}% with Theta >= 1 (incl. delta lobes)')
    ax.set_xlabel('Theta = 1 / (alpha * pdf)')
    ax.set_ylabel('fraction of sampled directions per bin (1/200)')
    if args.log:
        ax.set_yscale('log')
    ax.set_xlim(0, 1)
    ax.legend(fontsize=8)
    ax.set_title('Theta landscape (thesis Fig. 4.1/4.2); dashed: sigma-bin edges A_i')
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    print(f'wrote {args.out}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
