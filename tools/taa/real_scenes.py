"""Wraps a converted pbrt scene (`host --convert X.pbrt --out DIR/scene.json`) with the
camera path fragment scenes/paths/<name>.json, optionally retimed (speed variants), so
that `host --sequence` can render it.

  /usr/bin/python3 -m tools.taa.real_scenes SCENE.json PATH_FRAGMENT.json OUT.json [--speed S] [--t0 T] [--t1 T]
                 [--res WxH] [--spp N] [--max-depth D]

--speed S plays the path S times as fast (key times divided by S); --t0/--t1 keep only
the keys inside [t0, t1] of the original timeline (shifted to start at 0)."""
import argparse
import json


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("scene")
    ap.add_argument("fragment")
    ap.add_argument("out")
    ap.add_argument("--speed", type=float, default=1.0)
    ap.add_argument("--t0", type=float, default=None)
    ap.add_argument("--t1", type=float, default=None)
    ap.add_argument("--res", default=None, help="camera.resolution WxH")
    ap.add_argument("--spp", type=int, default=None, help="render.spp")
    ap.add_argument("--max-depth", type=int, default=None, help="render.maxDepth")
    a = ap.parse_args()
    sc = json.load(open(a.scene))
    frag = json.load(open(a.fragment))
    # a scenes/paths fragment ({"path": [...]}) or a scene.json wrapper (camera.path)
    keys = frag["path"] if "path" in frag else frag["camera"]["path"]
    if a.t0 is not None:
        keys = [k for k in keys if k["time"] >= a.t0]
    if a.t1 is not None:
        keys = [k for k in keys if k["time"] <= a.t1]
    t_first = keys[0]["time"]
    out = []
    for k in keys:
        k = dict(k)
        k["time"] = (k["time"] - t_first) / a.speed
        out.append(k)
    sc["camera"]["path"] = out
    if a.res:
        sc["camera"]["resolution"] = [int(v) for v in a.res.split("x")]
    if a.spp is not None:
        sc.setdefault("render", {})["spp"] = a.spp
    if a.max_depth is not None:
        sc.setdefault("render", {})["maxDepth"] = a.max_depth
    json.dump(sc, open(a.out, "w"), indent=1)


if __name__ == "__main__":
    main()
