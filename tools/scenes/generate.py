"""Procedural benchmark scenes for tunetrace (issue 5), each written as scene.json v1
(scenes/README.md, "Procedural scenes"). Python 3 + numpy (Debian python3-numpy) only.

  G="/usr/bin/python3 -m tools.scenes.generate"   # from the repository root
  $G voxel OUTDIR [--size 512] [--height 64] [--seed 1] [--trees 0.004]
      Minecraft-like open terrain of unit boxes from seeded fractal value noise (grass, dirt,
      stone, sand, snow, trees); only faces between a solid and an empty cell are emitted.
      Writes OUTDIR/voxel_<material>.ply (binary) and OUTDIR/scene.json with a sky
      environment, a sun (distant light) and a 100-sample camera path (open and occluded
      views). --size 512: ~1.5M triangles.
  $G cylinder SCENE.json OUT.json [--theta 30] [--axis 0 0 1] [--radius 0.002]
      [--segments 8]
      The rotating thin cylinder of thesis 3.2.3: an open cylinder of `segments` long thin
      quads, length half the scene's bounding-box diagonal, radius `radius` x length, centred
      on the scene's bounds, along +x rotated by theta degrees about `axis`, inserted into a
      copy of SCENE.json (mesh files keep referring to the original files).
  $G tessellated OUTDIR [--level 8] [--seed 1]
      A noise-displaced icosphere (level 8: 1,310,720 triangles) on a floor; writes
      OUTDIR/object.ply, OUTDIR/far.json (object a few pixels tall) and OUTDIR/near.json
      (object fills the view); both carry the same far-to-near camera path.
  $G cornell-variants OUTDIR [--base scenes/cornell-box/scene.json]
      The Cornell-box variants of thesis 4.4 (the two blocks' materials change):
      OUTDIR/{specular-plastic,box-plastic,specular-box}/scene.json, with a camera path.
"""
import argparse
import copy
import math
import os

import numpy as np

from tools.scenes import scenelib as sl

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


# ---------------------------------------------------------------------------------------------
# (1) voxel world

VOXEL_MATERIALS = {   # block id -> (name, material)
    1: ("stone", {"type": "diffuse", "albedo": [0.42, 0.42, 0.43]}),
    2: ("dirt", {"type": "diffuse", "albedo": [0.40, 0.27, 0.16]}),
    3: ("grass", {"type": "diffuse", "albedo": [0.22, 0.48, 0.12]}),
    4: ("sand", {"type": "diffuse", "albedo": [0.78, 0.72, 0.50]}),
    5: ("snow", {"type": "diffuse", "albedo": [0.90, 0.91, 0.93]}),
    6: ("wood", {"type": "diffuse", "albedo": [0.38, 0.25, 0.12]}),
    7: ("leaves", {"type": "diffuse", "albedo": [0.12, 0.36, 0.08]}),
}


def voxel_heightmap(size, height, seed):
    x, z = np.meshgrid(np.arange(size, dtype=np.float64), np.arange(size, dtype=np.float64),
                       indexing='ij')
    n = sl.fbm3(x / 90.0, z / 90.0, np.full_like(x, 0.37), seed, octaves=5)
    ridge = sl.fbm3(x / 40.0 + 17.3, z / 40.0 - 5.1, np.full_like(x, 3.1), seed + 7, octaves=3)
    n = n + 0.25 * (ridge - 0.5)
    lo, hi = np.percentile(n, 1), np.percentile(n, 99.5)   # value noise clusters at 0.5
    n = np.clip((n - lo) / (hi - lo), 0, 1)
    h = 3 + n ** 1.4 * (height - 14)
    return np.clip(np.round(h), 1, height - 10).astype(np.int32)


