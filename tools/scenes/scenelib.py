"""Shared helpers of the scene tools (tools/scenes/): binary PLY output, reading the geometry of
a scene.json (inline meshes and OBJ/PLY mesh files, with their transforms) for bounds, and
camera path keys. Python 3 + numpy (Debian python3-numpy) only.
"""
import gzip
import json
import math
import os
import struct

import numpy as np


# ---------------------------------------------------------------------------------------------
# PLY

def write_ply(path, positions, indices, normals=None):
    """Binary little-endian PLY: float x y z [nx ny nz], uchar-count int vertex_indices."""
    positions = np.ascontiguousarray(positions, dtype='<f4').reshape(-1, 3)
    indices = np.ascontiguousarray(indices, dtype='<i4').reshape(-1, 3)
    nv, nf = len(positions), len(indices)
    head = ["ply", "format binary_little_endian 1.0", "comment tunetrace tools/scenes",
            "element vertex %d" % nv, "property float x", "property float y", "property float z"]
    if normals is not None:
        head += ["property float nx", "property float ny", "property float nz"]
    head += ["element face %d" % nf, "property list uchar int vertex_indices", "end_header"]
    if normals is not None:
        normals = np.ascontiguousarray(normals, dtype='<f4').reshape(-1, 3)
        vert = np.hstack([positions, normals]).astype('<f4')
    else:
        vert = positions
    faces = np.zeros(nf, dtype=[('n', 'u1'), ('i', '<i4', (3,))])
    faces['n'] = 3
    faces['i'] = indices
    with open(path, 'wb') as f:
        f.write(("\n".join(head) + "\n").encode('ascii'))
        f.write(vert.tobytes())
        f.write(faces.tobytes())


_PLY_TYPES = {'char': 'i1', 'int8': 'i1', 'uchar': 'u1', 'uint8': 'u1', 'short': 'i2',
              'int16': 'i2', 'ushort': 'u2', 'uint16': 'u2', 'int': 'i4', 'int32': 'i4',
              'uint': 'u4', 'uint32': 'u4', 'float': 'f4', 'float32': 'f4', 'double': 'f8',
              'float64': 'f8'}


def read_ply_positions(path):
    """Vertex positions (n x 3 float64) of an ASCII or binary PLY (.ply or .ply.gz)."""
    opener = gzip.open if path.endswith('.gz') else open
    with opener(path, 'rb') as f:
        data = f.read()
    end = data.index(b'end_header')
    end = data.index(b'\n', end) + 1
    header = data[:end].decode('ascii', 'replace').splitlines()
    fmt, elements = 'ascii', []
    for line in header:
        w = line.split()
        if not w:
            continue
        if w[0] == 'format':
            fmt = w[1]
        elif w[0] == 'element':
            elements.append([w[1], int(w[2]), []])
        elif w[0] == 'property' and elements:
            elements[-1][2].append(w[1:])
    body = data[end:]
    if not elements or elements[0][0] != 'vertex':
        raise ValueError('%s: the first PLY element is not "vertex"' % path)
    name, count, props = elements[0]
    if any(p[0] == 'list' for p in props):
        raise ValueError('%s: list property in the vertex element' % path)
    names = [p[-1] for p in props]
    if fmt == 'ascii':
        rows = body.decode('ascii').split('\n', count)[:count]
        arr = np.array([r.split()[:len(names)] for r in rows], dtype=np.float64)
        cols = arr
    else:
        bo = '<' if fmt == 'binary_little_endian' else '>'
        dt = np.dtype([(n, bo + _PLY_TYPES[p[0]]) for n, p in zip(names, props)])
        cols = np.frombuffer(body, dtype=dt, count=count)
        cols = np.stack([cols[n].astype(np.float64) for n in names], axis=1)
    return cols[:, [names.index('x'), names.index('y'), names.index('z')]]


def read_obj_positions(path):
    pts = []
    with open(path, 'r', errors='replace') as f:
        for line in f:
            if line.startswith('v '):
                pts.append([float(v) for v in line.split()[1:4]])
    return np.array(pts, dtype=np.float64).reshape(-1, 3)


# ---------------------------------------------------------------------------------------------
# scene.json geometry

def _rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def axis_angle(axis, deg):
    a = np.asarray(axis, dtype=np.float64)
    a = a / np.linalg.norm(a)
    t = math.radians(deg)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(t) * K + (1 - math.cos(t)) * K @ K


def mesh_matrix(mesh):
    """4x4 object-to-world matrix of a scene.json mesh (transform or matrix)."""
    M = np.eye(4)
    if 'matrix' in mesh:
        M = np.array(mesh['matrix'], dtype=np.float64).reshape(4, 4)
    elif 'transform' in mesh:
        tr = mesh['transform']
        S = tr.get('scale', 1)
        S = np.diag(S if isinstance(S, list) else [S, S, S]).astype(np.float64)
        R = np.eye(3)
        rot = tr.get('rotate')
        if isinstance(rot, list):
            R = _rot_z(math.radians(rot[2])) @ _rot_y(math.radians(rot[1])) @ \
                _rot_x(math.radians(rot[0]))
        elif isinstance(rot, dict):
            R = axis_angle(rot['axis'], rot['angle'])
        M[:3, :3] = R @ S
        M[:3, 3] = tr.get('translate', [0, 0, 0])
    return M


