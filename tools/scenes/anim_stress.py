"""Procedural animated stress scene: many rigid objects in motion and a deforming cloth.

Writes one scene.json (inline meshes, no other files) whose every frame changes the
geometry a BVH is built over, for per-frame update tuning (rebuild vs. refit vs. two-level):

- `--objects` small rigid bodies (cubes, octahedra and tetrahedra of varied size) flying on
  seeded Lissajous paths through a shared volume while spinning about their own axes
  (scene.json "animation": cubic keys every 0.5 s, turns of at most 40 degrees per key);
  their paths cross, so the boxes of a refitted BVH overlap more and more over the sequence;
- a `--grid` x `--grid` cloth-like sheet that ripples (scene.json "morph": four targets, the
  sine and cosine of two travelling waves, weighted cos/sin of the wave phase, so the
  weighted sum is the two waves at every key time);
- a floor, an environment and a sun; a camera orbit over the whole duration.

All keys lie inside the camera path's time range, so `host --sequence N --fps F` with
N / F <= --duration plays the scene; the committed scenes/animated-stress/scene.json is the
default (5 s: 120 frames at 24 fps):

  /usr/bin/python3 -m tools.scenes.anim_stress OUT/scene.json [--objects 64] [--grid 20]
      [--duration 5] [--seed 1] [--detail 0]
"""
import argparse
import json
import math
import os

import numpy as np

from tools.scenes import scenelib as sl

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _cube():
    p = [[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]
    # outward faces (counter-clockwise seen from outside)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in quads:
        tris += [[a, b, c], [a, c, d]]
    return p, tris


def _octahedron():
    p = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]]
    tris = [[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]]
    return p, tris


def _tetrahedron():
    p = [[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]]
    tris = [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]]
    return p, tris


SHAPES = [("cube", _cube), ("octahedron", _octahedron), ("tetrahedron", _tetrahedron)]
MATERIALS = {
    "floor": {"type": "diffuse", "albedo": [0.55, 0.55, 0.52]},
    "red": {"type": "diffuse", "albedo": [0.7, 0.15, 0.1]},
    "blue": {"type": "diffuse", "albedo": [0.1, 0.25, 0.7]},
    "yellow": {"type": "diffuse", "albedo": [0.75, 0.6, 0.1]},
    "plastic": {"type": "plastic", "albedo": [0.2, 0.6, 0.3], "alpha": 0.08},
    "cloth": {"type": "diffuse", "albedo": [0.8, 0.78, 0.7]},
}
BODY_MATERIALS = ["red", "blue", "yellow", "plastic"]


def rigid_objects(n, duration, rng, detail=0, key_dt=0.5):
    """n rigid bodies with Lissajous paths inside [-4, 4] x [0.6, 3.4] x [-4, 4]; detail > 0:
    each is an icosphere of that level (20 * 4^detail triangles) squashed along its axes."""
    meshes = []
    times = np.arange(0.0, duration + 1e-9, key_dt)
    if detail > 0:
        from tools.scenes.generate import icosphere
        ico_v, ico_f = icosphere(detail)
    for i in range(n):
        name, make = SHAPES[i % len(SHAPES)]
        p, tris = make()
        size = float(rng.uniform(0.12, 0.35))
        if detail > 0:
            name, tris = "blob", ico_f.tolist()
            p = ico_v * rng.uniform(0.5, 1.3, 3)
        amp = rng.uniform([2.0, 0.6, 2.0], [3.8, 1.3, 3.8])
        centre = np.array([0.0, 2.0, 0.0]) + rng.uniform(-0.3, 0.3, 3)
        omega = rng.uniform(0.4, 1.6, 3) * rng.choice([-1, 1], 3)
        phase = rng.uniform(0, 2 * math.pi, 3)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        spin = float(rng.uniform(30, 80)) * float(rng.choice([-1, 1]))  # degrees per second
        keys = []
        for t in times:
            pos = centre + amp * np.sin(omega * t + phase)
            keys.append({"time": round(float(t), 4), "translate": sl.r3(pos),
                         "rotate": {"axis": sl.r3(axis), "angle": round(spin * float(t), 3)}})
        meshes.append({"name": "%s_%02d" % (name, i),
                       "material": BODY_MATERIALS[i % len(BODY_MATERIALS)],
                       "positions": [sl.r3(np.array(v) * size) for v in p], "indices": tris,
                       "animation": {"interpolation": "cubic", "keys": keys}})
    return meshes