def voxel_grid(size, height, seed, tree_density):
    hm = voxel_heightmap(size, height, seed)
    y = np.arange(height, dtype=np.int32)[None, :, None]
    h = hm[:, None, :]
    grid = np.zeros((size, height, size), dtype=np.uint8)
    depth = h - 1 - y   # 0 at the top block
    solid = y < h
    grid[solid] = 1
    grid[solid & (depth < 4)] = 2
    top = solid & (depth == 0)
    sand = hm[:, None, :] <= 12
    snow = hm[:, None, :] >= height - 22
    grid[top] = 3
    grid[top & sand] = 4
    grid[solid & (depth < 3) & sand] = 4
    grid[top & snow] = 5
    # trees on grass
    rng = np.random.default_rng(seed)
    cand = (hm > 12) & (hm < height - 22)
    cand[:3, :] = cand[-3:, :] = cand[:, :3] = cand[:, -3:] = False
    pick = cand & (rng.random(hm.shape) < tree_density)
    for tx, tz in zip(*np.nonzero(pick)):
        base = int(hm[tx, tz])
        trunk = int(rng.integers(4, 7))
        if base + trunk + 3 >= height:
            continue
        top_y = base + trunk
        for dx in range(-2, 3):
            for dz in range(-2, 3):
                for dy in range(-2, 2):
                    if dx * dx + dz * dz + dy * dy * 2 <= 6:
                        cx, cy, cz = tx + dx, top_y + dy, tz + dz
                        if grid[cx, cy, cz] == 0:
                            grid[cx, cy, cz] = 7
        grid[tx, base:top_y, tz] = 6
    return grid, hm


def voxel_faces(grid):
    """Exposed faces per block id: {id: (corner vertex ids (n x 4), )} with CCW winding seen
    from outside. Faces on the world's bottom (y = 0) are not emitted (nothing sees them)."""
    sx, sy, sz = grid.shape
    solid = grid > 0
    out = {}
    gid = lambda x, y, z: (x.astype(np.int64) * (sy + 1) + y) * (sz + 1) + z
    # (axis, sign): u, v axes such that u x v = +axis
    uv = {0: (1, 2), 1: (2, 0), 2: (0, 1)}
    for axis in range(3):
        for sign in (-1, 1):
            nb = np.zeros_like(solid)   # neighbour solid?
            src = [slice(None)] * 3
            dst = [slice(None)] * 3
            if sign > 0:
                dst[axis] = slice(0, -1)
                src[axis] = slice(1, None)
            else:
                dst[axis] = slice(1, None)
                src[axis] = slice(0, -1)
            nb[tuple(dst)] = solid[tuple(src)]
            exposed = solid & ~nb
            if axis == 1 and sign < 0:
                exposed[:, 0, :] = False
            idx = np.nonzero(exposed)
            if not len(idx[0]):
                continue
            ids = grid[idx]
            base = [idx[0].astype(np.int64), idx[1].astype(np.int64), idx[2].astype(np.int64)]
            base[axis] = base[axis] + (1 if sign > 0 else 0)
            u, v = uv[axis]
            corners = []
            for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                c = list(base)
                c[u] = c[u] + du
                c[v] = c[v] + dv
                corners.append(gid(*c))
            quad = np.stack(corners, axis=1)
            if sign < 0:
                quad = quad[:, ::-1]
            for b in np.unique(ids):
                out.setdefault(int(b), []).append(quad[ids == b])
    return {b: np.concatenate(q) for b, q in out.items()}


def path_samples(keys, n=100):
    """Camera positions at n samples of a path, as tt_scene_camera_at computes them
    (cubic Hermite, Catmull-Rom tangents scaled to the key spacing)."""
    t0, t1 = keys[0]["time"], keys[-1]["time"]
    times = [k["time"] for k in keys]
    out = []
    for i in range(n):
        t = t0 + (t1 - t0) * i / (n - 1)
        out.append(hermite_eval(keys, times, t, "position"))
    return np.array(out)


def hermite_eval(keys, times, t, field):
    n = len(keys)
    if n == 1 or t <= times[0]:
        return np.array(keys[0][field], dtype=np.float64)
    if t >= times[-1]:
        return np.array(keys[-1][field], dtype=np.float64)
    i = 0
    while i + 2 < n and t >= times[i + 1]:
        i += 1
    a, b, c = max(i - 1, 0), i, i + 1
    d = min(i + 2, n - 1)
    P = [np.array(keys[j][field], dtype=np.float64) for j in (a, b, c, d)]
    ta, tb, tc, td = times[a], times[b], times[c], times[d]
    h = tc - tb
    u = (t - tb) / h
    m1 = (P[2] - P[0]) / (tc - ta) * h if tc > ta else P[2] - P[1]
    m2 = (P[3] - P[1]) / (td - tb) * h if td > tb else P[2] - P[1]
    h00 = 2 * u ** 3 - 3 * u ** 2 + 1
    h10 = u ** 3 - 2 * u ** 2 + u
    h01 = -2 * u ** 3 + 3 * u ** 2
    h11 = u ** 3 - u ** 2
    return h00 * P[1] + h10 * m1 + h01 * P[2] + h11 * m2


