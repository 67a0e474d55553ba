"""Image reading and the error metric shared by the Python tools (OpenImageIO and numpy
only: no torch, so evaluation and charts run with just the packages tools/bootstrap.sh
installs).

rRMSE has one definition in tunetrace, the C function tt_rrmse of
core/include/tunetrace/tuning.h that the tuning objective (`host --objective rrmse`)
minimises; rrmse() here is the same formula, so a tool's figure and a tuning run's cost
compare:

    rRMSE = sqrt(mean over pixels of (L - R)^2 / (R^2 + 1e-3))

with L and R the Rec. 709 luminance of the image and of the reference.

A tool imports it as `from tools.common import images`."""
import numpy as np
import OpenImageIO as oiio

# Rec. 709 luminance weights (tt_luminance) and the rRMSE's guard against black (tt_rrmse).
LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)
RRMSE_EPS = 1e-3


def read_exr(path):
    """All channels of an image file as a float32 array (H, W, C); IOError naming the file."""
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise IOError(f"{path}: {oiio.geterror()}")
    px = inp.read_image("float")
    inp.close()
    if px is None:
        raise IOError(f"{path}: cannot read the pixels ({oiio.geterror()})")
    return np.asarray(px, dtype=np.float32)


def read_rgb(path):
    """Linear RGB of an image file as float32 (H, W, 3): its first three channels, a
    one-channel image repeated; IOError naming the file (also for two channels)."""
    px = read_exr(path)
    if px.ndim == 2:
        px = px[..., None]
    if px.shape[2] == 1:
        return np.repeat(px, 3, axis=2)
    if px.shape[2] < 3:
        raise IOError(f"{path}: expected 1 or 3+ channels (RGB[A]), got {px.shape[2]}")
    return px[..., :3]


def luminance(img):
    """Rec. 709 luminance (H, W) of an RGB image (H, W, 3+); an (H, W) array is returned as
    it is (it already is a luminance)."""
    img = np.asarray(img)
    if img.ndim == 2:
        return img
    wr, wg, wb = LUMINANCE_WEIGHTS
    return wr * img[..., 0] + wg * img[..., 1] + wb * img[..., 2]


def read_luminance(path):
    """Rec. 709 luminance (H, W) of an image file."""
    return luminance(read_rgb(path))


def rrmse(img, ref):
    """tunetrace's rRMSE (module docstring) of `img` against `ref`; each is an RGB image
    (H, W, 3+) or a luminance (H, W) of the same size."""
    L, R = luminance(img), luminance(ref)
    if L.shape != R.shape:
        raise ValueError(f"rrmse: image {L.shape} and reference {R.shape} differ in size")
    return float(np.sqrt(np.mean((L - R) ** 2 / (R ** 2 + RRMSE_EPS))))
