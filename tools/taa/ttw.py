"""post_taa's weights file (.ttw, plugins/post_taa/README.md) read and written with numpy
only (no torch: the tests and the evaluation tools use it; taa_model.py builds its networks
from it).

Version 1: 48-byte header, layer records, payload, FNV-1a checksum. Version 2 is version 1
with header field 44 (reserved in version 1) holding input flags: FLAG_REJECT (the rejection
input channel, in = 10 + hidden) and FLAG_RESET (history reset where the rejection is
certain). A model without flags is written as version 1, so files of the earlier shapes
stay byte-identical."""
import os
import struct

import numpy as np

MAGIC = b"TTAANET\0"
JITTER_SETS = 8
MIX_K = 5
ROLE_BODY, ROLE_KERNEL, ROLE_HIDDEN = 1, 2, 3
ACT_NONE, ACT_RELU, ACT_SOFTMAX = 0, 1, 2
FLAG_REJECT, FLAG_RESET = 1, 2
KNOWN_FLAGS = FLAG_REJECT | FLAG_RESET
HEADER = "<8sIIIIIIIIfI"  # magic, version, header bytes, in, width, hidden, mix k, jitter
                          # sets, layers, motion scale, flags (version 2; 0 in version 1)


class Layer:
    """One convolution: role, in, out, kernel size, sets (1 or 8), activation, weights
    float32 [sets][out][in][k][k] and biases [sets][out]."""

    def __init__(self, role, cin, cout, k, sets, act, weight=None, bias=None):
        self.role, self.cin, self.cout, self.k, self.sets, self.act = role, cin, cout, k, sets, act
        self.weight = (np.zeros((sets, cout, cin, k, k), np.float32) if weight is None
                       else np.asarray(weight, np.float32).reshape(sets, cout, cin, k, k))
        self.bias = (np.zeros((sets, cout), np.float32) if bias is None
                     else np.asarray(bias, np.float32).reshape(sets, cout))


class Model:
    """Header fields and layers of a weights file."""

    def __init__(self, width, hidden, layers, motion_scale=0.125, flags=0):
        self.width, self.hidden, self.layers = width, hidden, layers
        self.motion_scale, self.flags = motion_scale, flags

    @property
    def in_channels(self):
        return 9 + self.hidden + (1 if self.flags & FLAG_REJECT else 0)

    def params(self):
        return sum(l.weight.size + l.bias.size for l in self.layers)

    def flops_per_pixel(self):
        """Table 5.1: (2 K^2 I O + O) per layer, one weight set per frame."""
        return sum(2 * l.k * l.k * l.cin * l.cout + l.cout for l in self.layers)


def fnv1a(data):
    """FNV-1a 32 (the file's checksum)."""
    h = 2166136261
    for b in bytes(data):
        h = ((h ^ b) * 16777619) & 0xFFFFFFFF
    return h


def encode(model):
    """The file's bytes."""
    ls = model.layers
    version = 2 if model.flags else 1
    header = struct.pack(HEADER, MAGIC, version, 48 + 24 * len(ls), model.in_channels,
                         model.width, model.hidden, MIX_K, JITTER_SETS, len(ls),
                         model.motion_scale, model.flags)
    table = b"".join(struct.pack("<IIIIII", l.role, l.cin, l.cout, l.k, l.sets, l.act) for l in ls)
    payload = b"".join(l.weight.astype("<f4").tobytes() + l.bias.astype("<f4").tobytes()
                       for l in ls)
    return header + table + payload + struct.pack("<I", fnv1a(payload))


def write(model, path):
    """Writes atomically (a reader never sees half a file)."""
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(encode(model))
    os.replace(tmp, path)


def decode(data, source="weights"):
    """Parses bytes; ValueError naming `source` and the problem (the C reader's checks)."""
    if len(data) < 48 or data[:8] != MAGIC:
        raise ValueError(f"{source}: not a post_taa weights file")
    (_, version, hbytes, cin, width, hidden, mix_k, sets, nl, ms, flags) = struct.unpack_from(
        HEADER, data, 0)
    if version not in (1, 2):
        raise ValueError(f"{source}: weights format version {version} is not supported")
    if version == 1:
        flags = 0
    if flags & ~KNOWN_FLAGS or (flags & FLAG_RESET and not flags & FLAG_REJECT):
        raise ValueError(f"{source}: unknown input flags {flags:#x}")
    if mix_k != MIX_K or sets != JITTER_SETS or hbytes != 48 + 24 * nl or len(data) < hbytes:
        raise ValueError(f"{source}: bad header")
    layers, off = [], hbytes
    for i in range(nl):
        role, li, lo, k, s, act = struct.unpack_from("<IIIIII", data, 48 + 24 * i)
        nw, nb = s * lo * li * k * k, s * lo
        if off + 4 * (nw + nb) > len(data) - 4:
            raise ValueError(f"{source}: truncated")
        w = np.frombuffer(data, "<f4", nw, off).copy()
        b = np.frombuffer(data, "<f4", nb, off + 4 * nw).copy()
        off += 4 * (nw + nb)
        layers.append(Layer(role, li, lo, k, s, act, w, b))
    if off + 4 != len(data):
        raise ValueError(f"{source}: {len(data) - off - 4} bytes after the layers")
    if struct.unpack_from("<I", data, off)[0] != fnv1a(data[hbytes:off]):
        raise ValueError(f"{source}: checksum mismatch")
    m = Model(width, hidden, layers, ms, flags)
    if m.in_channels != cin:
        raise ValueError(f"{source}: in {cin} does not match hidden {hidden} and flags {flags}")
    return m


def read(path):
    with open(path, "rb") as f:
        return decode(f.read(), path)