def voxel_path(hm, height):
    s = hm.shape[0]
    g = lambda x, z: float(hm[int(np.clip(x, 0, s - 1)), int(np.clip(z, 0, s - 1))])
    # low keys: in the lowest spot of a window (a valley between hills: occluded views)
    def valley(cx, cz, r):
        x0, x1 = int(max(cx - r, 2)), int(min(cx + r, s - 3))
        z0, z1 = int(max(cz - r, 2)), int(min(cz + r, s - 3))
        win = hm[x0:x1, z0:z1]
        i, j = np.unravel_index(np.argmin(win), win.shape)
        return x0 + i + 0.5, z0 + j + 0.5
    poses = []
    # 0: high above a corner, overview of the whole world (open)
    poses.append(([-0.08 * s, height * 2.2, -0.08 * s], [0.5 * s, 0.0, 0.5 * s]))
    # 1: descending towards the first valley
    vx, vz = valley(0.3 * s, 0.35 * s, 0.12 * s)
    poses.append(([vx - 0.1 * s, g(vx, vz) + 22, vz - 0.1 * s], [vx, g(vx, vz), vz]))
    # 2: in the valley, looking along it at eye height (occluded by the hills around)
    poses.append(([vx, g(vx, vz) + 2.6, vz], [vx + 0.15 * s, g(vx, vz) + 3, vz + 0.1 * s]))
    # 3: a second valley further on
    wx, wz = valley(0.6 * s, 0.55 * s, 0.12 * s)
    poses.append(([wx, g(wx, wz) + 2.6, wz], [wx + 0.1 * s, g(wx, wz) + 6, wz + 0.15 * s]))
    # 4: climbing over the far side (open again)
    poses.append(([0.8 * s, height * 1.3, 0.75 * s], [0.45 * s, 0.2 * height, 0.45 * s]))
    # 5: high above the opposite corner, looking back
    poses.append(([1.08 * s, height * 2.0, 1.05 * s], [0.5 * s, 0.0, 0.5 * s]))
    keys = sl.path_keys(poses, 2.0)
    # lift keys until no sample of the 100 dips under the terrain (+1.5 blocks)
    for _ in range(40):
        pts = path_samples(keys)
        bad = [i for i, p in enumerate(pts) if 0 <= p[0] < s and 0 <= p[2] < s and
               p[1] < g(p[0], p[2]) + 1.5]
        if not bad:
            break
        times = [k["time"] for k in keys]
        t = keys[-1]["time"] * bad[0] / 99.0
        j = min(range(len(keys)), key=lambda k: abs(times[k] - t))
        keys[j]["position"][1] = round(keys[j]["position"][1] + 1.5, 4)
    return keys


