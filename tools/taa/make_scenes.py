"""Generates the synthetic TAA scenes (scene.json v1) into a folder: geometry chosen to alias
(thin bars, railings, stairs, slanted edges, hard shadows) under one distant light so that a
frame is noise-free at 1 spp with maxDepth 1 -- the input differs from the reference only by
aliasing, as with the rasterised frames of thesis 5.5.1. Camera paths mix smooth and sudden
moves at several speeds (keys are seconds; sequences are rendered at 24 fps).

  M="/usr/bin/python3 -m tools.taa.make_scenes"   # from the repository root
  $M OUTDIR             -> OUTDIR/{stairs,fence,pillars}/scene.json
  $M OUTDIR --set fast  -> OUTDIR/{windows,blinds,windows-pan,blinds-dolly,
                                  stairs-fast,fence-fast}/scene.json
  $M OUTDIR --set jumps -> OUTDIR/{blocks,stairs,fence,windows}-jumps/scene.json

The "fast" set (training only) covers fast camera motion (1-8 px per frame, rotations,
dolly, sudden jumps) over thin high-contrast features: two rooms whose window openings show
a bright sunlit backdrop through thin dark mullions / blinds, and the stairs and fence
geometry under new fast paths. The rooms stay noise-free at 1 spp: only distant lights,
one sun lighting a bright slope outside and entering through the windows (hard mullion
shadows on the floor and a side wall); the rest of the closed room stays dark. (Two lights
would not do: the path tracer picks one light per sample, which is noise at 1 spp.)
"""
import json
import math
import os
import random

from tools.tttools import cli


