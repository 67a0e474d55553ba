"""Reads sequences written by `host --sequence` (manifest.json + EXRs) into numpy arrays
and cuts the training windows of thesis 5.5.2 (8 frames x patch, all batch elements starting
at the same jitter index, channel-swap augmentation).

Training keeps every sequence in memory as one float32 torch tensor (T, 9, H, W) =
[colour 3, reference 3, motion 2, depth/max 1] (`Sequence.packed`), so a batch is a handful
of tensor slices, no EXR reading and no per-pixel Python; `cache_dir` stores the decoded
arrays as .npy so that later runs (ablations) skip the EXR decoding."""
import hashlib
import json
import os

import sys

import numpy as np
import torch

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "common"))
from images import read_exr  # noqa: E402  (re-exported: training code reads EXRs through dataset)


class Sequence:
    """All frames of one sequence folder: color (T,H,W,3) linear, depth_n (T,H,W) depth /
    frame max, motion (T,H,W,2), ref (T,H,W,3) or None, jitter (T,), post (T,H,W,3) or None."""

    def __init__(self, folder, key="color", with_ref=True, with_post=True, cache_dir=None):
        man = json.load(open(os.path.join(folder, "manifest.json")))
        self.folder, self.manifest = folder, man
        fr = man["frames"]
        self.jitter = np.array([f["jitter_index"] for f in fr])
        self.reset = np.array([bool(f.get("reset", False)) for f in fr])
        cache = None
        if cache_dir:
            tag = hashlib.sha1((os.path.abspath(folder) + key + str(with_ref) + str(with_post) +
                                str(os.path.getmtime(os.path.join(folder, "manifest.json")))
                                ).encode()).hexdigest()[:16]
            cache = os.path.join(cache_dir, f"{os.path.basename(os.path.normpath(folder))}_{tag}.npz")
            if os.path.exists(cache):
                z = np.load(cache)
                self.color, self.depth_n, self.motion = z["color"], z["depth_n"], z["motion"]
                self.ref = z["ref"] if "ref" in z else None
                self.post = z["post"] if "post" in z else None
                return
        self.color = np.stack([read_exr(os.path.join(folder, f[key])) for f in fr])
        depth = np.stack([read_exr(os.path.join(folder, f["depth"]))[..., 0] for f in fr])
        dmax = depth.reshape(len(fr), -1).max(1).clip(min=1e-30)
        self.depth_n = (depth / dmax[:, None, None]).astype(np.float32)
        self.motion = np.stack([read_exr(os.path.join(folder, f["motion"])) for f in fr])
        self.ref = (np.stack([read_exr(os.path.join(folder, f["reference"])) for f in fr])
                    if with_ref and "reference" in fr[0] else None)
        self.post = (np.stack([read_exr(os.path.join(folder, f["post"])) for f in fr])
                     if with_post and "post" in fr[0] else None)
        if cache:
            os.makedirs(cache_dir, exist_ok=True)
            arrs = {"color": self.color, "depth_n": self.depth_n, "motion": self.motion}
            if self.ref is not None:
                arrs["ref"] = self.ref
            if self.post is not None:
                arrs["post"] = self.post
            np.savez(cache + ".tmp.npz", **arrs)
            os.replace(cache + ".tmp.npz", cache)

    def packed(self):
        """(T, 9, H, W) float32 tensor: colour, reference, motion, depth_n."""
        a = np.concatenate([self.color, self.ref, self.motion, self.depth_n[..., None]], -1)
        return torch.from_numpy(np.ascontiguousarray(a.transpose(0, 3, 1, 2)))


def windows(seqs, batch, frames, patch, rng):
    """Yields (color, depth_n, motion, ref, jitter0) batches shaped (N,T,C,P,P) float32
    (numpy; the original reader, kept for reference: see `TensorWindows`)."""
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


class TensorWindows:
    """The same windows as `windows` (same sampling: sequence uniformly, a start frame with
    jitter index j0 (one j0 per batch), a patch position, a colour permutation applied to
    colour and reference alike), cut from the preloaded tensors. Sequences are drawn
    with probability proportional to `weights` (default uniform, as `windows`)."""

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
        out = torch.empty(self.batch, F, 9, P, P)
        for b in range(self.batch):
            si = int(rng.choice(len(self.data), p=self.p))
            d = self.data[si]
            st = self.starts[si][j0]
            t = int(st[int(rng.integers(0, len(st)))])
            H, W = d.shape[2], d.shape[3]
            y = int(rng.integers(0, H - P + 1))
            x = int(rng.integers(0, W - P + 1))
            perm = rng.permutation(3)
            ch = torch.from_numpy(np.concatenate([perm, 3 + perm, [6, 7, 8]]))
            out[b] = d[t:t + F, :, y:y + P, x:x + P].index_select(1, ch)
        return out[:, :, 0:3], out[:, :, 8:9], out[:, :, 6:8], out[:, :, 3:6], j0
