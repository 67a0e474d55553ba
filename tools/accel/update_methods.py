"""Per-frame acceleration-structure update time and render time of accel_embree's update
methods side by side: build from scratch every frame (rebuild), refit every frame, and the
two-level update (instances: each rigid mesh an Embree instance of its own BVH, only the top
level rebuilt), on scenes/animated-cornell, scenes/animated-stress (64 small rigid bodies and
a cloth) and a generated scene of many rigid objects of many triangles.

The many-object scene is written by this tool (--objects N spheres of --sphere-tris
triangles each, every one turning and moving on its own keyframed path over 2 s, above a
still floor under an area light), unless --scene names other scenes. Every measurement is
one `host --sequence` process (the manifest records each frame's update_ms and render_ms);
each round runs every configuration once, the order rotated per round, so the machine's
load drifts over all alike. Printed per scene and configuration: medians over every frame of
every round of update ms, render ms and their sum, and the median over rounds of the ratios
native rebuild / this (update time, render time, frame time). The load average is printed
at the start and the end; --out keeps the raw per-frame figures as JSON.

  /usr/bin/python3 -m tools.accel.update_methods --rounds 3 --frames 0:23
  /usr/bin/python3 -m tools.accel.update_methods --objects 400 --sphere-tris 1280 --res 96x96
"""
import json
import math
import os
import random
import statistics
import sys
import tempfile

from tools.accel.anim_update import run_sequence
from tools.tttools import cli, host

ROOT = host.ROOT
# label -> accel_embree settings; the first is the reference of the ratios
CONFIGS = {
    "native rebuild": [],
    "native refit": ["updateMethod=refit"],
    "native instances": ["updateMethod=instances"],
    "custom rebuild": ["backend=custom"],
    "custom refit": ["backend=custom", "updateMethod=refit"],
}


def sphere(subdiv):
    """Unit icosphere: (positions, triangles) with 20 * 4^subdiv triangles."""
    t = (1.0 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    for _ in range(subdiv):
        mid, nf = {}, []

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(x / n for x in p))
                mid[key] = len(v) - 1
            return mid[key]
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            nf += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = nf
    return v, f


