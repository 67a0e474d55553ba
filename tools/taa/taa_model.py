"""The thesis' kernel-prediction TAA network (chapter 5.4, Fig. 5.2) in PyTorch, bit-for-bit
the same computation as plugins/post_taa/taa_net.c, plus the weights file writer/reader.

Per frame: tonemap the new colour c/(1+max c); reproject the previous state [rgb, hidden]
with 4x4 Catmull-Rom along the motion vectors (clamped taps); input = [rgb, motion *
motion_scale, depth / max depth, reprojected state]; body convolutions with ReLU and zero
padding; kernel layer -> 50 logits, softmax per pixel; colour mix of eq. 5.3 (25 taps over
the new frame, 25 over the reprojected output, zero padding); 1x1 hidden-state layer.
Layers with 8 weight sets use set (jitter_index mod 8). Models with the rejection input
(flags, ttw.FLAG_REJECT) get one more input channel, the mask of rejection.py; with
ttw.FLAG_RESET the reprojected state is replaced by the fresh-start state where the mask
says reset (plugins/post_taa/taa_reject.c)."""
import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

from tools.taa import ttw
from tools.taa.ttw import (ACT_NONE, ACT_RELU, ACT_SOFTMAX, FLAG_REJECT, FLAG_RESET, JITTER_SETS,  # noqa: F401
                 MIX_K, ROLE_BODY, ROLE_HIDDEN, ROLE_KERNEL, fnv1a)


def tonemap(c):
    """c / (1 + max(r, g, b)) over channel dim 1 (negative values clamped to 0)."""
    c = c.clamp(min=0.0)
    m = c.max(dim=1, keepdim=True).values
    return c / (1.0 + m)


def untonemap(t):
    m = t.clamp(min=0.0).max(dim=1, keepdim=True).values.clamp(max=0.999)
    return t.clamp(min=0.0) / (1.0 - m)


def catmull_rom_reproject(img, motion):
    """Samples img (N,C,H,W) at (x + 0.5 + mx, y + 0.5 + my) with the separable 4x4
    Catmull-Rom kernel, taps clamped to the edge (taa_image.c)."""
    n, c, h, w = img.shape
    ys = torch.arange(h, dtype=img.dtype, device=img.device).view(1, h, 1)
    xs = torch.arange(w, dtype=img.dtype, device=img.device).view(1, 1, w)
    ux = (xs + 0.5 + motion[:, 0]) - 0.5
    uy = (ys + 0.5 + motion[:, 1]) - 0.5
    bx, by = torch.floor(ux), torch.floor(uy)
    fx, fy = ux - bx, uy - by

    def weights(f):
        return [f * (-0.5 + f * (1.0 - 0.5 * f)),
                1.0 + f * f * (-2.5 + 1.5 * f),
                f * (0.5 + f * (2.0 - 1.5 * f)),
                f * f * (-0.5 + 0.5 * f)]

    # One gather of all 16 taps (instead of 16 gathers and 16 read-modify-writes): the
    # separable weights wx[i] * wy[j] are the same products as before, summed over the taps.
    wx, wy = torch.stack(weights(fx), 1), torch.stack(weights(fy), 1)       # (n,4,h,w)
    wt = (wy[:, :, None] * wx[:, None, :]).reshape(n, 1, 16, h * w)         # j-major
    off = torch.arange(-1, 3, device=img.device)
    bxi, byi = bx.long(), by.long()
    xi = (bxi[:, None] + off.view(1, 4, 1, 1)).clamp(0, w - 1)              # (n,4,h,w)
    yi = (byi[:, None] + off.view(1, 4, 1, 1)).clamp(0, h - 1)
    idx = (yi[:, :, None] * w + xi[:, None, :]).reshape(n, 1, 16 * h * w)
    tap = torch.gather(img.reshape(n, c, h * w), 2, idx.expand(n, c, 16 * h * w))
    return (tap.view(n, c, 16, h * w) * wt).sum(2).view(n, c, h, w)