def cmd_voxel(a):
    os.makedirs(a.outdir, exist_ok=True)
    grid, hm = voxel_grid(a.size, a.height, a.seed, a.trees)
    faces = voxel_faces(grid)
    sx, sy, sz = grid.shape
    meshes, materials, total = [], {}, 0
    for b, quads in sorted(faces.items()):
        name, mat = VOXEL_MATERIALS[b]
        uniq, inv = np.unique(quads.reshape(-1), return_inverse=True)
        inv = inv.reshape(-1, 4)
        z = uniq % (sz + 1)
        y = (uniq // (sz + 1)) % (sy + 1)
        x = uniq // ((sz + 1) * (sy + 1))
        pos = np.stack([x, y, z], axis=1).astype(np.float32)
        tris = np.concatenate([inv[:, [0, 1, 2]], inv[:, [0, 2, 3]]])
        fname = "voxel_%s.ply" % name
        sl.write_ply(os.path.join(a.outdir, fname), pos, tris)
        meshes.append({"name": name, "material": name, "file": fname})
        materials[name] = mat
        total += len(tris)
        print("voxel: %-7s %9d triangles %9d vertices" % (name, len(tris), len(pos)))
    s, H = a.size, a.height
    scene = {
        "_comment": "tools/scenes/generate.py voxel --size %d --height %d --seed %d --trees %g: "
                    "%d triangles (exposed faces of unit boxes only), a sky (constant "
                    "environment) and a sun (distant light)" % (s, H, a.seed, a.trees, total),
        "version": 1,
        "camera": {"position": sl.r3([-0.08 * s, H * 2.2, -0.08 * s]),
                   "target": sl.r3([0.5 * s, 0, 0.5 * s]), "up": [0, 1, 0], "fov": 50,
                   "resolution": [640, 360], "path": voxel_path(hm, H)},
        "render": {"spp": 16, "maxDepth": 3, "seed": 1},
        "materials": materials,
        "meshes": meshes,
        "lights": [{"type": "environment", "radiance": [0.45, 0.6, 0.9]},
                   {"type": "distant", "direction": sl.r3(np.array([-0.45, -0.8, -0.35]) /
                                                          np.linalg.norm([-0.45, -0.8, -0.35])),
                    "irradiance": [3.0, 2.85, 2.5]}],
    }
    sl.save_scene(os.path.join(a.outdir, "scene.json"), scene)
    print("voxel: %d triangles in %d meshes -> %s" % (total, len(meshes),
                                                       os.path.join(a.outdir, "scene.json")))


# ---------------------------------------------------------------------------------------------
# (2) thin cylinder

def cylinder_mesh(center, length, radius, theta, axis, segments):
    ang = np.linspace(0, 2 * math.pi, segments, endpoint=False)
    ring = np.stack([np.zeros_like(ang), radius * np.cos(ang), radius * np.sin(ang)], axis=1)
    p0 = ring + [-length / 2, 0, 0]
    p1 = ring + [length / 2, 0, 0]
    pos = np.concatenate([p0, p1])
    R = sl.axis_angle(axis, theta)
    pos = pos @ R.T + center
    idx = []
    for i in range(segments):
        j = (i + 1) % segments
        # outward facing: (p0[i], p0[j], p1[j]) and (p0[i], p1[j], p1[i])
        idx += [[i, j, segments + j], [i, segments + j, segments + i]]
    nrm = np.concatenate([ring, ring]) / radius
    nrm = nrm @ R.T
    return pos, np.array(idx), nrm


def cmd_cylinder(a):
    scene = sl.load_scene(a.scene)
    src_dir = os.path.dirname(os.path.abspath(a.scene))
    lo, hi = sl.scene_bounds(scene, src_dir)
    diag = float(np.linalg.norm(hi - lo))
    length = diag / 2
    radius = a.radius * length
    pos, idx, nrm = cylinder_mesh((lo + hi) / 2, length, radius, a.theta, a.axis, a.segments)
    out = copy.deepcopy(scene)
    dst_dir = os.path.dirname(os.path.abspath(a.out))
    sl.rebase_files(out, src_dir, dst_dir)
    mat = "thin_cylinder"
    while mat in out["materials"]:
        mat += "_"
    out["materials"][mat] = {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
    out["meshes"].append({"name": "thin_cylinder", "material": mat,
                          "positions": [sl.r3(p, 5) for p in pos],
                          "normals": [sl.r3(n, 5) for n in nrm],
                          "indices": idx.tolist()})
    out["_comment"] = ("%s + the thin cylinder of thesis 3.2.3 (tools/scenes/generate.py "
                       "cylinder --theta %g --axis %s --radius %g --segments %d): length %.6g "
                       "(half the diagonal %.6g), radius %.6g, %d triangles"
                       % (os.path.basename(a.scene), a.theta, " ".join("%g" % v for v in a.axis),
                          a.radius, a.segments, length, diag, radius, len(idx)))
    sl.save_scene(a.out, out)
    print("cylinder: theta %g, length %.6g, radius %.6g, %d triangles -> %s"
          % (a.theta, length, radius, len(idx), a.out))


# ---------------------------------------------------------------------------------------------
# (3) finely tessellated object

def icosphere(level):
    t = (1 + 5 ** 0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]],
                 dtype=np.float64)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9],
                  [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2],
                  [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
                  [8, 6, 7], [9, 8, 1]], dtype=np.int64)
    v /= np.linalg.norm(v, axis=1)[:, None]
    for _ in range(level):
        e = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
        e.sort(axis=1)
        key = e[:, 0] * (len(v) + 1) + e[:, 1]
        uk, inv = np.unique(key, return_inverse=True)
        a_, b_ = uk // (len(v) + 1), uk % (len(v) + 1)
        mid = v[a_] + v[b_]
        mid /= np.linalg.norm(mid, axis=1)[:, None]
        m = len(v) + inv.reshape(3, -1)   # midpoints of edges 01, 12, 20
        v = np.concatenate([v, mid])
        f = np.concatenate([np.stack([f[:, 0], m[0], m[2]], 1), np.stack([f[:, 1], m[1], m[0]], 1),
                            np.stack([f[:, 2], m[2], m[1]], 1), np.stack([m[0], m[1], m[2]], 1)])
    return v, f