def many_objects_scene(path, objects, sphere_tris, seed=7):
    """Writes the many-rigid-objects scene.json at `path` (atomically)."""
    subdiv = max(0, round(math.log(max(sphere_tris, 20) / 20, 4)))
    v, f = sphere(subdiv)
    rng = random.Random(seed)
    side = math.ceil(objects ** (1 / 3))
    meshes = [{"name": "floor", "material": "floor",
               "positions": [[-12, -6, -12], [12, -6, -12], [12, -6, 12], [-12, -6, 12]],
               "indices": [[0, 2, 1], [0, 3, 2]]},
              {"name": "light", "material": "lamp",
               "positions": [[-3, 9, -3], [3, 9, -3], [3, 9, 3], [-3, 9, 3]],
               "indices": [[0, 1, 2], [0, 2, 3]]}]
    for i in range(objects):
        cell = [(i % side), (i // side) % side, i // (side * side)]
        c = [(x + 0.5) / side * 10 - 5 for x in cell]
        r = 0.35 * 10 / side
        axis = [rng.uniform(-1, 1) for _ in range(3)]
        axis[1] += 1.5
        keys = []
        for k, time in enumerate((0.0, 1.0, 2.0)):
            off = [rng.uniform(-1, 1) * 10 / side for _ in range(3)] if k else [0, 0, 0]
            keys.append({"time": time, "translate": [c[j] + off[j] for j in range(3)],
                         "rotate": {"axis": axis, "angle": 0 if k == 0 else rng.uniform(60, 170) * k}})
        meshes.append({"name": f"ball{i}", "material": f"m{i % 4}",
                       "positions": [[round(r * x, 6) for x in p] for p in v],
                       "indices": [list(t) for t in f],
                       "animation": {"keys": keys}})
    scene = {"version": 1,
             "camera": {"position": [0, 4, 22], "target": [0, 0, 0], "up": [0, 1, 0], "fov": 45,
                        "resolution": [128, 128],
                        "path": [{"time": 0}, {"time": 2, "position": [6, 5, 21]}]},
             "materials": {"floor": {"albedo": [0.6, 0.6, 0.6]},
                           "lamp": {"albedo": 0, "emission": [20, 20, 20]},
                           "m0": {"albedo": [0.7, 0.2, 0.2]}, "m1": {"albedo": [0.2, 0.6, 0.2]},
                           "m2": {"albedo": [0.2, 0.3, 0.7]},
                           "m3": {"type": "plastic", "albedo": [0.8, 0.6, 0.1], "alpha": 0.1}},
             "meshes": meshes}
    tmp = path + ".tmp"
    with open(tmp, "w") as fh:
        json.dump(scene, fh)
    os.replace(tmp, path)
    return objects * len(f) + 4


def main(argv=None):
    p = cli.parser(__doc__)
    p.add_argument("--scene", action="append",
                   help="scene(s) to measure (default: animated-cornell, animated-stress and the "
                        "generated one)")
    p.add_argument("--objects", type=int, default=200, help="rigid objects of the generated scene")
    p.add_argument("--sphere-tris", type=int, default=1280,
                   help="triangles per object (20 * 4^k, rounded)")
    p.add_argument("--frames", default="0:23", help="frames A:B of the sequence (default 0:23)")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--res", default="96x96")
    p.add_argument("--spp", type=int, default=1)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--nice", type=int, default=None, help="run the host under nice -n NICE")
    p.add_argument("--out", help="raw per-frame figures as JSON")
    args = p.parse_args(argv)
    exe = host.find(args.host)
    labels = list(CONFIGS)
    print(f"load average at start: {os.getloadavg()}")
    results = {}
    with tempfile.TemporaryDirectory(prefix="tt_update_methods.") as tmp:
        scenes = args.scene
        if not scenes:
            gen = os.path.join(tmp, "many_objects.json")
            tris = many_objects_scene(gen, args.objects, args.sphere_tris)
            print(f"generated scene: {args.objects} rigid objects, {tris} triangles")
            scenes = [os.path.join(ROOT, "scenes", name, "scene.json")
                      for name in ("animated-cornell", "animated-stress")] + [gen]
        for scene in scenes:
            frames = {k: [] for k in labels}
            for r in range(args.rounds):
                order = labels[r % len(labels):] + labels[:r % len(labels)]
                for k in order:
                    folder = os.path.join(tmp, f"{len(results)}_r{r}_{labels.index(k)}")
                    os.makedirs(folder)
                    frames[k].append(run_sequence(exe, scene, CONFIGS[k], args, folder))
            results[scene] = frames
            report(scene, frames, args)
    print(f"load average at end: {os.getloadavg()}")
    if args.out:
        tmp_out = args.out + ".tmp"
        with open(tmp_out, "w") as f:
            json.dump({"frames": args.frames, "res": args.res, "spp": args.spp,
                       "threads": args.threads, "configs": CONFIGS, "runs": results}, f, indent=1)
        os.replace(tmp_out, args.out)
    return 0


def report(scene, frames, args):
    """Prints one scene's table."""
    labels = list(frames)
    ref = labels[0]
    print(f"\n{scene}: frames {args.frames}, {args.res}, {args.spp} spp, {args.threads} threads, "
          f"{args.rounds} rounds (medians over every frame of every round; wall time)")
    print(f"{'configuration':20s} {'update ms':>10s} {'render ms':>10s} {'frame ms':>9s} "
          f"{'rebuilt':>8s} {'upd x':>7s} {'render x':>9s} {'frame x':>8s}")

    def ratio(k, fn):
        """Median over rounds of sum(fn) over the reference's frames / this config's."""
        return statistics.median(sum(fn(f) for f in a) / max(sum(fn(f) for f in b), 1e-9)
                                 for a, b in zip(frames[ref], frames[k]))

    def upd(f):
        return f.get("update_ms", 0.0)

    def ren(f):
        return f["render_ms"]

    for k in labels:
        every = [f for run in frames[k] for f in run]
        rebuilt = sum(f.get("update") == "rebuild" for f in every)
        print(f"{k:20s} {statistics.median(map(upd, every)):10.3f} "
              f"{statistics.median(map(ren, every)):10.2f} "
              f"{statistics.median(upd(f) + ren(f) for f in every):9.2f} "
              f"{rebuilt:4d}/{len(every):<3d} {ratio(k, upd):7.2f} {ratio(k, ren):9.3f} "
              f"{ratio(k, lambda f: upd(f) + ren(f)):8.3f}")


if __name__ == "__main__":
    sys.exit(main())
