"""Reads sequences written by `host --sequence` (manifest.json + EXRs) into numpy arrays
and cuts the training windows of thesis 5.5.2 (8 frames x patch, all batch elements starting
at the same jitter index, channel-swap augmentation)."""
import json
import os

import numpy as np
import OpenImageIO as oiio


def read_exr(path):
    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise IOError(f"{path}: {oiio.geterror()}")
    px = inp.read_image("float")
    inp.close()
    return np.asarray(px, dtype=np.float32)


class Sequence:
    """All frames of one sequence folder: color (T,H,W,3) linear, depth_n (T,H,W) depth /
    frame max, motion (T,H,W,2), ref (T,H,W,3) or None, jitter (T,), post (T,H,W,3) or None."""

    def __init__(self, folder, key="color", with_ref=True):
        man = json.load(open(os.path.join(folder, "manifest.json")))
        self.folder, self.manifest = folder, man
        fr = man["frames"]
        self.jitter = np.array([f["jitter_index"] for f in fr])
        self.color = np.stack([read_exr(os.path.join(folder, f[key])) for f in fr])
        depth = np.stack([read_exr(os.path.join(folder, f["depth"]))[..., 0] for f in fr])
        dmax = depth.reshape(len(fr), -1).max(1).clip(min=1e-30)
        self.depth_n = (depth / dmax[:, None, None]).astype(np.float32)
        self.motion = np.stack([read_exr(os.path.join(folder, f["motion"])) for f in fr])
        self.ref = (np.stack([read_exr(os.path.join(folder, f["reference"])) for f in fr])
                    if with_ref and "reference" in fr[0] else None)
        self.post = (np.stack([read_exr(os.path.join(folder, f["post"])) for f in fr])
                     if "post" in fr[0] else None)


def windows(seqs, batch, frames, patch, rng):
    """Yields (color, depth_n, motion, ref, jitter0) batches shaped (N,T,C,P,P) float32."""
    while True:
        j0 = int(rng.integers(0, 8))
        cs, ds, ms, rs = [], [], [], []
        for _ in range(batch):
            s = seqs[int(rng.integers(0, len(seqs)))]
            T, H, W = s.color.shape[:3]
            starts = [t for t in range(T - frames + 1) if s.jitter[t] == j0]
            t = starts[int(rng.integers(0, len(starts)))]
            y = int(rng.integers(0, H - patch + 1))
            x = int(rng.integers(0, W - patch + 1))
            sl = (slice(t, t + frames), slice(y, y + patch), slice(x, x + patch))
            perm = rng.permutation(3)   # channel swapping augmentation
            cs.append(s.color[sl][..., perm])
            rs.append(s.ref[sl][..., perm])
            ds.append(s.depth_n[sl][..., None])
            ms.append(s.motion[sl])
        f = lambda a: np.ascontiguousarray(np.stack(a).transpose(0, 1, 4, 2, 3))
        yield f(cs), f(ds), f(ms), f(rs), j0
