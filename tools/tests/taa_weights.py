"""tools/taa's torch-free halves of the network (run with torch blocked, as every test):
- ttw.py: the shipped weights decode and re-encode byte-identically; a network with 0 hidden
  channels and 8 jitter sets in every layer, and one with the rejection input + reset flags
  (a version-2 file), round-trip exactly; cut, corrupted or unknown files raise a
  ValueError naming the file;
- rejection.py: the synthetic disocclusion of plugins/post_taa/tests/taa_net.c (a square at depth 4 moving 6
  pixels right over a plane at depth 10) marks exactly the disoccluded rectangle, as the C
  plugin does; off-screen history is rejected; without prevdepth only off-screen is;
- blend_weights.py: 0 and 1 give the two files back bit for bit, 0.5 their mean; files of
  different shapes are refused."""
import os
import sys

import numpy as np

from tools.taa import blend_weights, rejection, ttw

from tools.tests import checks
from tools.tests.checks import check

root = os.environ.get("TT_SOURCE_ROOT", ".")


def random_model(width, hidden, sets, flags, seed):
    rng = np.random.default_rng(seed)
    cin = 9 + hidden + (1 if flags & ttw.FLAG_REJECT else 0)
    layers = []
    for i, k in enumerate((3, 3, 5)):
        layers.append(ttw.Layer(ttw.ROLE_BODY, cin, width, k, sets if i else 1, ttw.ACT_RELU,
                                rng.standard_normal((sets if i else 1) * width * cin * k * k),
                                rng.standard_normal((sets if i else 1) * width)))
        cin = width
    layers.append(ttw.Layer(ttw.ROLE_KERNEL, width, 50, 5, sets, ttw.ACT_SOFTMAX,
                            rng.standard_normal(sets * 50 * width * 25),
                            rng.standard_normal(sets * 50)))
    if hidden:
        layers.append(ttw.Layer(ttw.ROLE_HIDDEN, width, hidden, 1, sets, ttw.ACT_NONE,
                                rng.standard_normal(sets * hidden * width),
                                rng.standard_normal(sets * hidden)))
    return ttw.Model(width, hidden, layers, 0.125, flags)


def same(a, b):
    return (a.width == b.width and a.hidden == b.hidden and a.flags == b.flags and
            a.motion_scale == b.motion_scale and len(a.layers) == len(b.layers) and
            all((x.role, x.cin, x.cout, x.k, x.sets, x.act) == (y.role, y.cin, y.cout, y.k, y.sets, y.act)
                and np.array_equal(x.weight, y.weight) and np.array_equal(x.bias, y.bias)
                for x, y in zip(a.layers, b.layers)))


def expect_error(data, needle, what):
    try:
        ttw.decode(data, "bad.ttw")
        check(False, f"{what}: accepted")
    except ValueError as e:
        check("bad.ttw" in str(e) and needle in str(e), f"{what}: {e}")


def test_format():
    wdir = os.path.join(root, "plugins", "post_taa")
    shipped = sorted(n for n in os.listdir(wdir) if n.endswith(".ttw"))
    check(len(shipped) >= 2, f"shipped weights: {', '.join(shipped)}")
    for n in shipped:
        data = open(os.path.join(wdir, n), "rb").read()
        m = ttw.decode(data, n)
        check(ttw.encode(m) == data, f"{n}: decode + encode is byte-identical "
              f"(width {m.width}, hidden {m.hidden}, flags {m.flags}, {m.params()} params, "
              f"{m.flops_per_pixel()} FLOP/px)")
    for label, (width, hidden, sets, flags) in {
            "hidden 0, 8 jitter sets, 12 channels": (12, 0, 8, 0),
            "hidden 0, 8 jitter sets, 6 channels": (6, 0, 8, 0),
            "hidden 0, rejection input + reset": (6, 0, 8, ttw.FLAG_REJECT | ttw.FLAG_RESET)}.items():
        m = random_model(width, hidden, sets, flags, 5)
        data = ttw.encode(m)
        back = ttw.decode(data, label)
        check(same(m, back) and data[8] == (2 if flags else 1),
              f"round trip, {label}: {len(data)} bytes, version {data[8]}")
    data = bytearray(ttw.encode(random_model(6, 0, 8, 0, 6)))
    expect_error(bytes(data[:-10]), "truncated", "cut short")
    expect_error(bytes(data[:30]), "not a post_taa weights file", "header cut short")
    bad = bytearray(data)
    bad[-40] ^= 0x10
    expect_error(bytes(bad), "checksum", "flipped payload bit")
    bad = bytearray(data)
    bad[8] = 3
    expect_error(bytes(bad), "version 3", "unknown version")
    bad = bytearray(data)
    bad[8], bad[44] = 2, 4
    expect_error(bytes(bad), "flags", "unknown input flag")
    expect_error(bytes(data) + b"configs 1 0", "11 bytes after the layers", "appended bytes")


