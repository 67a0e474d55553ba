"""Writes the TAA test-set scenes: scenes that no training or validation sequence uses
(tools/taa/README, "Three sets"), each under a camera path with one key per frame, so the
pose of every frame is exactly the one written here:

  frames 0-7    slow move   (1/250 of the way from the scene's first path key to its second
                             per frame: well under a pixel per frame)
  frames 8-15   fast move   (1/12 of that way per frame: 2-6 pixels per frame)
  frame 16      a jump      (to the scene's third path key within one frame)
  frames 16-23  medium move (1/80 of the way from the third key to the fourth per frame)

  /usr/bin/python3 -m tools.taa.make_test_set OUT [--res 160x90] [--scenes a,b,c]

writes OUT/NAME/scene.json for each scene (a wrapper that imports scenes/NAME's file, so
the checkout's scenes/ and ../shared/scenes must be in place); render each with
tools/taa/render_test_set.sh. Every scene's own path has at least four keys."""
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
}
DEFAULT = "cornell-box,killeroos,veach-mis"
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
    ap.add_argument("--scenes", default=DEFAULT, help="comma-separated, from: " + ",".join(SCENES))
    a = ap.parse_args()
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
        if "import" in base:  # imports do not nest: import what the wrapper imports
            src = os.path.normpath(os.path.join(os.path.dirname(src), base["import"]))
        if len(keys) < 4:
            sys.exit(f"make_test_set: {src}: camera.path has {len(keys)} keys, expected >= 4")
        d = os.path.join(a.out, name)
        os.makedirs(d, exist_ok=True)
        sc = {"_comment": f"TAA test sequence: {SCENES[name]}'s scene, slow / fast / jump / "
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
