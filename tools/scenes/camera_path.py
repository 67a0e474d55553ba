"""Camera paths for benchmark scenes (thesis 3.3.5.1): a few keyframes mixing open and
occluded views, interpolated by tt_scene_camera_at and sampled into 100 poses by
`host --camera-index I` (t = I/99 of the path's time range; `--frames A:B` renders frames
at --fps instead, t = f / fps).

  P="/usr/bin/python3 -m tools.scenes.camera_path"   # from the repository root
  $P auto SOURCE [--seconds 2]         print a {"path": [...]} fragment
      SOURCE is a scene.json (bounds computed from its meshes) or one line of
      `scenes_info` output (build-*/tests/scenes_info SCENE.pbrt > info.json): the still
      camera and bounds as imported, i.e. in tunetrace's world coordinates (the pbrt importer
      may mirror x). Keys: the still view (open); halfway to the bounds' centre turned left;
      80% of the way to the centre looking sideways (occluded close-ups); the same spot
      looking back; the still position turned right.
  $P merge SCENE.json FRAGMENT.json OUT.json
      a copy of SCENE.json with camera.path from FRAGMENT (relative mesh/texture paths are
      rewritten so OUT.json still finds the original files)
  $P sample SOURCE [--n 100]
      print the n sampled poses (JSON lines: index, t, position, target, up, fov) as host
      computes them, from a scene.json or a fragment
  $P wrap SCENE.pbrt PATH OUT.json [--max-depth N]
      a small scene.json that imports SCENE.pbrt (path relative to OUT.json's folder) and
      carries camera.path from PATH (a fragment or a scene.json with a path)
  $P sheet SCENE.json OUT.png [--n 10] [--cols 5] [--res 96x64] [--spp 16]
                       [--threads 2] [--colors 64] [--host PATH]
      renders n evenly spaced samples of the path (`host --camera-index`, indices
      round(j * 99 / (n - 1))) into a labelled contact sheet with a `colors` palette
      (needs python3-pil)

host renders a path only from scene.json. A .pbrt scene has no camera path: a scene.json
that imports it carries one (scenes/<name>/scene.json, written with `wrap`).
"""
import argparse
import json
import os

import numpy as np

from tools.scenes import scenelib as sl
from tools.scenes.generate import hermite_eval
from tools.tttools import cli, host


def _rotate(v, up, deg):
    return sl.axis_angle(up, deg) @ v


def auto_path(position, target, up, fov, lo, hi, seconds=2.0):
    P0, T0 = np.array(position, float), np.array(target, float)
    up = np.array(up, float)
    up = up / np.linalg.norm(up)
    diag = float(np.linalg.norm(np.array(hi, float) - np.array(lo, float)))
    fwd = T0 - P0
    dist = float(np.linalg.norm(fwd))
    fwd = fwd / dist
    look = max(dist, 0.25 * diag)   # distance of the look-at points
    C = (np.array(lo, float) + np.array(hi, float)) / 2
    P2 = P0 + 0.8 * (C - P0)   # towards the middle of the bounds (inside a room or box)
    P1 = (P0 + P2) / 2
    poses = [
        (P0, P0 + fwd * look, fov),                                   # open: the still view
        (P1, P1 + _rotate(fwd, up, 35) * look, fov),                  # turning left
        (P2, P2 + _rotate(fwd, up, 100) * look * 0.5, fov * 1.15),    # close-up, sideways
        (P2 + up * 0.02 * diag, P2 - fwd * look, fov * 1.15),         # looking back
        (P0, P0 + _rotate(fwd, up, -30) * look, fov),                 # back, turned right
    ]
    keys = sl.path_keys(poses, seconds)
    for k in keys:
        k["fov"] = round(min(max(k["fov"], 5.0), 120.0), 4)
    return keys


def load_source(path):
    """(camera dict with position/target/up/fov, lo, hi, scene or None)."""
    with open(path) as f:
        text = f.read()
    d = json.loads(text.splitlines()[0]) if text.lstrip().startswith('{"scene"') else json.loads(text)
    if "bounds" in d:   # scenes_info output
        c = dict(d["camera"])
        c["_scene"] = "(scenes_info of %s)" % os.path.basename(d["scene"])
        return c, d["bounds"][0], d["bounds"][1], None
    lo, hi = sl.scene_bounds(d, os.path.dirname(os.path.abspath(path)))
    c = dict(d["camera"])
    c.setdefault("up", [0, 1, 0])
    c.setdefault("fov", 45)
    return c, lo, hi, d


def cmd_auto(a):
    c, lo, hi, _ = load_source(a.source)
    name = c.get("_scene", os.path.basename(a.source))
    keys = auto_path(c["position"], c["target"], c.get("up", [0, 1, 0]), c.get("fov", 45), lo,
                     hi, a.seconds)
    print(json.dumps({"_comment": "tools/scenes/camera_path.py auto %s" % name,
                      "path": keys}, indent=1))


def cmd_merge(a):
    scene = sl.load_scene(a.scene)
    with open(a.fragment) as f:
        frag = json.load(f)
    scene["camera"]["path"] = frag["path"] if isinstance(frag, dict) else frag
    sl.rebase_files(scene, os.path.dirname(os.path.abspath(a.scene)),
                    os.path.dirname(os.path.abspath(a.out)))
    sl.save_scene(a.out, scene)