def vertex_normals(v, f):
    fn = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.zeros_like(v)
    for k in range(3):
        np.add.at(n, f[:, k], fn)
    return n / np.maximum(np.linalg.norm(n, axis=1)[:, None], 1e-20)


def cmd_tessellated(a):
    os.makedirs(a.outdir, exist_ok=True)
    v, f = icosphere(a.level)
    d = sl.fbm3(v[:, 0] * 2.2 + 5, v[:, 1] * 2.2, v[:, 2] * 2.2, a.seed, octaves=6)
    fine = sl.fbm3(v[:, 0] * 24, v[:, 1] * 24, v[:, 2] * 24, a.seed + 3, octaves=3)
    r = 1 + 0.45 * (d - 0.5) + 0.03 * (fine - 0.5)
    v = v * r[:, None]
    v[:, 1] *= 1.3   # taller than wide, like a statue
    v[:, 1] -= v[:, 1].min()   # rests on y = 0
    n = vertex_normals(v, f)
    sl.write_ply(os.path.join(a.outdir, "object.ply"), v, f, n)
    top = float(v[:, 1].max())
    c = [0.0, top / 2, 0.0]
    materials = {
        "object": {"type": "plastic", "albedo": [0.6, 0.45, 0.3], "alpha": 0.15},
        "floor": {"type": "diffuse", "albedo": 0.5},
        "lamp": {"type": "diffuse", "albedo": 0, "emission": [12, 12, 11]},
    }
    meshes = [
        {"name": "object", "material": "object", "file": "object.ply"},
        {"name": "floor", "material": "floor",
         "positions": [[-200, 0, -200], [200, 0, -200], [200, 0, 200], [-200, 0, 200]],
         "indices": [[0, 2, 1], [0, 3, 2]]},
        {"name": "lamp", "material": "lamp",
         "positions": [[-1.5, 6, -1.5], [1.5, 6, -1.5], [1.5, 6, 1.5], [-1.5, 6, 1.5]],
         "indices": [[0, 1, 2], [0, 2, 3]]},
    ]
    far = ([0.0, top * 0.6, 90.0], c, 30.0)
    near = ([0.9, top * 0.75, 2.6], [0.0, top * 0.55, 0.0], 45.0)
    poses = [far, ([20.0, top * 2, 45.0], c, 30.0), ([6.0, top * 1.5, 10.0], c, 35.0),
             ([-2.5, top * 0.9, 4.0], c, 40.0), near]
    path = sl.path_keys(poses, 2.0)
    for name, pose in (("far", far), ("near", near)):
        scene = {
            "_comment": "tools/scenes/generate.py tessellated --level %d --seed %d: a "
                        "noise-displaced icosphere of %d triangles, camera %s (the path goes "
                        "from far to near)" % (a.level, a.seed, len(f), name),
            "version": 1,
            "camera": {"position": sl.r3(pose[0]), "target": sl.r3(pose[1]), "fov": pose[2],
                       "resolution": [640, 360], "path": path},
            "render": {"spp": 16, "maxDepth": 3, "seed": 1},
            "materials": materials, "meshes": meshes,
            "lights": [{"type": "environment", "radiance": [0.35, 0.4, 0.5]}],
        }
        sl.save_scene(os.path.join(a.outdir, name + ".json"), scene)
    print("tessellated: %d triangles, %d vertices -> %s/{far,near}.json"
          % (len(f), len(v), a.outdir))


