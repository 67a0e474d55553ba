"""Writes the TAA test-set scenes: scenes that no training or validation sequence uses
(tools/taa/README, "Three sets"), each under a camera path with one key per frame, so the
pose of every frame is exactly the one written here; `--set train` / `--set val` write the
training and validation sequences of the same kind from other scenes (disjoint from the test
scenes and from each other):

  frames 0-7    slow move   (1/250 of the way from the scene's first path key to its second
                             per frame: well under a pixel per frame)
  frames 8-15   fast move   (1/12 of that way per frame: 2-6 pixels per frame)
  frame 16      a jump      (to the scene's third path key within one frame)
  frames 16-23  medium move (1/80 of the way from the third key to the fourth per frame)

  /usr/bin/python3 -m tools.taa.make_test_set OUT [--res 160x90] [--set test|train|val]
                                              [--scenes a,b,c] [--offset K]

writes OUT/NAME/scene.json for each scene (a wrapper that imports scenes/NAME's file, so
the checkout's scenes/ and ../shared/scenes must be in place); render each with
tools/taa/render_test_set.sh. The poses come from the scene path's keys K..K+3 (--offset,
default 0; a sequence with K > 0 is named NAME-kK). Every scene's own path has at least four
keys."""
import argparse
import json
import os
import sys

# name -> the scene file under scenes/ whose camera path the poses come from
SCENES = {
    "cornell-box": "cornell-box/path.json",
    "killeroos": "killeroos/scene.json",
    "veach-mis": "veach-mis/scene.json",
    "veach-ajar": "veach-ajar/scene.json",
    "staircase": "staircase/scene.json",
    "bathroom": "bathroom/scene.json",
    "caustic-glass": "caustic-glass/scene.json",
    "living-room": "living-room/scene.json",
    "bmw-m6": "bmw-m6/scene.json",
}
# The three disjoint sets (tools/taa/README, "Three sets"): test scenes are reported once and
# never choose anything; validation chooses runs and checkpoints; training takes gradient steps.
SETS = {
    "test": "cornell-box,killeroos,veach-mis",
    "val": "living-room,bmw-m6",
    "train": "veach-ajar,staircase,bathroom,caustic-glass",
}
DEFAULT = SETS["test"]
FRAMES = 24
FPS = 24.0


def lerp_key(a, b, s):
    out = {}
    for f in ("position", "target", "up"):
        pa = a.get(f, [0.0, 1.0, 0.0] if f == "up" else None)
        pb = b.get(f, pa)
        out[f] = [round(x + (y - x) * s, 6) for x, y in zip(pa, pb)]
    if "fov" in a:
        out["fov"] = round(a["fov"] + (b.get("fov", a["fov"]) - a["fov"]) * s, 6)
    return out


def frame_keys(k):
    """One key per frame (times f / 24 s): slow, fast, jump, medium (module docstring)."""
    keys = []
    s = 0.0
    for f in range(FRAMES):
        if f < 16:
            s = f / 250.0 if f < 8 else 7 / 250.0 + (f - 7) / 12.0
            key = lerp_key(k[0], k[1], s)
        else:
            key = lerp_key(k[2], k[3], (f - 16) / 80.0)
        key["time"] = round(f / FPS, 9)
        keys.append(key)
    return keys


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--res", default="160x90", help="camera.resolution WxH (160x90)")
    ap.add_argument("--set", choices=sorted(SETS), default="test",
                    help="which set's scenes (default test); --scenes overrides")
    ap.add_argument("--scenes", default=None, help="comma-separated, from: " + ",".join(SCENES))
    ap.add_argument("--offset", type=int, default=0,
                    help="use the path keys K..K+3 (default 0); names get a -kK suffix")
    a = ap.parse_args()
    if a.scenes is None:
        a.scenes = SETS[a.set]
    if a.offset < 0:
        sys.exit(f"make_test_set: --offset {a.offset}: expected >= 0")
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scenes")
    try:
        w, h = (int(v) for v in a.res.split("x"))
    except ValueError:
        sys.exit(f"make_test_set: --res {a.res!r}: expected WxH, e.g. 160x90")
    for name in a.scenes.split(","):
        if name not in SCENES:
            sys.exit(f"make_test_set: --scenes: unknown scene {name!r} (known: {', '.join(SCENES)})")
        src = os.path.normpath(os.path.join(root, SCENES[name]))
        with open(src) as f:
            base = json.load(f)
        keys = base["camera"]["path"]
        path_file = src
        if "import" in base:  # imports do not nest: import what the wrapper imports
            src = os.path.normpath(os.path.join(os.path.dirname(src), base["import"]))
        if len(keys) < 4 + a.offset:
            sys.exit(f"make_test_set: {path_file}: camera.path has {len(keys)} keys, expected >= "
                     f"{4 + a.offset} (--offset {a.offset})")
        keys = keys[a.offset:]
        seq = f"{name}-k{a.offset}" if a.offset else name
        d = os.path.join(a.out, seq)
        os.makedirs(d, exist_ok=True)
        sc = {"_comment": f"TAA {a.set} sequence: {SCENES[name]}'s scene, slow / fast / jump / "
                          f"medium camera (tools/taa/make_test_set.py)",
              "version": 1, "import": os.path.abspath(src),
              "camera": {"resolution": [w, h], "path": frame_keys(keys)}}
        tmp = os.path.join(d, "scene.json.tmp")
        with open(tmp, "w") as f:
            json.dump(sc, f, indent=1)
        os.replace(tmp, os.path.join(d, "scene.json"))
        print(os.path.join(d, "scene.json"))


if __name__ == "__main__":
    main()