def read_keys(path):
    with open(path) as f:
        d = json.load(f)
    return d["path"] if "path" in d else d["camera"]["path"]


def wrapper_text(comment, rel_import, keys, render=None):
    """scene.json text of a wrapper: import + camera.path (one key per line) + render."""
    head = json.dumps({"_comment": comment, "version": 1, "import": rel_import}, indent=2)[:-2]
    text = head + ',\n  "camera": {\n    "path": [\n      ' + \
        ',\n      '.join(json.dumps(k) for k in keys) + '\n    ]\n  }'
    if render:
        text += ',\n  "render": ' + json.dumps(render)
    return text + '\n}\n'


def cmd_wrap(a):
    out_dir = os.path.dirname(os.path.abspath(a.out))
    rel = os.path.relpath(os.path.abspath(a.pbrt), out_dir)
    comment = ("%s wrapped with a camera path (tools/scenes/camera_path.py); check it with "
               "`camera_path.py sheet`" % os.path.basename(a.pbrt))
    text = wrapper_text(comment, rel, read_keys(a.path),
                        {"maxDepth": a.max_depth} if a.max_depth is not None else None)
    json.loads(text)
    os.makedirs(out_dir, exist_ok=True)
    with open(a.out, "w") as f:
        f.write(text)


def cmd_sheet(a):
    import tempfile
    from PIL import Image, ImageDraw
    n, w_h = a.n, [int(x) for x in a.res.split("x")]
    idx = [round(i * 99 / max(n - 1, 1)) for i in range(n)]
    cols = min(n, a.cols)
    rows = (n + cols - 1) // cols
    label = 11
    sheet = Image.new("RGB", (cols * w_h[0], rows * (w_h[1] + label)), (40, 40, 40))
    draw = ImageDraw.Draw(sheet)
    with tempfile.TemporaryDirectory() as tmp:
        for j, i in enumerate(idx):
            out = os.path.join(tmp, "f%02d.exr" % i)
            host.run(a.host, ["--quiet", "--camera-index", str(i), "--res", a.res, "--spp", str(a.spp),
                              "--threads", str(a.threads), "--out", out, a.scene],
                     nice=5, capture=True)
            im = Image.open(out[:-4] + ".png").convert("RGB")
            x, y = (j % cols) * w_h[0], (j // cols) * (w_h[1] + label)
            sheet.paste(im, (x, y + label))
            draw.text((x + 2, y), "%d" % i, fill=(255, 255, 255))
    if a.colors:   # a palette keeps committed sheets small (noise costs PNG bytes)
        sheet = sheet.quantize(colors=a.colors, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
    sheet.save(a.out, optimize=True)


def cmd_sample(a):
    with open(a.source) as f:
        d = json.load(f)
    cam = d.get("camera", {})
    keys = cam.get("path") if "camera" in d else d["path"]
    still = {"position": cam.get("position"), "target": cam.get("target"),
             "up": cam.get("up", [0, 1, 0]), "fov": cam.get("fov", 45)}
    full = []
    for k in keys:
        kk = dict(k)
        for f in ("position", "target", "up", "fov"):
            if f not in kk:
                kk[f] = still[f]
        kk["fov"] = [kk["fov"]] * 3
        full.append(kk)
    times = [k["time"] for k in full]
    for i in range(a.n):
        t = times[0] + (times[-1] - times[0]) * i / max(a.n - 1, 1)
        pos = hermite_eval(full, times, t, "position")
        tgt = hermite_eval(full, times, t, "target")
        up = hermite_eval(full, times, t, "up")
        up = up / max(np.linalg.norm(up), 1e-12)
        fov = float(hermite_eval(full, times, t, "fov")[0])
        print(json.dumps({"index": i, "t": round(t, 6), "position": sl.r3(pos, 6),
                          "target": sl.r3(tgt, 6), "up": sl.r3(up, 6),
                          "fov": round(min(max(fov, 1e-3), 179.999), 6)}))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("auto")
    p.add_argument("source")
    p.add_argument("--seconds", type=float, default=2.0)
    p = sub.add_parser("merge")
    p.add_argument("scene")
    p.add_argument("fragment")
    p.add_argument("out")
    p = sub.add_parser("sample")
    p.add_argument("source")
    p.add_argument("--n", type=int, default=100)
    p = sub.add_parser("wrap")
    p.add_argument("pbrt")
    p.add_argument("path")
    p.add_argument("out")
    p.add_argument("--max-depth", type=int, default=None)
    p = sub.add_parser("sheet", parents=[cli.HOST])
    p.add_argument("scene")
    p.add_argument("out")
    p.add_argument("--n", type=int, default=10)
    p.add_argument("--cols", type=int, default=5)
    p.add_argument("--res", default="96x64")
    p.add_argument("--spp", type=int, default=16)
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--colors", type=int, default=64, help="palette size of the PNG (0: RGB)")
    a = ap.parse_args()
    if a.cmd == "sheet":
        a.host = host.find(a.host)
    {"auto": cmd_auto, "merge": cmd_merge, "sample": cmd_sample, "wrap": cmd_wrap,
     "sheet": cmd_sheet}[a.cmd](a)


if __name__ == "__main__":
    main()
