"""Reads sequences written by `host --sequence` (manifest.json + EXRs) into numpy arrays
and cuts the training windows of thesis 5.5.2 (8 frames x patch, all batch elements starting
at the same jitter index, channel-swap augmentation).

Training keeps every sequence in memory as one float32 torch tensor (T, 11, H, W) =
[colour 3, reference 3, motion 2, depth/max 1, rejection raw 1, reset 1] (`Sequence.packed`),
so a batch is a handful of tensor slices, no EXR reading and no per-pixel Python;
`cache_dir` stores the decoded arrays as .npz so that later runs (ablations) skip the EXR
decoding. The rejection masks (rejection.py) are computed on whole frames at load (a
patch's history may come from outside the patch); sequences without the prevdepth AOV get
the off-screen test only."""
import hashlib
import json
import os


import numpy as np
import torch

from tools.common.images import read_exr  # noqa: F401  (re-exported: training code reads EXRs here)
from tools.taa import rejection

CACHE_VERSION = "rej2"   # bump when what the cache holds changes


class Sequence:
    """All frames of one sequence folder: color (T,H,W,3) linear, depth_n (T,H,W) depth /
    frame max, motion (T,H,W,2), ref (T,H,W,3) or None, jitter (T,), post (T,H,W,3) or None,
    rej (T,2,H,W) float32 rejection masks [raw, reset] (frames starting fresh: 1)."""

    def __init__(self, folder, key="color", with_ref=True, with_post=True, cache_dir=None):
        man = json.load(open(os.path.join(folder, "manifest.json")))
        self.folder, self.manifest = folder, man
        fr = man["frames"]
        self.jitter = np.array([f["jitter_index"] for f in fr])
        self.reset = np.array([bool(f.get("reset", False)) for f in fr])
        self.jitter_xy = np.array([f.get("jitter", [0.0, 0.0]) for f in fr], np.float32)
        cache = None
        if cache_dir:
            tag = hashlib.sha1((CACHE_VERSION + os.path.abspath(folder) + key + str(with_ref) +
                                str(with_post) +
                                str(os.path.getmtime(os.path.join(folder, "manifest.json")))
                                ).encode()).hexdigest()[:16]
            cache = os.path.join(cache_dir, f"{os.path.basename(os.path.normpath(folder))}_{tag}.npz")
            if os.path.exists(cache):
                z = np.load(cache)
                self.color, self.depth_n, self.motion = z["color"], z["depth_n"], z["motion"]
                self.rej = z["rej"]
                self.ref = z["ref"] if "ref" in z else None
                self.post = z["post"] if "post" in z else None
                return
        self.color = np.stack([read_exr(os.path.join(folder, f[key])) for f in fr])
        depth = np.stack([read_exr(os.path.join(folder, f["depth"]))[..., 0] for f in fr])
        dmax = depth.reshape(len(fr), -1).max(1).clip(min=1e-30)
        self.depth_n = (depth / dmax[:, None, None]).astype(np.float32)
        self.motion = np.stack([read_exr(os.path.join(folder, f["motion"]))[..., :2] for f in fr])
        zprev = (np.stack([read_exr(os.path.join(folder, f["prev_depth"]))[..., 0] for f in fr])
                 if "prev_depth" in fr[0] else None)
        raw, rst = rejection.sequence_masks(depth, zprev, self.motion, self.jitter_xy, self.reset)
        self.rej = np.stack([raw, rst], 1)
        self.ref = (np.stack([read_exr(os.path.join(folder, f["reference"])) for f in fr])
                    if with_ref and "reference" in fr[0] else None)
        self.post = (np.stack([read_exr(os.path.join(folder, f["post"])) for f in fr])
                     if with_post and "post" in fr[0] else None)
        if cache:
            os.makedirs(cache_dir, exist_ok=True)
            arrs = {"color": self.color, "depth_n": self.depth_n, "motion": self.motion,
                    "rej": self.rej}
            if self.ref is not None:
                arrs["ref"] = self.ref
            if self.post is not None:
                arrs["post"] = self.post
            tmp = f"{cache}.{os.getpid()}.tmp.npz"   # runs side by side write their own
            np.savez(tmp, **arrs)
            os.replace(tmp, cache)

    def packed(self):
        """(T, 11, H, W) float32 tensor: colour, reference, motion, depth_n, rejection masks."""
        a = np.concatenate([self.color, self.ref, self.motion, self.depth_n[..., None],
                            self.rej.transpose(0, 2, 3, 1)], -1)
        return torch.from_numpy(np.ascontiguousarray(a.transpose(0, 3, 1, 2)))


class TensorWindows:
    """Training windows (thesis 5.5.2) cut from the preloaded tensors: per batch one start
    jitter index j0; per element a sequence (probability proportional to `weights`, default
    uniform), a start frame with jitter index j0, a patch position, a colour permutation
    applied to colour and reference alike. Yields (colour, depth_n, motion, reference, j0,
    rejection masks), tensors (N, T, C, P, P)."""

    def __init__(self, seqs, batch, frames, patch, rng, weights=None):
        self.data = [s.packed() for s in seqs]
        self.jit = [s.jitter for s in seqs]
        self.batch, self.frames, self.patch, self.rng = batch, frames, patch, rng
        w = np.ones(len(seqs)) if weights is None else np.asarray(weights, float)
        self.p = w / w.sum()
        self.starts = [[np.array([t for t in range(d.shape[0] - frames + 1) if jit[t] == j])
                        for j in range(8)] for d, jit in zip(self.data, self.jit)]

    def __iter__(self):
        return self

    def __next__(self):
        rng, P, F = self.rng, self.patch, self.frames
        j0 = int(rng.integers(0, 8))
        out = torch.empty(self.batch, F, 11, P, P)
        for b in range(self.batch):
            si = int(rng.choice(len(self.data), p=self.p))
            d = self.data[si]
            st = self.starts[si][j0]
            t = int(st[int(rng.integers(0, len(st)))])
            H, W = d.shape[2], d.shape[3]
            y = int(rng.integers(0, H - P + 1))
            x = int(rng.integers(0, W - P + 1))
            perm = rng.permutation(3)
            ch = torch.from_numpy(np.concatenate([perm, 3 + perm, [6, 7, 8, 9, 10]]))
            out[b] = d[t:t + F, :, y:y + P, x:x + P].index_select(1, ch)
        return (out[:, :, 0:3], out[:, :, 8:9], out[:, :, 6:8], out[:, :, 3:6], j0,
                out[:, :, 9:11])
