#!/usr/bin/python3
"""Tuning along an animated sequence (host --sequence A:B with a tuner or --explore N over
scenes/animated-cornell): the frames are the measurements.

 - every measured window of --tune-window frames is one database row in the state of its
   first frame (that frame in the context and camera, indicators of its geometry), and its
   build_ms / render_ms are the means of the manifest's per-frame update_ms / render_ms
   over the window's frames, cost their sum (objective build+render): measured inside the
   one process that renders the sequence;
 - a window whose configuration differs from the one before starts with a rebuild (the
   configuration takes over there); a refit window refits the rest of its frames;
 - once the search is done the remaining windows run its best (lowest mean cost over its
   samples), marked "best" in the manifest;
 - the frames of rebuild and refit windows are those of the same sequence without tuning,
   bit for bit (a configuration changes how fast a frame renders, not what it shows);
 - a second run with the same database is answered from it (same frames, same states);
 - bad input: a still scene, a target other than the accel, an objective that is not a
   time, --tune-window 0 -- clear errors, exit 2.

Environment: TT_BUILD_ROOT, TT_SOURCE_ROOT (tests/meson.build); reads the database through
tools/tttools/db.py (the library's binding) and the EXRs with OpenImageIO."""
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import OpenImageIO as oiio

from tools.tttools import db as ttdb

HOST = os.path.join(os.environ["TT_BUILD_ROOT"], "host", "host")
SRC = os.environ["TT_SOURCE_ROOT"]
SCENE = os.path.join(SRC, "scenes", "animated-cornell", "scene.json")
STILL = os.path.join(SRC, "scenes", "cornell-box", "scene.json")
WINDOW = 4
FRAMES = 24  # 0:23, six windows
failures = checks = 0


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def host(*args):
    return subprocess.run([HOST, *args], capture_output=True, text=True)


def sequence(out, *extra, scene=SCENE):
    r = host("--sequence", f"0:{FRAMES - 1}", "--spp", "1", "--res", "32x32", "--seed", "5",
             "--threads", "2", "--out-dir", out, *extra, scene)
    check(r.returncode == 0, f"{' '.join(extra)}: exit {r.returncode}: {r.stderr}")
    try:
        with open(os.path.join(out, "manifest.json")) as f:
            return json.load(f)["frames"], r.stderr
    except (OSError, ValueError, KeyError) as e:
        check(False, f"{out}/manifest.json: {e}")
        return [], r.stderr


def pixels(folder, frame):
    inp = oiio.ImageInput.open(os.path.join(folder, f"color_{frame:04d}.exr"))
    if inp is None:
        check(False, f"open {folder} frame {frame}: {oiio.geterror()}")
        return np.zeros((1,))
    px = inp.read_image(0, 0, 0, 3, "float")
    inp.close()
    return px


def windows(frames):
    """The manifest's frames grouped by their tuning window, in order."""
    out = {}
    for f in frames:
        out.setdefault(f.get("tune", {}).get("window"), []).append(f)
    return [out[k] for k in sorted(k for k in out if k is not None)]


def check_rows(rows, frames, label):
    """Each row is one measured window: its state, and means of the frames' own times."""
    by_frame = {f["index"]: f for f in frames}
    check(rows and all(ttdb.ok(r) for r in rows), f"{label}: {len(rows)} measured rows")
    for r in rows:
        seq = r["context"].get("sequence", {})
        first = seq.get("frame")
        check(first is not None and first % WINDOW == 0 and seq.get("window") == WINDOW,
              f"{label}: row state {seq}")
        if first is None:
            continue
        check(abs(r["camera"].get("sequence_time", -1) - first / 24.0) < 1e-6,
              f"{label}: row camera {r['camera']}")
        check(r["indicators"] is not None and len(r["indicators"]) > 0, f"{label}: indicators")
        win = [by_frame[i] for i in range(first, min(first + WINDOW, FRAMES))]
        upd = sum(f["update_ms"] for f in win) / len(win)
        ren = sum(f["render_ms"] for f in win) / len(win)
        # the manifest rounds to 1 us
        check(abs(r["build_ms"] - upd) < 2e-3 and abs(r["render_ms"] - ren) < 2e-3,
              f"{label}: frame {first}: row {r['build_ms']:.4f} + {r['render_ms']:.4f} ms, "
              f"frames' means {upd:.4f} + {ren:.4f}")
        check(abs(r["cost"] - (r["build_ms"] + r["render_ms"])) < 1e-9 and
              r["objective"] == "build+render", f"{label}: cost of frame {first}")
        check(win[0]["tune"].get("config") == r["config"],
              f"{label}: frame {first}: the row's configuration is the one the window ran")


