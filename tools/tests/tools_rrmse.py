"""tools.common.images and the C library agree on tunetrace's one rRMSE: images.rrmse
and images.luminance against tt_rrmse / tt_luminance of libtunetrace (ctypes), on random
images with dark and bright pixels, plus a value known in closed form."""
import ctypes
import os
import sys

import numpy as np

from tools.common import images


def main():
    lib = ctypes.CDLL(os.path.join(os.environ.get("TT_BUILD_ROOT", "build"), "core",
                                   "libtunetrace.so"))
    lib.tt_rrmse.restype = ctypes.c_double
    lib.tt_rrmse.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t]
    lib.tt_luminance.restype = None
    lib.tt_luminance.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_size_t,
                                 ctypes.c_void_p]
    fails = 0
    rng = np.random.default_rng(7)
    for trial in range(5):
        h, w = 17 + trial, 23
        img = (rng.random((h, w, 3)) ** 3 * 4).astype(np.float32)   # many dark pixels
        ref_rgb = (rng.random((h, w, 3)) ** 3 * 4).astype(np.float32)
        ref_lum = np.empty((h, w), dtype=np.float64)
        lib.tt_luminance(ref_rgb.ctypes.data, 3, h * w, ref_lum.ctypes.data)
        py_lum = images.luminance(ref_rgb.astype(np.float64))
        if not np.allclose(ref_lum, py_lum, rtol=1e-12, atol=0):
            print(f"FAIL trial {trial}: luminance differs by {np.abs(ref_lum - py_lum).max()}")
            fails += 1
        c = lib.tt_rrmse(img.ctypes.data, ref_lum.ctypes.data, h * w)
        py = images.rrmse(img.astype(np.float64), ref_lum)
        if abs(c - py) > 1e-12 * c:
            print(f"FAIL trial {trial}: C {c!r} vs Python {py!r}")
            fails += 1
        else:
            print(f"ok   trial {trial}: rRMSE {c:.9f} (C) = {py:.9f} (Python)")
    # closed form: a grey image 0.1 against 0.5 everywhere: 0.4 / sqrt(0.25 + 1e-3)
    grey = np.full((4, 4, 3), 0.1)
    want = 0.4 / np.sqrt(0.25 + 1e-3)
    got = images.rrmse(grey, np.full((4, 4), 0.5))
    if abs(got - want) > 1e-12:
        print(f"FAIL closed form: {got!r} != {want!r}")
        fails += 1
    try:
        images.rrmse(grey, np.zeros((3, 4)))
        print("FAIL: images of different sizes were compared")
        fails += 1
    except ValueError:
        pass
    print(f"tools_rrmse: {fails} failed")
    return 1 if fails else 0


if __name__ == "__main__":
    sys.exit(main())