# ---------------------------------------------------------------------------------------------
# (4) Cornell-box variants

CORNELL_VARIANTS = {
    # name: (short block material, tall block material), thesis 4.4
    "specular-plastic": ({"type": "plastic", "albedo": [0.73, 0.73, 0.73], "alpha": 0.05,
                          "ior": 1.5},
                         {"type": "mirror", "specular": [0.95, 0.95, 0.95]}),
    "box-plastic": ({"type": "plastic", "albedo": [0.73, 0.73, 0.73], "alpha": 0.08,
                     "ior": 1.5},
                    {"type": "plastic", "albedo": [0.73, 0.73, 0.73], "alpha": 0.08,
                     "ior": 1.5}),
    "specular-box": ({"type": "mirror", "specular": [0.95, 0.95, 0.95]},
                     {"type": "mirror", "specular": [0.95, 0.95, 0.95]}),
}

# Cornell box camera path (mm): the classic view, inside the box towards the blocks, the gap
# between the blocks (occluded), up at the light, and back out.
CORNELL_PATH = [
    ([278, 273, -800], [278, 273, 0], 39.3077),
    ([200, 300, -300], [300, 200, 300], 45),
    ([350, 60, 150], [200, 80, 420], 60),         # low, between the blocks (occluded)
    ([500, 200, 120], [150, 150, 400], 60),       # beside the tall block, looking across
    ([278, 250, 200], [278, 548, 280], 70),       # looking up at the light
    ([278, 273, -800], [278, 273, 0], 39.3077),
]


def cmd_cornell_variants(a):
    base = sl.load_scene(a.base)
    for name, (short_mat, tall_mat) in CORNELL_VARIANTS.items():
        s = copy.deepcopy(base)
        s["_comment"] = ("Cornell-box variant '%s' of thesis 4.4 (tools/scenes/generate.py "
                         "cornell-variants): scenes/cornell-box with the short block %s and "
                         "the tall block %s; everything else unchanged. A camera path of %d "
                         "keys is added." % (name, short_mat["type"], tall_mat["type"],
                                             len(CORNELL_PATH)))
        s["materials"]["short_block"] = short_mat
        s["materials"]["tall_block"] = tall_mat
        for m in s["meshes"]:
            if m["name"] in ("short_block", "tall_block"):
                m["material"] = m["name"]
        s["camera"]["path"] = sl.path_keys(CORNELL_PATH, 2.0)
        path = os.path.join(a.outdir, name, "scene.json")
        sl.save_scene(path, s)
        print("cornell-variants: %s" % path)


def main(argv=None):
    """The command line (argv: its arguments, default sys.argv[1:]); other tools call
    main(["voxel", OUTDIR]) to generate a scene in-process."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("voxel")
    p.add_argument("outdir")
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--height", type=int, default=64)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--trees", type=float, default=0.004)
    p = sub.add_parser("cylinder")
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--theta", type=float, default=30.0)
    p.add_argument("--axis", type=float, nargs=3, default=[0.0, 0.0, 1.0])
    p.add_argument("--radius", type=float, default=0.002)
    p.add_argument("--segments", type=int, default=8)
    p = sub.add_parser("tessellated")
    p.add_argument("outdir")
    p.add_argument("--level", type=int, default=8)
    p.add_argument("--seed", type=int, default=1)
    p = sub.add_parser("cornell-variants")
    p.add_argument("outdir")
    p.add_argument("--base", default=os.path.join(ROOT, "scenes", "cornell-box", "scene.json"))
    a = ap.parse_args(argv)
    if a.cmd == "voxel":
        if a.size < 8 or a.height < 24:
            ap.error("voxel: --size >= 8 and --height >= 24")
        cmd_voxel(a)
    elif a.cmd == "cylinder":
        if a.segments < 3 or not a.radius > 0:
            ap.error("cylinder: --segments >= 3 and --radius > 0")
        cmd_cylinder(a)
    elif a.cmd == "tessellated":
        if not 0 <= a.level <= 10:
            ap.error("tessellated: --level in 0..10")
        cmd_tessellated(a)
    else:
        cmd_cornell_variants(a)


if __name__ == "__main__":
    main()