def mesh_positions(mesh, base_dir):
    """World-space positions (n x 3) of one scene.json mesh."""
    if 'file' in mesh:
        path = os.path.join(base_dir, mesh['file'])
        low = path.lower()
        if low.endswith('.ply') or low.endswith('.ply.gz'):
            p = read_ply_positions(path)
        elif low.endswith('.obj'):
            p = read_obj_positions(path)
        else:
            raise ValueError('%s: bounds of this mesh format are not supported here' % path)
    else:
        p = np.array(mesh['positions'], dtype=np.float64).reshape(-1, 3)
    M = mesh_matrix(mesh)
    return p @ M[:3, :3].T + M[:3, 3]


def scene_bounds(scene, base_dir):
    lo = np.full(3, np.inf)
    hi = np.full(3, -np.inf)
    for m in scene['meshes']:
        p = mesh_positions(m, base_dir)
        if len(p):
            lo = np.minimum(lo, p.min(axis=0))
            hi = np.maximum(hi, p.max(axis=0))
    return lo, hi


def load_scene(path):
    with open(path) as f:
        return json.load(f)


def save_scene(path, scene, compact_meshes=True):
    """Writes scene.json; inline mesh arrays go on one line each to keep the file small."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    text = json.dumps(scene, indent=2)
    if compact_meshes:
        # collapse number lists onto single lines
        import re
        text = re.sub(r'\[\s+([-0-9.e, \n]+?)\s+\]',
                      lambda m: '[' + ' '.join(m.group(1).split()) + ']', text)
    with open(path, 'w') as f:
        f.write(text + '\n')


def rebase_files(scene, src_dir, dst_dir):
    """Rewrites relative `file`/`texture`/`image` paths so they resolve from dst_dir."""
    def fix(p):
        if os.path.isabs(p):
            return p
        return os.path.relpath(os.path.join(src_dir, p), dst_dir)
    for m in scene.get('meshes', []):
        if 'file' in m:
            m['file'] = fix(m['file'])
    for mat in scene.get('materials', {}).values():
        if isinstance(mat, dict) and 'texture' in mat:
            mat['texture'] = fix(mat['texture'])
    for l in scene.get('lights', []):
        if 'image' in l:
            l['image'] = fix(l['image'])


# ---------------------------------------------------------------------------------------------
# camera paths

def r3(v, nd=4):
    return [round(float(x), nd) for x in v]


def path_keys(poses, seconds_per_key=2.0, fov=None):
    """Camera path keys from [(position, target), ...] (or (position, target, fov))."""
    keys = []
    for i, pose in enumerate(poses):
        k = {"time": round(i * seconds_per_key, 4), "position": r3(pose[0]),
             "target": r3(pose[1])}
        f = pose[2] if len(pose) > 2 else fov
        if f is not None:
            k["fov"] = round(float(f), 4)
        keys.append(k)
    return keys


# ---------------------------------------------------------------------------------------------
# noise

def _hash3(ix, iy, iz, seed):
    h = (ix.astype(np.int64) * 73856093) ^ (iy.astype(np.int64) * 19349663) ^ \
        (iz.astype(np.int64) * 83492791) ^ (seed * 2654435761)
    h = (h ^ (h >> 13)) * 1274126177
    h = h ^ (h >> 16)
    return (h & 0xFFFFFF).astype(np.float64) / float(0xFFFFFF)


def value_noise3(x, y, z, seed):
    """Smooth value noise in [0, 1] at arrays of points (quintic interpolation)."""
    x0, y0, z0 = np.floor(x), np.floor(y), np.floor(z)
    fx, fy, fz = x - x0, y - y0, z - z0
    ix, iy, iz = x0.astype(np.int64), y0.astype(np.int64), z0.astype(np.int64)
    s = lambda t: t * t * t * (t * (t * 6 - 15) + 10)
    ux, uy, uz = s(fx), s(fy), s(fz)
    out = 0
    for dx in (0, 1):
        wx = ux if dx else 1 - ux
        for dy in (0, 1):
            wy = uy if dy else 1 - uy
            for dz in (0, 1):
                wz = uz if dz else 1 - uz
                out = out + wx * wy * wz * _hash3(ix + dx, iy + dy, iz + dz, seed)
    return out


def fbm3(x, y, z, seed, octaves=5, lacunarity=2.0, gain=0.5):
    """Fractal sum of value noise, normalised to [0, 1]."""
    total, amp, norm, f = 0.0, 1.0, 0.0, 1.0
    for o in range(octaves):
        total = total + amp * value_noise3(x * f, y * f, z * f, seed + 101 * o)
        norm += amp
        amp *= gain
        f *= lacunarity
    return total / norm