def check_windows(frames, rows, label):
    ws = windows(frames)
    check(len(ws) == FRAMES // WINDOW and all(len(w) == WINDOW for w in ws),
          f"{label}: windows {[len(w) for w in ws]}")
    prev = None
    for w in ws:
        cfg = w[0]["tune"].get("config")
        check(cfg is not None, f"{label}: window {w[0]['tune']} names its configuration")
        if cfg is None:
            continue
        if prev is not None and cfg != prev:
            check(w[0]["update"] == "rebuild",
                  f"{label}: frame {w[0]['index']}: a new configuration starts with a rebuild")
        interval = cfg.get("refitInterval", 0)
        if cfg.get("updateMethod") == "refit" and (interval == 0 or interval > WINDOW) and \
                not cfg.get("refitSahGrowth"):
            check(all(f["update"] == "refit" for f in w[1:]),
                  f"{label}: refit window at {w[0]['index']}: {[f['update'] for f in w]}")
        if cfg.get("updateMethod") == "rebuild":
            check(all(f["update"] == "rebuild" for f in w), f"{label}: rebuild window")
        prev = cfg
    # the windows after the search run its best: the lowest mean cost over its samples
    best_ws = [w for w in ws if w[0]["tune"]["mode"] == "best"]
    measured = [w for w in ws if w[0]["tune"]["mode"] != "best"]
    check(len(measured) == len(rows), f"{label}: {len(measured)} measured windows, {len(rows)} rows")
    costs = {}
    for r in rows:
        costs.setdefault(json.dumps(r["config"], sort_keys=True), []).append(r["cost"])
    best = min(costs, key=lambda k: sum(costs[k]) / len(costs[k])) if costs else None
    check(best_ws and all(json.dumps(w[0]["tune"]["config"], sort_keys=True) == best for w in best_ws),
          f"{label}: {len(best_ws)} windows after the search run the best configuration")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        dbp = os.path.join(tmp, "tuning.db")
        plain, _ = sequence(os.path.join(tmp, "plain"))
        # random exploration of the update method and two builder parameters, 3 proposals:
        # windows 1-4 measure (the default first), 5-6 run the best
        common = ["--explore", "3", "--tune-window", str(WINDOW), "--db", dbp,
                  "--tune-params", "updateMethod,refitInterval,quality,compact"]
        frames, log = sequence(os.path.join(tmp, "tuned"), *common)
        check("tuning along the sequence" in log, f"the log says what was tuned: {log}")
        rows = [r for r in ttdb.samples(dbp, "accel_embree")]
        check(len(rows) == 4, f"default + 3 explored windows recorded: {len(rows)} rows")
        check_rows(rows, frames, "explore")
        check_windows(frames, rows, "explore")
        check(rows and rows[0]["mode"] == "default", "the first window measures the default")
        # (updateMethod instances intersects in each object's own space: its hits may differ
        # from a flat tree's in the last bits, so its windows are left out of this check)
        method = {}
        for w in windows(frames):
            for f in w:
                method[f["index"]] = w[0]["tune"]["config"]["updateMethod"]
        same = [i for i in range(FRAMES) if method.get(i) in ("rebuild", "refit")]
        check(len(same) >= 2 * WINDOW, f"rebuild/refit windows to compare: {same}")
        for i in same:
            check(np.array_equal(pixels(os.path.join(tmp, "tuned"), i),
                                 pixels(os.path.join(tmp, "plain"), i)),
                  f"frame {i} ({method[i]}): tuning changed what the frame shows")
        # the same run again: the first window's state (frame 0) and the default are in the
        # database, so the default is answered, not measured; the proposals come a window
        # earlier than in the first run (other frames: other states) and are measured
        again, log2 = sequence(os.path.join(tmp, "again"), *common)
        check("3 measured (1 from the database)" in log2 and
              len(ttdb.samples(dbp, "accel_embree")) == 4 + 3,
              f"a second run is answered from the database where it can: {log2}")
        # a tuner along the sequence (the whole space, update parameters included)
        nm_frames, nm_log = sequence(os.path.join(tmp, "nm"), "--plugin", "tuner_nm",
                                     "--iterations", "3", "--tune-window", str(WINDOW),
                                     "--no-db")
        check("search done" in nm_log and len(windows(nm_frames)) == FRAMES // WINDOW,
              f"tuner_nm along the sequence: {nm_log}")
        # bad input
        bad = [
            (["--explore", "2", STILL], "does not move"),
            (["--explore", "2", "--tune", "integrator_pt", SCENE], "tunes the accel"),
            (["--explore", "2", "--objective", "metric:foo", SCENE], "frames' times"),
            (["--explore", "2", "--tune-window", "0", SCENE], "--tune-window"),
        ]
        for args, want in bad:
            r = host("--sequence", "0:3", "--res", "16x16", "--no-db",
                     "--out-dir", os.path.join(tmp, "bad"), *args)
            check(r.returncode == 2 and want in r.stderr,
                  f"{' '.join(args[:-1])}: exit {r.returncode}, expected 2 and '{want}': {r.stderr}")
    print(f"host_seq_tune: {checks} checks, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
