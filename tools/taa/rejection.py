"""History rejection of post_taa's network (plugins/post_taa/taa_reject.c), in numpy with
the same float32 operations, for the training data and the golden fixture.

Pixel p of frame t sees a point that sat at q = p + 0.5 + jitter_t + motion_t in the
previous frame (film coordinates: the host's motion vectors run from the jittered sample
position back to the previous camera). Frame t - 1 sampled its pixel i at i + 0.5 +
jitter_{t-1}, so the 2 x 2 pixels i0 = floor(q - 0.5 - jitter_{t-1}), i0 + 1 (per axis)
are the samples around q; for a plane (1/z affine on the film) the depth at q lies within
their [min, max]. With z' the prevdepth AOV (the depth the point had in the previous
camera) the history is *disoccluded* when
    z' > max(previous depths at the 2 x 2 samples) * (1 + TOL)
(the previous frame saw only nearer surfaces there: an occluder; sky, depth 0, counts as
infinitely far: a sky sample is never nearer, sky now is disoccluded unless a sample was
sky), or *off-screen* when q lies outside the previous frame. The opposite
mismatch (the previous frame saw something farther) cannot happen to an unoccluded point of
a static scene: it is thin geometry aliasing between jitter positions, and the history is
kept there.
`raw` = disoccluded or off-screen: the network's rejection input (0 / 1). `reset`
(models with the reset flag: the history is replaced by the new frame, as after a cut) =
off-screen, or disoccluded in a region that holds a 3 x 3 square (a 3 x 3 opening: one-
or two-pixel flags on thin aliasing geometry keep their history)."""
import numpy as np

TOL = np.float32(0.01)


def masks(dprev, zprev, motion, jitter, jitter_prev):
    """dprev: previous frame's depth (H, W); zprev: this frame's prevdepth AOV (H, W) or
    None (unknown: only the off-screen test); motion (H, W, 2) pixels; jitter,
    jitter_prev: this and the previous frame's (jx, jy). Returns (raw, reset) bool (H, W)."""
    h, w = motion.shape[:2]
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    half = np.float32(0.5)
    qx = (xs + half + np.float32(jitter[0])) + motion[..., 0].astype(np.float32)
    qy = (ys + half + np.float32(jitter[1])) + motion[..., 1].astype(np.float32)
    inside = (qx >= 0) & (qx < np.float32(w)) & (qy >= 0) & (qy < np.float32(h))
    off = ~inside
    if zprev is None:
        return off.copy(), off.copy()
    ux = np.where(inside, (qx - half) - np.float32(jitter_prev[0]), 0)
    uy = np.where(inside, (qy - half) - np.float32(jitter_prev[1]), 0)
    ix = np.floor(ux).astype(np.int64)
    iy = np.floor(uy).astype(np.int64)
    hi = np.full((h, w), -np.inf, np.float32)
    sky = np.zeros((h, w), bool)
    for dy in (0, 1):
        for dx in (0, 1):
            t = dprev[np.clip(iy + dy, 0, h - 1), np.clip(ix + dx, 0, w - 1)].astype(np.float32)
            g = t > 0
            hi = np.where(g, np.maximum(hi, t), hi)
            sky |= ~g
    z = zprev.astype(np.float32)
    with np.errstate(invalid="ignore"):   # a sky sample is farther than anything
        far = ~sky & (~(z > 0) | (z > hi * (np.float32(1) + TOL))) & inside
    return off | far, off | opening(far)


def _morph(m, erode):
    p = np.pad(m, 1, mode="edge")
    h, w = m.shape
    out = np.ones_like(m) if erode else np.zeros_like(m)
    for dy in range(3):
        for dx in range(3):
            if erode:
                out &= p[dy:dy + h, dx:dx + w]
            else:
                out |= p[dy:dy + h, dx:dx + w]
    return out


def opening(m):
    """3 x 3 morphological opening (erosion, then dilation), edge pixels replicated: keeps
    the regions that hold a 3 x 3 square."""
    return _morph(_morph(m, True), False)


def sequence_masks(depth, prev_depth, motion, jitter, reset):
    """Masks of every frame of a sequence: depth, prev_depth (T, H, W) (prev_depth may be
    None), motion (T, H, W, 2), jitter (T, 2), reset (T,) history cuts. Frames that start
    fresh (0 and cuts) reject everything. Returns (raw, reset) float32 (T, H, W)."""
    raw = np.ones(depth.shape, np.float32)
    rst = np.ones(depth.shape, np.float32)
    for t in range(1, depth.shape[0]):
        if reset[t]:
            continue
        r, s = masks(depth[t - 1], None if prev_depth is None else prev_depth[t], motion[t],
                     jitter[t], jitter[t - 1])
        raw[t], rst[t] = r, s
    return raw, rst