def square_frames():
    h, w = 32, 48
    ys, xs = np.mgrid[0:h, 0:w]
    sq0 = (xs >= 12) & (xs < 24) & (ys >= 8) & (ys < 20)
    sq1 = (xs >= 18) & (xs < 30) & (ys >= 8) & (ys < 20)
    d0 = np.where(sq0, 4.0, 10.0).astype(np.float32)
    d1 = np.where(sq1, 4.0, 10.0).astype(np.float32)
    mo = np.zeros((h, w, 2), np.float32)
    mo[..., 0] = np.where(sq1, -6.0, 0.0)
    return d0, d1, mo, (xs >= 12) & (xs < 18) & (ys >= 8) & (ys < 19)


def test_rejection():
    d0, d1, mo, want = square_frames()
    raw, reset = rejection.masks(d0, d1, mo, (0, 0), (0, 0))
    check(np.array_equal(raw, want) and np.array_equal(reset, want),
          f"disocclusion: {int(want.sum())} pixels, raw differs in {int((raw != want).sum())}, "
          f"reset in {int((reset != want).sum())}")
    raw, reset = rejection.masks(d0, None, mo, (0, 0), (0, 0))
    check(not raw.any() and not reset.any(), "without prevdepth nothing on-screen is rejected")
    mo[..., 0] = -6.0
    raw, reset = rejection.masks(d0, None, mo, (0, 0), (0, 0))
    xs = np.mgrid[0:32, 0:48][1]
    check(np.array_equal(raw, xs < 6) and np.array_equal(reset, xs < 6),
          "off-screen history (x < 6 with motion -6) is rejected")
    # thin aliasing geometry: a 2-pixel bar seen only by the previous frame (a 1-pixel one
    # never fills the 2 x 2 samples) is flagged (raw, 1 pixel wide) but too thin for the
    # reset (the 3 x 3 opening)
    d_prev = np.full((32, 48), 10.0, np.float32)
    d_prev[:, 20:22] = 4.0
    raw, reset = rejection.masks(d_prev, np.full((32, 48), 10.0, np.float32),
                                 np.zeros((32, 48, 2), np.float32), (0.3, 0.1), (0.3, 0.1))
    check(int(raw.sum()) == 32 and not reset.any(), f"2-pixel bar: raw {int(raw.sum())} "
          f"pixels, reset {int(reset.sum())}")


def test_blend():
    a, b = random_model(6, 5, 8, 0, 11), random_model(6, 5, 8, 0, 12)
    check(same(blend_weights.blend(a, b, 0.0), a) and same(blend_weights.blend(a, b, 1.0), b),
          "blend 0 / 1: the two files bit for bit")
    m = blend_weights.blend(a, b, 0.5)
    check(all(np.allclose(x.weight, 0.5 * (y.weight + z.weight), atol=1e-6)
              and np.allclose(x.bias, 0.5 * (y.bias + z.bias), atol=1e-6)
              for x, y, z in zip(m.layers, a.layers, b.layers)), "blend 0.5: the mean")
    try:
        blend_weights.blend(a, random_model(12, 5, 8, 0, 13), 0.5)
        check(False, "blend of different shapes: accepted")
    except SystemExit as e:
        check("different shapes" in str(e), f"blend of different shapes refused: {e}")


def main():
    test_format()
    test_rejection()
    test_blend()
    print(f"taa_weights: {checks.failures} failed")
    return 1 if checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
