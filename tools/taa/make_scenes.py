#!/usr/bin/python3
"""Generates the synthetic TAA scenes (scene.json v1) into a folder: geometry chosen to alias
(thin bars, railings, stairs, slanted edges, hard shadows) under one distant light so that a
frame is noise-free at 1 spp with maxDepth 1 -- the input differs from the reference only by
aliasing, as with the rasterised frames of thesis 5.5.1. Camera paths mix smooth and sudden
moves at several speeds (keys are seconds; sequences are rendered at 24 fps).

  make_scenes.py OUTDIR        -> OUTDIR/{stairs,fence,pillars}/scene.json
"""
import json
import math
import os
import random
import sys


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


def main():
    out = sys.argv[1]
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