def cloth(grid, duration, key_dt=1.0 / 12):
    """A grid x grid sheet at height 1.2 rippling with two travelling waves (morph targets)."""
    u = np.linspace(-3.0, 3.0, grid)
    x, z = np.meshgrid(u, u, indexing='ij')
    rest = np.stack([x, np.full_like(x, 1.2), z], axis=-1).reshape(-1, 3)
    k1, k2 = 2 * math.pi / 3.0, 2 * math.pi / 2.2   # wave numbers (1/units)
    a1, a2 = 0.35, 0.2                             # amplitudes
    w1, w2 = 2 * math.pi * 0.6, 2 * math.pi * 0.9  # angular speeds (1/s)
    ph1 = (k1 * x).reshape(-1)
    ph2 = (k2 * (0.6 * x + 0.8 * z)).reshape(-1)
    up = np.array([0.0, 1.0, 0.0])

    def target(d):
        return [sl.r3(v) for v in rest + d[:, None] * up]
    # y = a1 sin(k1 x - w1 t) + a2 sin(k2 s - w2 t)
    #   = a1 [sin(k1 x) cos(w1 t) - cos(k1 x) sin(w1 t)] + the same for wave 2
    targets = [{"positions": target(a1 * np.sin(ph1))}, {"positions": target(-a1 * np.cos(ph1))},
               {"positions": target(a2 * np.sin(ph2))}, {"positions": target(-a2 * np.cos(ph2))}]
    keys = []
    for t in np.arange(0.0, duration + 1e-9, key_dt):
        keys.append({"time": round(float(t), 5),
                     "weights": [round(math.cos(w1 * t), 5), round(math.sin(w1 * t), 5),
                                 round(math.cos(w2 * t), 5), round(math.sin(w2 * t), 5)]})
    tris = []
    for i in range(grid - 1):
        for j in range(grid - 1):
            a, b, c, d = i * grid + j, (i + 1) * grid + j, (i + 1) * grid + j + 1, i * grid + j + 1
            tris += [[a, d, c], [a, c, b]]   # facing +y
    return {"name": "cloth", "material": "cloth", "positions": [sl.r3(v) for v in rest],
            "indices": tris,
            "morph": {"targets": targets, "interpolation": "linear", "keys": keys}}


def camera_orbit(duration, n=6):
    keys = []
    for i in range(n):
        t = duration * i / (n - 1)
        a = math.radians(30 + 60 * i / (n - 1))
        pos = [9.5 * math.cos(a), 4.2 + 0.6 * math.sin(2 * a), 9.5 * math.sin(a)]
        keys.append({"time": round(t, 4), "position": sl.r3(pos), "target": [0, 1.5, 0]})
    return keys


def build(objects, grid, duration, seed, detail=0):
    rng = np.random.default_rng(seed)
    meshes = [{"name": "floor", "material": "floor",
               "positions": [[-12, 0, -12], [12, 0, -12], [12, 0, 12], [-12, 0, 12]],
               "indices": [[0, 2, 1], [0, 3, 2]]}]
    meshes += rigid_objects(objects, duration, rng, detail)
    meshes.append(cloth(grid, duration))
    path = camera_orbit(duration)
    return {
        "version": 1,
        "_comment": ("tools/scenes/anim_stress.py --objects %d --grid %d --duration %g --seed %d%s: "
                     "%d rigid bodies on crossing paths and a %dx%d cloth with two travelling "
                     "waves; %g s (%d frames at 24 fps)"
                     % (objects, grid, duration, seed, " --detail %d" % detail if detail else "",
                        objects, grid, grid, duration, round(duration * 24))),
        "camera": {"position": path[0]["position"], "target": path[0]["target"], "fov": 45,
                   "resolution": [320, 240], "path": path},
        "render": {"spp": 16, "maxDepth": 4},
        "materials": MATERIALS,
        "meshes": meshes,
        "lights": [{"type": "environment", "radiance": [0.35, 0.42, 0.55]},
                   {"type": "distant", "direction": [-0.4, -1.0, -0.3], "irradiance": [2.2, 2.0, 1.8]}],
    }


def write_compact(path, scene):
    """scene.json with one line per top-level field and per mesh (small and diffable)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    dump = lambda v: json.dumps(v, separators=(",", ":"))
    lines = []
    for k, v in scene.items():
        if k == "meshes":
            lines.append('"meshes": [\n' + ",\n".join("  " + dump(m) for m in v) + "\n]")
        else:
            lines.append("%s: %s" % (json.dumps(k), dump(v)))
    with open(path, "w") as f:
        f.write("{\n" + ",\n".join(lines) + "\n}\n")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("out", help="scene.json to write")
    p.add_argument("--objects", type=int, default=64, help="rigid bodies (default 64)")
    p.add_argument("--grid", type=int, default=20, help="cloth vertices per side (default 20)")
    p.add_argument("--duration", type=float, default=5.0, help="seconds (default 5)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--detail", type=int, default=0,
                   help="bodies as icospheres of this level, 20 * 4^L triangles each (default 0: "
                        "cubes, octahedra, tetrahedra)")
    a = p.parse_args(argv)
    if a.objects < 0 or a.objects > 100000:
        p.error("--objects: expected 0..100000, got %d" % a.objects)
    if a.grid < 2 or a.grid > 2000:
        p.error("--grid: expected 2..2000 vertices per side, got %d" % a.grid)
    if a.detail < 0 or a.detail > 6:
        p.error("--detail: expected 0..6, got %d" % a.detail)
    if not (math.isfinite(a.duration) and 0.25 <= a.duration <= 3600):
        p.error("--duration: expected 0.25..3600 seconds, got %g" % a.duration)
    scene = build(a.objects, a.grid, a.duration, a.seed, a.detail)
    tmp = a.out + ".tmp"
    write_compact(tmp, scene)
    os.replace(tmp, a.out)   # atomic: a reader never sees half a scene
    tri = sum(len(m["indices"]) for m in scene["meshes"])
    print("anim_stress: %d rigid bodies, %dx%d cloth, %d triangles, %g s -> %s"
          % (a.objects, a.grid, a.grid, tri, a.duration, a.out))


if __name__ == "__main__":
    main()
