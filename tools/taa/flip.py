"""LDR-FLIP image difference (Andersson et al. 2020, "FLIP: A Difference Evaluator for
Alternating Images", HPG 2020), written from the paper's description with numpy + scipy.

  flip_ldr(ref, test, ppd=67.0) -> per-pixel error map (..., H, W) in [0, 1]
  flip_mean(ref, test, ppd=67.0) -> mean of that map (per image for a stack)

ref / test: (..., H, W, 3) sRGB-encoded colours in [0, 1] (a leading stack axis is
allowed: frames are processed together). srgb_encode(lin) turns linear [0, 1] colours
(e.g. the tonemapped c/(1+max c) frames of eval.py) into sRGB first, as the FLIP tool does
for LDR input.

Pipeline (paper section 3/4):
  colour:  sRGB -> linear RGB -> XYZ -> YCxCz (opponent space, D65-normalised);
           each channel filtered by its contrast-sensitivity Gaussian(s)
           h(x) = sum_i a_i sqrt(pi/b_i) exp(-pi^2 x^2 / b_i)  (x in degrees, kernel
           normalised to unit sum, radius ceil(3 sqrt(max b / (2 pi^2)) ppd) pixels):
           achromatic a=1 b=0.0047; red-green a=1 b=0.0053; blue-yellow
           a=(34.1, 13.5) b=(0.04, 0.025); back to linear RGB, clamped to [0,1]^3;
           L*a*b*, Hunt adjustment (a, b scaled by 0.01 L); HyAB distance
           |dL| + ||(da, db)||, raised to qc = 0.7 and compressed with
           cmax = HyAB(green, blue)^qc, pc = 0.4, pt = 0.95 into [0, 1].
  feature: normalised luminance Y/Yn; edge (first Gaussian derivative) and point (second
           derivative) detectors, sd = 0.5 * 0.082 * ppd, radius ceil(3 sd), positive
           weights normalised to 1 and negative to -1; per pixel
           dF = max(| |e_r| - |e_t| |, | |p_r| - |p_t| |), then (dF / sqrt 2)^qf, qf = 0.5.
  result:  dE = dE_c ^ (1 - dF').
All filters are separable and use clamp-to-edge borders.

  F="/usr/bin/python3 -m tools.taa.flip"   # from the repository root
  $F --selftest                 property checks (+ one fixed synthetic pair)
  $F REF.exr TEST.exr [--ppd P] mean FLIP of two linear EXRs (tonemapped, sRGB)
"""
import sys

import numpy as np
from scipy.ndimage import correlate1d

QC, PC, PT = 0.7, 0.4, 0.95       # colour exponent, compression knee (fraction, value)
QF, FEATURE_W = 0.5, 0.082        # feature exponent, edge-detector peak-to-trough (deg)
# contrast-sensitivity Gaussians per YCxCz channel: ((a1, b1), (a2, b2))
CSF = (((1.0, 0.0047),), ((1.0, 0.0053),), ((34.1, 0.04), (13.5, 0.025)))


def _srgb_to_xyz_matrix():
    """Linear sRGB -> XYZ from the sRGB primaries' and D65 chromaticities."""
    prim = np.array([[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]])
    wx, wy = 0.3127, 0.3290

    def xyz(x, y):
        return np.array([x / y, 1.0, (1.0 - x - y) / y])
    cols = np.stack([xyz(x, y) for x, y in prim], axis=1)
    scale = np.linalg.solve(cols, xyz(wx, wy))
    return cols * scale


RGB2XYZ = _srgb_to_xyz_matrix()
XYZ2RGB = np.linalg.inv(RGB2XYZ)
WHITE = RGB2XYZ.sum(axis=1)       # XYZ of linear RGB (1, 1, 1)