class SetConv(nn.Module):
    """A convolution with 1 or 8 weight sets (chosen by jitter index)."""

    def __init__(self, cin, cout, k, sets, role, act):
        super().__init__()
        self.cin, self.cout, self.k, self.sets, self.role, self.act = cin, cout, k, sets, role, act
        fan_in = cin * k * k
        self.weight = nn.Parameter(torch.randn(sets, cout, cin, k, k) * (2.0 / fan_in) ** 0.5)
        self.bias = nn.Parameter(torch.zeros(sets, cout))

    def forward(self, x, j):
        s = j % JITTER_SETS if self.sets > 1 else 0
        w = self.weight[s]
        if x.is_contiguous(memory_format=torch.channels_last) and self.k > 1:
            w = w.contiguous(memory_format=torch.channels_last)
        return F.conv2d(x, w, self.bias[s], padding=self.k // 2)


class TAANet(nn.Module):
    """width: body channels (12 or 6); hidden: state channels; body: kernel sizes of the
    body layers (thesis: 3, 3, 5); jitter_layers: which layers have 8 sets, a string of
    'b1', 'b2', ..., 'k', 'h' tokens (thesis best: 2-3-K = 'b2 b3 k')."""

    def __init__(self, width=12, hidden=5, body=(3, 3, 5), jitter_layers="b2 b3 k",
                 motion_scale=0.125, flags=0, kernel=5):
        super().__init__()
        self.width, self.hidden, self.motion_scale = width, hidden, motion_scale
        self.flags = flags
        toks = set(jitter_layers.split())
        self.in_channels = 9 + hidden + (1 if flags & FLAG_REJECT else 0)
        layers, cin = [], self.in_channels
        for i, k in enumerate(body):
            sets = JITTER_SETS if f"b{i + 1}" in toks else 1
            layers.append(SetConv(cin, width, k, sets, ROLE_BODY, ACT_RELU))
            cin = width
        self.body = nn.ModuleList(layers)
        # the kernel-prediction layer: a kernel x kernel convolution (thesis: 5) to the
        # 2 x 25 weights of the 5 x 5 colour mix
        self.kernel = SetConv(width, 2 * MIX_K * MIX_K, kernel,
                              JITTER_SETS if "k" in toks else 1, ROLE_KERNEL, ACT_SOFTMAX)
        self.hid = (SetConv(width, hidden, 1, JITTER_SETS if "h" in toks else 1, ROLE_HIDDEN,
                            ACT_NONE) if hidden else None)
        # Training speed only (same computation): NHWC tensors let oneDNN skip its reorders.
        self.channels_last = False

    def init_state(self, tm):
        """State standing in for the previous output on the first frame / after a reset."""
        n, _, h, w = tm.shape
        return torch.cat([tm, tm.new_zeros(n, self.hidden, h, w)], 1)

    def step(self, color, depth_n, motion, state, j, fresh, reject=None):
        """One frame. color: linear (N,3,H,W); depth_n: depth / frame max (N,1,H,W); motion
        (N,2,H,W) pixels; state (N,3+hidden,H,W) or None; reject (N,2,H,W): the rejection
        masks [raw, reset] of rejection.py (models with the rejection input; None: nothing
        rejected); returns (out_tm, new_state)."""
        tm = tonemap(color)
        fresh = fresh or state is None
        fb = self.init_state(tm) if fresh else catmull_rom_reproject(state, motion)
        parts = [tm, motion * self.motion_scale, depth_n, fb]
        if self.flags & FLAG_REJECT:
            if fresh:
                r = tm.new_ones(tm.shape[0], 1, *tm.shape[2:])
            else:
                r = reject[:, 0:1] if reject is not None else tm.new_zeros(tm.shape[0], 1, *tm.shape[2:])
                if self.flags & FLAG_RESET and reject is not None:
                    fb = torch.where(reject[:, 1:2] > 0, self.init_state(tm), fb)
                    parts[3] = fb
            parts.append(r)
        x = torch.cat(parts, 1)
        if self.channels_last:
            x = x.contiguous(memory_format=torch.channels_last)
        for layer in self.body:
            x = F.relu(layer(x, j))
        k = torch.softmax(self.kernel(x, j), dim=1)
        n, _, h, w = tm.shape
        cu = F.unfold(tm, MIX_K, padding=MIX_K // 2).view(n, 3, MIX_K * MIX_K, h, w)
        ru = F.unfold(fb[:, :3], MIX_K, padding=MIX_K // 2).view(n, 3, MIX_K * MIX_K, h, w)
        t = MIX_K * MIX_K
        out = (k[:, None, :t] * cu).sum(2) + (k[:, None, t:] * ru).sum(2)
        parts = [out]
        if self.hid is not None:
            parts.append(self.hid(x, j))
        return out, torch.cat(parts, 1)

    def layers(self):
        return list(self.body) + [self.kernel] + ([self.hid] if self.hid is not None else [])

    def flops_per_pixel(self):
        """Table 5.1: (2 * K^2 * I * O + O) per layer (one weight set is used per frame)."""
        rows = []
        for l in self.layers():
            rows.append((l.role, l.k, l.cin, l.cout, 2 * l.k * l.k * l.cin * l.cout + l.cout))
        return rows


def to_ttw(model):
    """The weights as a ttw.Model (numpy)."""
    return ttw.Model(model.width, model.hidden,
                     [ttw.Layer(l.role, l.cin, l.cout, l.k, l.sets, l.act,
                                l.weight.detach().cpu().numpy(), l.bias.detach().cpu().numpy())
                      for l in model.layers()], model.motion_scale, model.flags)


def save_weights(model, path):
    ttw.write(to_ttw(model), path)


def from_ttw(t):
    """A TAANet holding the weights of a ttw.Model."""
    body = tuple(l.k for l in t.layers if l.role == ROLE_BODY)
    toks = [f"b{i + 1}" for i, l in enumerate(l for l in t.layers if l.role == ROLE_BODY)
            if l.sets > 1]
    toks += ["k" for l in t.layers if l.role == ROLE_KERNEL and l.sets > 1]
    toks += ["h" for l in t.layers if l.role == ROLE_HIDDEN and l.sets > 1]
    kernel = next(l.k for l in t.layers if l.role == ROLE_KERNEL)
    m = TAANet(t.width, t.hidden, body, " ".join(toks), t.motion_scale, t.flags, kernel)
    for dst, src in zip(m.layers(), t.layers):
        dst.weight.data = torch.from_numpy(src.weight.copy()).view_as(dst.weight)
        dst.bias.data = torch.from_numpy(src.bias.copy()).view_as(dst.bias)
    return m


def load_weights(path):
    """Reads a weights file back into a TAANet (for evaluation of exported models)."""
    return from_ttw(ttw.read(path))
