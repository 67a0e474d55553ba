#!/usr/bin/python3
"""host --sequence over an animated scene (scenes/animated-cornell) updates the acceleration
structure every frame: the manifest records each frame's update (refit, or rebuild every
refitInterval frames), the frames change as the objects move, and a sequence whose accel
is refitted renders every frame bit for bit as one whose accel is built from scratch each
frame, and as a sequence that starts at that frame.

Reads the EXRs with OpenImageIO (python3-openimageio, tools/bootstrap.sh).
Environment: TT_BUILD_ROOT, TT_SOURCE_ROOT (tests/meson.build)."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

HOST = os.path.join(os.environ["TT_BUILD_ROOT"], "host", "host")
SCENE = os.path.join(os.environ["TT_SOURCE_ROOT"], "scenes", "animated-cornell", "scene.json")
failures = checks = 0


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def sequence(out, frames, *sets):
    args = [HOST, "--quiet", "--sequence", frames, "--spp", "2", "--res", "48x48", "--out-dir", out]
    for s in sets:
        args += ["--set", "accel_embree." + s]
    r = subprocess.run(args + [SCENE], capture_output=True, text=True)
    check(r.returncode == 0, f"{' '.join(args)}: exit {r.returncode}: {r.stdout}{r.stderr}")
    try:
        with open(os.path.join(out, "manifest.json")) as f:
            return json.load(f)["frames"]
    except (OSError, ValueError, KeyError) as e:
        check(False, f"{out}/manifest.json: {e}")
        return []


def pixels(folder, frame):
    inp = oiio.ImageInput.open(os.path.join(folder, f"color_{frame:04d}.exr"))
    check(inp is not None, f"open {folder} frame {frame}: {oiio.geterror()}")
    if inp is None:
        return np.zeros((1,))
    px = inp.read_image(0, 0, 0, 3, "float")
    inp.close()
    return px


def main():
    with tempfile.TemporaryDirectory() as tmp:
        runs = {
            "rebuild": sequence(os.path.join(tmp, "rebuild"), "0:6"),
            "refit": sequence(os.path.join(tmp, "refit"), "0:6", "updateMethod=refit", "refitInterval=3"),
            "custom": sequence(os.path.join(tmp, "custom"), "0:6", "backend=custom", "updateMethod=refit"),
            "custom_rebuild": sequence(os.path.join(tmp, "custom_rebuild"), "0:6", "backend=custom"),
            "late": sequence(os.path.join(tmp, "late"), "6:6", "updateMethod=refit"),
        }
        updates = {k: [f.get("update") for f in v] for k, v in runs.items()}
        check(updates["rebuild"] == ["rebuild"] * 7, f"rebuild: {updates['rebuild']}")
        # frame 0 refits the tree built at the scene's start; every 3rd update rebuilds
        check(updates["refit"] == ["refit", "refit", "rebuild"] * 2 + ["refit"], f"refit: {updates['refit']}")
        check(updates["custom"] == ["refit"] * 7, f"custom: {updates['custom']}")
        check(all(f.get("update_ms", -1) >= 0 for v in runs.values() for f in v), "update_ms per frame")
        check(all(f.get("sah_cost", 0) > 0 for f in runs["custom"]), "the custom tree reports its SAH cost")
        frames = {k: [pixels(os.path.join(tmp, k), i) for i in range(7)] for k in
                  ("rebuild", "refit", "custom", "custom_rebuild")}
        for i in range(7):
            check(np.array_equal(frames["refit"][i], frames["rebuild"][i]),
                  f"frame {i}: native refit differs from rebuild")
            check(np.array_equal(frames["custom"][i], frames["custom_rebuild"][i]),
                  f"frame {i}: custom refit differs from rebuild")
        moved = [np.count_nonzero(frames["rebuild"][i] != frames["rebuild"][i - 1]) for i in range(1, 7)]
        check(min(moved) > 0, f"values changed between consecutive frames: {moved}")
        # the frames' seeds differ, so compare frame 6 of a sequence starting there instead
        check(np.array_equal(pixels(os.path.join(tmp, "late"), 6), frames["rebuild"][6]),
              "frame 6 of 6:6 equals frame 6 of 0:6")
    print(f"host_anim_sequence: {checks} checks, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