def box(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    p = [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
         [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]]
    f = [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [3, 6, 2], [3, 7, 6], [0, 4, 7], [0, 7, 3], [1, 2, 6], [1, 6, 5]]
    return p, f


class Builder:
    def __init__(self):
        self.meshes = {}

    def add(self, mat, lo, hi):
        p, f = box(lo, hi)
        m = self.meshes.setdefault(mat, ([], []))
        base = len(m[0])
        m[0].extend(p)
        m[1].extend([[a + base, b + base, c + base] for a, b, c in f])

    def quad(self, mat, p):
        m = self.meshes.setdefault(mat, ([], []))
        base = len(m[0])
        m[0].extend([list(v) for v in p])
        m[1].extend([[base, base + 1, base + 2], [base, base + 2, base + 3]])

    def json(self):
        return [{"name": k, "material": k, "positions": v[0], "indices": v[1]}
                for k, v in self.meshes.items()]


MATERIALS = {
    "floor": {"type": "diffuse", "albedo": [0.55, 0.5, 0.45]},
    "wall": {"type": "diffuse", "albedo": [0.7, 0.72, 0.75]},
    "wood": {"type": "diffuse", "albedo": [0.6, 0.35, 0.15]},
    "metal": {"type": "diffuse", "albedo": [0.08, 0.08, 0.1]},
    "red": {"type": "diffuse", "albedo": [0.75, 0.12, 0.1]},
    "blue": {"type": "diffuse", "albedo": [0.1, 0.25, 0.7]},
}


def stairs(b):
    b.add("floor", (-20, -0.1, -20), (20, 0, 20))
    b.add("wall", (-20, 0, -6), (20, 8, -5.8))
    for i in range(14):   # steps with gaps between them
        b.add("wood", (-1.5, 0.25 * i, -0.35 * i), (1.5, 0.25 * i + 0.06, -0.35 * i - 0.3))
        for side in (-1.55, 1.55):   # thin balusters
            b.add("metal", (side - 0.015, 0.25 * i, -0.35 * i - 0.15),
                  (side + 0.015, 0.25 * i + 1.0, -0.35 * i - 0.12))
    for side in (-1.55, 1.55):   # slanted handrail, one box per step
        for i in range(14):
            b.add("metal", (side - 0.03, 0.25 * i + 1.0, -0.35 * i - 0.35),
                  (side + 0.03, 0.25 * i + 1.04, -0.35 * i + 0.02))
    for i in range(8):   # door frames, almost vertical
        x = -6 + 1.6 * i
        b.add("red" if i % 2 else "blue", (x, 0, -5.7), (x + 0.08, 3.0, -5.6))


def fence(b):
    b.add("floor", (-30, -0.1, -30), (30, 0, 30))
    for i in range(60):   # pickets
        x = -6 + 0.2 * i
        b.add("wood", (x, 0, -2), (x + 0.05, 1.2 + 0.1 * math.sin(i), -1.95))
    b.add("wood", (-6, 0.3, -2.05), (6, 0.36, -2.0))
    b.add("wood", (-6, 0.9, -2.05), (6, 0.96, -2.0))
    for i in range(12):   # wires / thin rods at several depths
        z = -4 - 0.7 * i
        b.add("metal", (-10, 1.5 + 0.2 * i, z), (10, 1.52 + 0.2 * i, z + 0.02))
    for i in range(6):
        b.add("red", (-5 + 2 * i, 0, -9), (-4.2 + 2 * i, 2 + 0.3 * i, -8.2))


def pillars(b):
    b.add("floor", (-30, -0.1, -30), (30, 0, 30))
    b.add("wall", (-30, 0, -12), (30, 10, -11.8))
    random.seed(3)
    for i in range(10):
        x = -8 + 1.8 * i
        b.add("wall", (x, 0, -6), (x + 0.35, 5, -5.65))
        b.add("metal", (x + 0.6, 0, -4), (x + 0.63, 3.5, -3.97))   # thin poles
    for i in range(30):   # slats of a blind, slightly slanted via steps
        y = 0.5 + 0.15 * i
        b.add("blue", (-3, y, -8), (3, y + 0.04, -7.9))
    for i in range(5):
        b.add("red", (-6 + 3 * i, 0, -2), (-5.4 + 3 * i, 0.8, -1.4))


def path(center, target, segments):
    """Camera keys: each segment (duration s, yaw deg, height, distance) from the last key;
    a duration of 1/24 s makes a sudden move (a cut-like jump)."""
    keys, t = [], 0.0
    for dur, yaw, h, d in segments:
        t += dur
        a = math.radians(yaw)
        keys.append({"time": round(t, 5),
                     "position": [center[0] + d * math.sin(a), h, center[2] + d * math.cos(a)],
                     "target": target})
    keys[0]["time"] = 0.0
    return keys


SCENES = {
    "stairs": (stairs, (0, 0, 3), [0, 1.5, -2.5],
               [(0, -25, 1.6, 6), (2, -10, 1.8, 5.5), (1, 10, 2.2, 5), (1 / 24, 30, 1.5, 4),
                (0.7, 45, 2.5, 5), (1.5, 0, 1.7, 7), (0.5, -20, 1.6, 6)]),
    "fence": (fence, (0, 0, 2), [0, 1.0, -3],
              [(0, -30, 1.2, 4), (3, 15, 1.4, 4.5), (1 / 24, -10, 2.0, 3), (1, -35, 1.0, 5),
               (0.6, 0, 1.5, 4), (2, 25, 1.3, 3.5)]),
    "pillars": (pillars, (0, 0, 2), [0, 2.0, -6],
                [(0, -20, 1.8, 5), (2.5, 20, 2.0, 6), (0.8, 35, 2.6, 5), (1 / 24, -5, 1.5, 4),
                 (1.5, -30, 2.2, 7)]),
}


def room(b, windows, inside):
    """Closed room x -8..8, y 0..4, z -5..8 whose wall z = -5 has the openings `windows`
    ((x0, x1, y0, y1, bars) each; bars: list of ("v"|"h", position, half-width)); outside, a
    bright slope and dark poles; `inside(b)` adds the furniture."""
    b.add("floor", (-30, -0.1, -30), (30, 0, 30))
    b.add("wall", (-8.2, 0, -5), (-8, 4, 8))
    b.add("wall", (8, 0, -5), (8.2, 4, 8))
    b.add("wall", (-8.2, 0, 8), (8.2, 4, 8.2))
    b.add("wall", (-8.2, 4, -5.2), (8.2, 4.2, 8.2))
    # window wall: columns between the openings, sill and lintel pieces above / below each
    xs = sorted(windows)
    x = -8.0
    for (x0, x1, y0, y1, bars) in xs:
        b.add("wall", (x, 0, -5.2), (x0, 4, -5))
        b.add("wall", (x0, 0, -5.2), (x1, y0, -5))
        b.add("wall", (x0, y1, -5.2), (x1, 4, -5))
        for kind, pos, hw in bars:   # thin dark mullions / slats inside the opening
            if kind == "v":
                b.add("frame", (pos - hw, y0, -5.12), (pos + hw, y1, -5.08))
            else:
                b.add("frame", (x0, pos - hw, -5.12), (x1, pos + hw, -5.08))
        x = x1
    b.add("wall", (x, 0, -5.2), (8.0, 4, -5))
    # sunlit slope rising away from the windows (20 degrees): the bright backdrop
    b.quad("white", [(-60, 0, -6), (60, 0, -6), (60, 19.6, -60), (-60, 19.6, -60)])
    for i in range(9):   # dark poles / trunks outside
        px = -9 + 2.3 * i
        b.add("metal", (px, 0, -9 - 0.4 * (i % 3)), (px + 0.06 + 0.03 * (i % 2), 5.5, -8.9 - 0.4 * (i % 3)))
    b.add("red", (-14, 1.5, -11.5), (-6, 3.2, -10.5))
    b.add("blue", (5, 1.5, -11.5), (12, 3.5, -10.5))
    inside(b)


def grid(x0, x1, y0, y1, nv, nh, hw):
    bars = [("v", x0 + (x1 - x0) * (i + 1) / (nv + 1), hw) for i in range(nv)]
    return bars + [("h", y0 + (y1 - y0) * (i + 1) / (nh + 1), hw) for i in range(nh)]


def windows(b):
    w = []
    for i, (cx, nv, nh, hw) in enumerate([(-5.4, 1, 1, 0.03), (-1.8, 2, 2, 0.02),
                                          (1.8, 3, 1, 0.04), (5.4, 1, 3, 0.015)]):
        x0, x1, y0, y1 = cx - 1.2, cx + 1.2, 0.9, 2.9
        w.append((x0, x1, y0, y1, grid(x0, x1, y0, y1, nv, nh, hw)))

    def inside(b):
        b.add("wood", (-2, 0.75, -2), (1, 0.8, -1))   # table with thin legs
        for lx, lz in ((-1.95, -1.95), (0.92, -1.95), (-1.95, -1.08), (0.92, -1.08)):
            b.add("metal", (lx, 0, lz), (lx + 0.03, 0.75, lz + 0.03))
        b.add("blue", (4, 0, 1), (6.5, 0.9, 2.5))      # sofa-like block
        b.add("metal", (-6, 0, 0), (-5.97, 3.0, 0.03))  # lamp pole
        for i in range(6):   # shelf boards on the left wall
            b.add("wood", (-8, 0.4 + 0.5 * i, 2), (-7.6, 0.43 + 0.5 * i, 5))
    room(b, w, inside)


def blinds(b):
    w = []
    # tall narrow windows with dense vertical bars; one with horizontal blinds
    for i, cx in enumerate((-6.0, -3.6, -1.2)):
        x0, x1, y0, y1 = cx - 0.7, cx + 0.7, 0.5, 3.5
        w.append((x0, x1, y0, y1, grid(x0, x1, y0, y1, 5 - i, 0, 0.012 + 0.008 * i)))
    x0, x1, y0, y1 = 0.8, 4.4, 1.0, 3.2
    w.append((x0, x1, y0, y1, [("h", y0 + 0.1 * (k + 1), 0.018) for k in range(21)]))
    x0, x1, y0, y1 = 5.4, 7.4, 0.6, 3.0
    w.append((x0, x1, y0, y1, grid(x0, x1, y0, y1, 1, 5, 0.025)))

    def inside(b):
        for k in range(7):   # chair-like frames of thin bars
            cx = -6 + 2 * k
            b.add("metal", (cx, 0, -1), (cx + 0.03, 1.0, -0.97))
            b.add("metal", (cx + 0.5, 0, -1), (cx + 0.53, 1.0, -0.97))
            b.add("red" if k % 2 else "wood", (cx, 0.45, -1.4), (cx + 0.53, 0.5, -0.97))
        b.add("wall", (2, 0, 3), (2.1, 2.2, 7))   # partition
    room(b, w, inside)


def keyed(keys):
    """Camera keys from (duration s, position, target) segments; 1/24 s is a sudden jump."""
    out, t = [], 0.0
    for dur, pos, tgt in keys:
        t += dur
        out.append({"time": round(t, 5), "position": list(pos), "target": list(tgt)})
    out[0]["time"] = 0.0
    return out


J = 1 / 24
FAST_MATERIALS = dict(MATERIALS, frame={"type": "diffuse", "albedo": [0.05, 0.05, 0.05]},
                      white={"type": "diffuse", "albedo": [0.9, 0.9, 0.88]})
ROOM_LIGHTS = [{"type": "distant", "direction": [0.3, -1.0, 0.8], "irradiance": 40.0}]
SUN = [{"type": "distant", "direction": [0.4, -1.0, -0.5], "irradiance": 3.0}]   # as SCENES
FAST = {   # name: (geometry, camera keys, lights, materials)
    "windows": (windows, keyed([
        (0, (-3, 1.6, 4), (-3, 1.8, -5)), (1.0, (3, 1.6, 4), (3, 1.8, -5)),
        (0.5, (3, 1.6, 4), (-2, 1.5, -5)), (J, (0, 1.2, 1), (0, 2, -5)),
        (1.0, (0, 1.8, -1), (1, 2, -5)), (0.7, (-2, 1.8, -1), (-6, 2.2, -5)),
        (0.8, (-2, 2.5, 3), (4, 1.0, -5)), (1.0, (2, 1.5, 5), (0, 1.5, -5))]),
        ROOM_LIGHTS, FAST_MATERIALS),
    "blinds": (blinds, keyed([
        (0, (5, 1.8, 5), (3, 2.0, -5)), (0.6, (5, 1.8, 5), (-4, 1.6, -5)),
        (0.6, (-3, 1.4, 2), (-4, 2.2, -5)), (J, (3, 2.2, 0), (3.5, 1.8, -5)),
        (0.8, (0, 2.0, 4), (-6, 1.5, -5)), (0.4, (0, 2.0, 4), (6, 2.0, -5)),
        (J, (-5, 1.0, 0), (-2, 2.5, -5)), (1.2, (5, 1.6, 1), (2, 2.0, -5)),
        (0.8, (2, 2.6, 6), (0, 1.0, -5))]),
        ROOM_LIGHTS, FAST_MATERIALS),
    "windows-pan": (windows, keyed([   # 1-3 px per frame, as most of a real walkthrough
        (0, (-4, 1.7, 5), (-6, 1.9, -5)), (1.5, (-1, 1.7, 5), (-1, 1.9, -5)),
        (1.2, (1, 1.5, 3), (3, 1.6, -5)), (1.3, (3, 1.9, 2), (6, 2.1, -5)),
        (J, (-3, 1.6, 0), (-4, 1.8, -5)), (1.0, (-3, 1.6, 1.5), (-1, 1.8, -5))]),
        ROOM_LIGHTS, FAST_MATERIALS),
    "blinds-dolly": (blinds, keyed([   # dolly in / out with turns
        (0, (0, 1.8, 7), (0, 2.0, -5)), (1.0, (0, 1.8, 0), (1, 2.0, -5)),
        (0.8, (-2, 1.6, -2), (-4, 1.9, -5)), (0.8, (-2, 2.0, 5), (3, 1.8, -5)),
        (J, (6, 1.5, -1), (6, 2.0, -5)), (1.3, (4, 2.3, 6), (-2, 1.5, -5))]),
        ROOM_LIGHTS, FAST_MATERIALS),
    "stairs-fast": (stairs, path((0, 0, 3), [0, 1.5, -2.5],
                    [(0, -40, 1.6, 6), (0.8, 20, 1.8, 5), (0.5, -15, 2.4, 4.5), (J, 35, 1.5, 5),
                     (0.7, -30, 2.8, 6.5), (0.6, 25, 1.4, 4), (J, -10, 2.0, 7),
                     (1.2, 40, 2.2, 5)]),
                    SUN, MATERIALS),
    "fence-fast": (fence, path((0, 0, 2), [0, 1.0, -3],
                   [(0, 35, 1.2, 4), (0.7, -25, 1.5, 4.5), (0.5, 10, 1.0, 3), (J, -40, 2.0, 5),
                    (1.0, 30, 1.3, 3.5), (0.5, -5, 1.8, 5), (J, 20, 1.1, 3),
                    (1.2, -35, 1.6, 4.5)]),
                   SUN, MATERIALS),
}


def blocks(b):
    """Boxes of every material at several depths on a floor, hard shadows: a jump turns
    them across contrasting floor and wall (disocclusions everywhere)."""
    b.add("floor", (-30, -0.1, -30), (30, 0, 30))
    b.add("wall", (-30, 0, -14), (30, 6, -13.8))
    rnd = random.Random(7)
    mats = ["red", "blue", "wood", "metal", "wall"]
    for i in range(40):
        x, z = rnd.uniform(-10, 10), rnd.uniform(-12, 1)
        sx, sz, h = rnd.uniform(0.3, 1.0), rnd.uniform(0.2, 1.2), rnd.uniform(0.3, 2.2)
        b.add(mats[i % 5], (x, 0, z), (x + sx, h, z + sz))


def jumpy(seed, yaw0, h0, d0, cycles=9):
    """Path segments: cycles of a slow 0.4 s drift (<= 3 degrees) then a sudden orbit of
    12-40 degrees within one frame (with a height / distance change; pillars' jump is 40
    degrees): reprojected objects land on newly visible background (ghosting)."""
    rnd = random.Random(seed)
    yaw, h, d = yaw0, h0, d0
    segs = [(0, yaw, h, d)]
    for _ in range(cycles):
        yaw += rnd.uniform(-3, 3)
        segs.append((0.4, yaw, h, d))
        yaw += rnd.choice((-1, 1)) * rnd.uniform(12, 40)
        h = min(max(h + rnd.uniform(-0.5, 0.5), 1.0), 2.6)
        d = min(max(d + rnd.uniform(-1.0, 1.0), 3.5), 7.5)
        segs.append((J, yaw, h, d))
    return segs


JUMPS = {   # name: (geometry, camera keys, lights, materials); training only
    "blocks-jumps": (blocks, path((0, 0, 2), [0, 0.8, -6], jumpy(11, -20, 1.8, 6)),
                     SUN, MATERIALS),
    "stairs-jumps": (stairs, path((0, 0, 3), [0, 1.5, -2.5], jumpy(12, 15, 1.8, 5.5)),
                     SUN, MATERIALS),
    "fence-jumps": (fence, path((0, 0, 2), [0, 1.0, -3], jumpy(13, -10, 1.4, 4.5)),
                    SUN, MATERIALS),
    "windows-jumps": (windows, path((0, 0, 2), [0, 1.8, -5], jumpy(14, 10, 1.7, 4.0)),
                      ROOM_LIGHTS, FAST_MATERIALS),
}


def main():
    ap = cli.parser(__doc__, host=False)
    ap.add_argument("out", help="the folder to write the scenes into")
    ap.add_argument("--set", choices=("fast", "jumps"), help="a training set instead of the "
                    "evaluation scenes")
    a = ap.parse_args()
    out = a.out
    if a.set:
        chosen = FAST if a.set == "fast" else JUMPS
        for name, (fn, keys, lights, mats) in chosen.items():
            b = Builder()
            fn(b)
            scene = {"version": 1, "_comment": "generated by tools/taa/make_scenes.py --set " + a.set,
                     "camera": {"position": keys[0]["position"], "target": keys[0]["target"],
                                "fov": 50, "resolution": [128, 96], "path": keys},
                     "render": {"spp": 1, "maxDepth": 1, "seed": 1},
                     "materials": mats, "meshes": b.json(), "lights": lights}
            os.makedirs(os.path.join(out, name), exist_ok=True)
            with open(os.path.join(out, name, "scene.json"), "w") as f:
                json.dump(scene, f)
            print(name, "keys", len(keys), "duration", keys[-1]["time"], "s")
        return
    for name, (fn, center, target, segs) in SCENES.items():
        b = Builder()
        fn(b)
        keys = path(center, target, segs)
        scene = {
            "version": 1,
            "_comment": "generated by tools/taa/make_scenes.py",
            "camera": {"position": keys[0]["position"], "target": target, "fov": 50,
                       "resolution": [128, 96], "path": keys},
            "render": {"spp": 1, "maxDepth": 1, "seed": 1},
            "materials": MATERIALS,
            "meshes": b.json(),
            "lights": [{"type": "distant", "direction": [0.4, -1.0, -0.5], "irradiance": 3.0}],
        }
        os.makedirs(os.path.join(out, name), exist_ok=True)
        with open(os.path.join(out, name, "scene.json"), "w") as f:
            json.dump(scene, f)
        print(name, "keys", len(keys), "duration", keys[-1]["time"], "s")


if __name__ == "__main__":
    main()