def srgb_encode(c):
    c = np.clip(c, 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def srgb_decode(s):
    return np.where(s <= 0.04045, s / 12.92, np.power((s + 0.055) / 1.055, 2.4))


def _mat(c, m):
    return np.einsum("...c,dc->...d", c, m)


def _ycxcz(lin):
    w = _mat(lin, RGB2XYZ) / WHITE
    return np.stack([116.0 * w[..., 1] - 16.0, 500.0 * (w[..., 0] - w[..., 1]),
                     200.0 * (w[..., 1] - w[..., 2])], axis=-1)


def _ycxcz_to_linear(o):
    y = (o[..., 0] + 16.0) / 116.0
    xyz = np.stack([y + o[..., 1] / 500.0, y, y - o[..., 2] / 200.0], axis=-1) * WHITE
    return _mat(xyz, XYZ2RGB)


def _lab(lin):
    t = _mat(lin, RGB2XYZ) / WHITE
    d = 6.0 / 29.0
    f = np.where(t > d ** 3, np.cbrt(t), t / (3 * d * d) + 4.0 / 29.0)
    return np.stack([116.0 * f[..., 1] - 16.0, 500.0 * (f[..., 0] - f[..., 1]),
                     200.0 * (f[..., 1] - f[..., 2])], axis=-1)


def _hunt(lab):
    return np.concatenate([lab[..., :1], lab[..., 1:] * (0.01 * lab[..., :1])], axis=-1)


def _hyab(p, q):
    d = p - q
    return np.abs(d[..., 0]) + np.hypot(d[..., 1], d[..., 2])


def _sep(img, k1x, k1y):
    """Separable correlation over the last two axes (H, W), clamp-to-edge."""
    out = correlate1d(img, k1x, axis=-1, mode="nearest")
    return correlate1d(out, k1y, axis=-2, mode="nearest")


def _csf_filter(opp, ppd):
    bmax = max(b for ch in CSF for _, b in ch)
    r = int(np.ceil(3.0 * np.sqrt(bmax / (2.0 * np.pi ** 2)) * ppd))
    xdeg = np.arange(-r, r + 1) / ppd
    out = np.empty_like(opp)
    for c, terms in enumerate(CSF):
        # 2-D kernel sum_i a_i sqrt(pi/b_i) g_i(x) g_i(y), normalised to unit sum:
        # each term is separable; weight of term i = a_i sqrt(pi/b_i) S_i^2 / total.
        gs = [np.exp(-np.pi ** 2 * xdeg ** 2 / b) for _, b in terms]
        ws = np.array([a * np.sqrt(np.pi / b) * g.sum() ** 2 for (a, b), g in zip(terms, gs)])
        ws /= ws.sum()
        ch = opp[..., c]
        out[..., c] = sum(w * _sep(ch, g / g.sum(), g / g.sum()) for w, g in zip(ws, gs))
    return out


def _detector_kernels(ppd):
    sd = 0.5 * FEATURE_W * ppd
    r = int(np.ceil(3.0 * sd))
    x = np.arange(-r, r + 1, dtype=np.float64)
    g = np.exp(-x ** 2 / (2 * sd * sd))

    def signed_norm(k):
        return np.where(k < 0, k / -k[k < 0].sum(), k / k[k > 0].sum())
    edge = signed_norm(-x * g)                       # d/dx of the Gaussian
    point = signed_norm((x ** 2 / (sd * sd) - 1) * g)  # d2/dx2 of the Gaussian
    return edge, point, g / g.sum()


def _features(y, ppd):
    edge, point, g = _detector_kernels(ppd)
    e = np.hypot(_sep(y, edge, g), _sep(y, g, edge))
    p = np.hypot(_sep(y, point, g), _sep(y, g, point))
    return e, p


def _cmax():
    g = _hunt(_lab(np.array([0.0, 1.0, 0.0])))
    b = _hunt(_lab(np.array([0.0, 0.0, 1.0])))
    return _hyab(g, b) ** QC


def flip_ldr(ref, test, ppd=67.0):
    """LDR-FLIP map (..., H, W) in [0, 1] for sRGB-encoded (..., H, W, 3) images in [0, 1]."""
    ref = np.asarray(ref, dtype=np.float64)
    test = np.asarray(test, dtype=np.float64)
    if ref.shape != test.shape or ref.shape[-1] != 3:
        raise ValueError(f"shapes {ref.shape} / {test.shape}: need equal (..., H, W, 3)")
    lr, lt = srgb_decode(np.clip(ref, 0, 1)), srgb_decode(np.clip(test, 0, 1))
    orr, ot = _ycxcz(lr), _ycxcz(lt)
    # colour pipeline
    fr = np.clip(_ycxcz_to_linear(_csf_filter(orr, ppd)), 0.0, 1.0)
    ft = np.clip(_ycxcz_to_linear(_csf_filter(ot, ppd)), 0.0, 1.0)
    de = _hyab(_hunt(_lab(fr)), _hunt(_lab(ft))) ** QC
    cmax = _cmax()
    knee = PC * cmax
    dc = np.where(de < knee, de * (PT / knee), PT + (de - knee) / (cmax - knee) * (1.0 - PT))
    # feature pipeline on normalised luminance Y/Yn
    er, pr = _features((orr[..., 0] + 16.0) / 116.0, ppd)
    et, pt = _features((ot[..., 0] + 16.0) / 116.0, ppd)
    df = np.maximum(np.abs(er - et), np.abs(pr - pt))
    df = (df / np.sqrt(2.0)) ** QF
    return np.power(dc, 1.0 - df)


def flip_mean(ref, test, ppd=67.0):
    m = flip_ldr(ref, test, ppd)
    return m.mean(axis=(-2, -1))


def tonemap_srgb(x):
    """eval.py's tonemap c/(1+max c) of linear HDR colours, then sRGB-encoded."""
    x = np.maximum(np.asarray(x, dtype=np.float64), 0.0)
    return srgb_encode(x / (1.0 + x.max(-1, keepdims=True)))


# ----------------------------------------------------------------------------- self-check
# Fixed synthetic pair: mean / 90th percentile / max of the map measured with a copy of
# NVIDIA's reference Python LDR-FLIP (numpy version, clamp-to-edge borders, ppd 67.0).
# Ours agree to <= 2e-6 on these (the maps differ by <= 2e-5, mostly from the RGB->XYZ
# matrix derived here from the sRGB chromaticities instead of the reference's rational
# constants, plus its float32 arithmetic). Tolerance 1e-5.
SYNTH_EXPECTED = {"mean": 0.0554805, "p90": 0.0762342, "max": 0.9799495}


def _synthetic_pair():
    h, w = 48, 64
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    ref = np.stack([0.5 + 0.4 * np.sin(xx / 5.0) * np.cos(yy / 7.0),
                    0.5 + 0.4 * np.cos((xx + yy) / 9.0),
                    0.3 + 0.3 * (xx / w)], axis=-1)
    ref[20:28, 30:40] = [0.9, 0.1, 0.2]                 # a saturated block (edges)
    test = ref.copy()
    test[..., 0] += 0.08 * np.sin(xx * 1.7 + yy * 0.9)  # deterministic high-freq "noise"
    test[..., 2] += 0.05 * np.cos(xx * 0.8 - yy * 2.3)
    test[10:14, 5:9] = 1.0                              # a white speck
    return np.clip(ref, 0, 1), np.clip(test, 0, 1)


def selftest():
    rng = np.random.default_rng(7)
    fails = []

    def check(ok, what):
        print(("ok   " if ok else "FAIL ") + what)
        if not ok:
            fails.append(what)
    base = np.clip(rng.random((40, 56, 3)), 0, 1)
    m0 = flip_ldr(base, base)
    check(np.all(m0 == 0.0), "identical images -> 0 everywhere")
    blk, wht = np.zeros((40, 56, 3)), np.ones((40, 56, 3))
    mbw = flip_ldr(blk, wht)
    check(mbw.min() > 0.95 and abs(mbw.mean() - 1.0) < 0.05,
          f"black vs white -> ~1 (mean {mbw.mean():.4f}, min {mbw.min():.4f})")
    smooth = np.stack([0.5 + 0.3 * np.sin(np.arange(56) / 6.0 + k)[None, :] *
                       np.cos(np.arange(40) / 8.0)[:, None] for k in range(3)], -1)
    noise = rng.standard_normal(smooth.shape)
    means = [float(flip_mean(smooth, np.clip(smooth + a * noise, 0, 1)))
             for a in (0.0, 0.01, 0.03, 0.1, 0.3)]
    check(all(b > a for a, b in zip(means, means[1:])),
          "mean error strictly increasing in noise amplitude: " +
          " ".join(f"{m:.4f}" for m in means))
    a, b = rng.random((32, 32, 3)), rng.random((32, 32, 3))
    mab, mba = flip_ldr(a, b), flip_ldr(b, a)
    check(mab.min() >= 0 and mab.max() <= 1 and mba.min() >= 0 and mba.max() <= 1,
          "random pair maps within [0, 1]")
    check(abs(float(mab.mean()) - float(mba.mean())) < 0.02,
          f"roughly symmetric: mean(a,b) {mab.mean():.4f} vs mean(b,a) {mba.mean():.4f}")
    stack = flip_ldr(np.stack([a, base[:32, :32]]), np.stack([b, base[:32, :32]]))
    check(np.allclose(stack[0], mab, atol=1e-12) and np.all(stack[1] == 0),
          "stacked frames == per-frame evaluation")
    r, t = _synthetic_pair()
    ms = flip_ldr(r, t)
    got = {"mean": float(ms.mean()), "p90": float(np.percentile(ms, 90)), "max": float(ms.max())}
    for k, v in SYNTH_EXPECTED.items():
        check(abs(got[k] - v) < 1e-5,
              f"synthetic pair {k} {got[k]:.7f} vs reference implementation {v:.7f}")
    print("selftest:", "FAILED" if fails else "passed")
    return 1 if fails else 0


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--selftest", action="store_true")
    ap.add_argument("--ppd", type=float, default=67.0)
    ap.add_argument("images", nargs="*", help="REF TEST (linear EXR: tonemapped, sRGB)")
    a = ap.parse_args(argv)
    if a.selftest:
        return selftest()
    if len(a.images) != 2:
        ap.error("give --selftest or REF TEST")
    from tools.common import images
    r, t = (tonemap_srgb(images.read_exr(p)[..., :3]) for p in a.images)
    print(f"mean FLIP {float(flip_mean(r, t, a.ppd)):.6f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
