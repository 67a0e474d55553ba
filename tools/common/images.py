"""Image reading shared by the Python tools (OpenImageIO only: no torch, so evaluation and
charts run with just the packages tools/bootstrap.sh installs).

Import it from a tool with
    sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
    import images"""
import numpy as np
import OpenImageIO as oiio


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
