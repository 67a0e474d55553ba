#!/usr/bin/python3
"""The hybrid loop along an animated sequence (host --hybrid --sequence A:B over
scenes/animated-cornell): each window of --tune-window frames is a state, explored (a search
replaying the window, --iterations K) with probability --epsilon, else exploited (the model's
one configuration, played once).

 - determinism: the same seed draws the same explore/exploit per state; a warm-started
   exploit run (epsilon 0) predicts the same configurations and writes the same frames;
 - epsilon 0 with an empty model: every state exploits, falls back to the default and says
   so (manifest, --stats, log);
 - epsilon 1: every state explores: K + 1 database rows in its state (the frame in the
   context, indicators of its geometry, costs = means of the played frames' update + render),
   its written frames played with the best of them, and the manifest names state, mode and
   configuration per frame; --tune-window 1 makes every frame a state;
 - a warm-started exploit run's frames are bit for bit those of a plain --sequence with the
   predicted configuration set by --set, each state played once;
 - rows measured along a sequence and rows of a still never teach each other's warm start;
 - bad input: a still scene, --tune-window 0, a post-filter: clear errors, exit 2.

Environment: TT_BUILD_ROOT, TT_SOURCE_ROOT (tests/meson.build); reads the database through
tools/tttools/db.py and the EXRs with OpenImageIO."""
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
FRAMES = 12  # 0:11, three states
K = 3
PARAMS = "updateMethod,refitInterval,quality,compact"
failures = checks = 0


def check(cond, what):
    global failures, checks
    checks += 1
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def host(*args):
    return subprocess.run([HOST, *args], capture_output=True, text=True)


def sequence(out, *extra, frames=FRAMES):
    """The manifest's frames, the --stats record (when asked for) and the log of one run."""
    r = host("--sequence", f"0:{frames - 1}", "--spp", "1", "--res", "32x32", "--seed", "5",
             "--threads", "2", "--out-dir", out, *extra, SCENE)
    check(r.returncode == 0, f"{' '.join(extra)}: exit {r.returncode}: {r.stderr}")
    stats = None
    try:
        with open(os.path.join(out, "manifest.json")) as f:
            man = json.load(f)["frames"]
        if "--stats" in extra:
            with open(extra[list(extra).index("--stats") + 1]) as f:
                stats = json.load(f)["hybrid"]
    except (OSError, ValueError, KeyError) as e:
        check(False, f"{out}: {e}")
        return [], stats, r.stderr
    return man, stats, r.stderr


def pixels(folder, frame):
    inp = oiio.ImageInput.open(os.path.join(folder, f"color_{frame:04d}.exr"))
    if inp is None:
        check(False, f"open {folder} frame {frame}: {oiio.geterror()}")
        return np.zeros((1,))
    px = inp.read_image(0, 0, 0, 3, "float")
    inp.close()
    return px


def hybrid(out, stats, *extra, frames=FRAMES, window=WINDOW):
    return sequence(out, "--hybrid", "--tune-window", str(window), "--iterations", str(K),
                    "--tune-params", PARAMS, "--stats", stats, *extra, frames=frames)


def sets_of(config):
    """--set arguments of a configuration's JSON object."""
    out = []
    for k, v in config.items():
        v = ("true" if v else "false") if isinstance(v, bool) else v
        out += ["--set", f"accel_embree.{k}={v}"]
    return out


def check_states(frames, stats, label, window=WINDOW, nframes=FRAMES):
    """Every frame names its state; a state's frames are its window, one mode, one config."""
    check(len(frames) == nframes and [f["index"] for f in frames] == list(range(nframes)),
          f"{label}: frames {[f['index'] for f in frames]}")
    nstates = (nframes + window - 1) // window
    check(stats is not None and stats["states_done"] == nstates and
          len(stats["states"]) == nstates, f"{label}: {nstates} states in --stats")
    by_index = {f["index"]: f for f in frames}
    for f in frames:
        hy = f.get("hybrid", {})
        s = f["index"] // window
        check(hy.get("state") == s and hy.get("window") == [s * window,
                                                             min(s * window + window, nframes) - 1],
              f"{label}: frame {f['index']}: {hy}")
        if stats and s < len(stats["states"]):
            st = stats["states"][s]
            check(hy.get("mode") == st["mode"] and hy.get("config") == st["config"],
                  f"{label}: frame {f['index']}: manifest and --stats agree on mode and config")
        if f["index"] % window == 0:
            # built from scratch, unless the state goes on with the configuration running
            prev = by_index.get(f["index"] - 1, {}).get("hybrid", {})
            cont = hy.get("continued")
            check(cont == (hy.get("plays") is not None and prev.get("config") == hy.get("config")
                           and hy.get("mode") == "exploit" and hy.get("plays") == 1) or
                  hy.get("mode") == "explore",
                  f"{label}: frame {f['index']}: continued {cont} (previous config "
                  f"{'same' if prev.get('config') == hy.get('config') else 'other'})")
            if not cont:
                check(f["update"] == "rebuild",
                      f"{label}: frame {f['index']}: a state's first frame is built from scratch")


def main():
    with tempfile.TemporaryDirectory() as tmp:
        j = lambda *p: os.path.join(tmp, *p)
        # epsilon 0, empty model: every state exploits the default, and says so
        frames, st, log = hybrid(j("cold"), j("cold.json"), "--epsilon", "0", "--no-db")
        check_states(frames, st, "cold")
        check(st and st["exploited"] == 3 and st["fallbacks"] == 3 and st["plays"] == 3,
              f"cold: every state exploits the default, played once: {st and st['plays']}")
        check(all(f["hybrid"]["mode"] == "exploit" and f["hybrid"]["fallback"] for f in frames),
              "cold: the manifest marks the fallback")
        check("no usable prediction" in log and "model had nothing to predict from" in log,
              f"cold: the log says the default ran for want of a model: {log}")
        # epsilon 1: every state searched, K + 1 rows in its own state
        dbp = j("train.db")
        frames, st, log = hybrid(j("explore"), j("explore.json"), "--epsilon", "1", "--db", dbp)
        check_states(frames, st, "explore")
        check(st and st["explored"] == 3 and st["exploited"] == 0, "explore: all states searched")
        rows = ttdb.samples(dbp, "accel_embree")
        check(len(rows) == 3 * (K + 1), f"explore: {len(rows)} rows, expected {3 * (K + 1)}")
        by_frame = {f["index"]: f for f in frames}
        for s in range(3):
            first = s * WINDOW
            mine = [r for r in rows if r["context"].get("sequence", {}).get("frame") == first]
            check(len(mine) == K + 1 and all(r["indicators"] for r in mine) and
                  all(r["context"].get("measure") == "mean per-frame accel update + render"
                      for r in mine) and
                  all(abs(r["camera"]["sequence_time"] - first / 24.0) < 1e-6 for r in mine),
                  f"explore: state {s}: {len(mine)} rows in its state")
            costs = {}
            for r in mine:
                check(abs(r["cost"] - r["build_ms"] - r["render_ms"]) < 1e-9,
                      "explore: cost = mean update + mean render")
                costs.setdefault(json.dumps(r["config"], sort_keys=True), []).append(r["cost"])
            if costs:
                best = min(costs, key=lambda k: sum(costs[k]) / len(costs[k]))
                cfg = by_frame[first]["hybrid"]["config"]
                check(json.dumps(cfg, sort_keys=True) == best,
                      f"explore: state {s}: the written frames ran the best of its search")
                win = [by_frame[i] for i in range(first, first + WINDOW)]
                # --stats' frame times are the written frames' (the last play's)
                upd = sum(f["update_ms"] for f in win) / WINDOW
                ren = sum(f["render_ms"] for f in win) / WINDOW
                check(abs(st["states"][s]["frames_update_ms"] - upd) < 2e-3 and
                      abs(st["states"][s]["frames_render_ms"] - ren) < 2e-3,
                      f"explore: state {s}: --stats frames times are the manifest's")
            check(st["states"][s]["plays"] in (K + 1, K + 2),
                  f"explore: state {s}: {st['states'][s]['plays']} plays for {K + 1} samples")
        # determinism: the same seed draws the same modes
        modes = []
        for run in ("d1", "d2"):
            _, s2, _ = hybrid(j(run), j(run + ".json"), "--epsilon", "0.5", "--no-db",
                              frames=24)
            modes.append([x["mode"] for x in s2["states"]] if s2 else None)
        check(modes[0] is not None and modes[0] == modes[1] and len(modes[0]) == 6,
              f"same seed, same explore/exploit draws: {modes}")
        # warm-started exploitation: the model answers per state, each state played once,
        # the frames those of a plain sequence with the predicted configuration
        warm = ["--epsilon", "0", "--warm-start", dbp, "--no-db"]
        frames, st, log = hybrid(j("warm"), j("warm.json"), *warm)
        check_states(frames, st, "warm")
        check(st and st["exploited"] == 3 and st["fallbacks"] == 0 and st["plays"] == 3 and
              st["warm_start"][0]["rows"] == len(rows),
              f"warm: 3 predicted states, played once each, {len(rows)} rows learnt: {st}")
        frames2, st2, _ = hybrid(j("warm2"), j("warm2.json"), *warm)
        # the first state's answer comes from the warm start alone: the same in every run
        # (later answers may differ: the model also learns its own answers' measured costs)
        check(st and st2 and st["states"][0]["config"] == st2["states"][0]["config"],
              "warm: the first prediction is deterministic")
        by2 = {f["index"]: f for f in frames2}
        configs = {}
        for f in frames:
            configs.setdefault(json.dumps(f["hybrid"]["config"], sort_keys=True), []).append(
                f["index"])
        for n, (cfg, idx) in enumerate(configs.items()):
            plain, _, _ = sequence(j(f"plain{n}"), *sets_of(json.loads(cfg)))
            for i in idx:
                check(np.array_equal(pixels(j("warm"), i), pixels(j(f"plain{n}"), i)),
                      f"warm: frame {i}: not the plain sequence's with --set {cfg}")
                if by2.get(i, {}).get("hybrid", {}).get("config") == json.loads(cfg):
                    check(np.array_equal(pixels(j("warm"), i), pixels(j("warm2"), i)),
                          f"warm: frame {i}: not deterministic")
        check(all(np.array_equal(pixels(j("warm"), i), pixels(j("warm2"), i))
                  for i in range(WINDOW)), "warm: the first state's frames are deterministic")
        # --predict --sequence: the model's answer per window's first frame, nothing
        # rendered; the first is the one the exploit run played (later states may differ:
        # the exploit run's model also learns from its own answers)
        r = host("--predict", "--sequence", f"0:{FRAMES - 1}", "--tune-window", str(WINDOW),
                 "--tune-params", PARAMS, "--warm-start", dbp, "--res", "32x32", "--threads",
                 "2", SCENE)
        try:
            pred = json.loads(r.stdout)["predictions"]
        except (ValueError, KeyError) as e:
            pred = []
            check(False, f"--predict --sequence: {e}: {r.stdout} {r.stderr}")
        check([p.get("frame") for p in pred] == [0, 4, 8] and st and
              pred[0]["config"] == st["states"][0]["config"],
              f"--predict --sequence: per window {[p.get('frame') for p in pred]}")
        # per-frame states
        frames, st, _ = hybrid(j("one"), j("one.json"), "--epsilon", "0", "--warm-start", dbp,
                               "--no-db", frames=5, window=1)
        check_states(frames, st, "per-frame", window=1, nframes=5)
        # per-frame states of an unchanged configuration go on updating its structure: a
        # refit configuration refits (as the plain sequence with it does), not rebuilt per frame
        cont = [f for f in frames[1:] if f["hybrid"]["continued"]]
        same = [f for f in frames[1:]
                if f["hybrid"]["config"] == frames[f["index"] - 1]["hybrid"]["config"]]
        check(cont == same, f"per-frame: exactly the states of an unchanged configuration "
              f"continue: {[f['index'] for f in cont]} vs {[f['index'] for f in same]}")
        refit = [f for f in cont if f["hybrid"]["config"]["updateMethod"] == "refit"]
        check(not refit or any(f["update"] == "refit" for f in refit),
              f"per-frame: continued refit states refit: {[f['update'] for f in refit]}")
        check(all(f["update"] == "rebuild" for f in frames[1:] if not f["hybrid"]["continued"]),
              "per-frame: a state that changes the configuration builds it from scratch")
        # rows of a still never teach a sequence's warm start (nor the other way round)
        still_db = j("still.db")
        r = host("--tune", "accel_embree", "--plugin", "tuner_nm", "--iterations", "2", "--tune-params", PARAMS,
                 "--objective", "build+render", "--res", "32x32", "--spp", "1", "--threads",
                 "2", "--db", still_db, "--out", j("still.exr"), SCENE)
        check(r.returncode == 0, f"still tune: {r.stderr}")
        _, st, log = hybrid(j("mix"), j("mix.json"), "--epsilon", "0", "--warm-start",
                            still_db, "--no-db")
        check(st and st["warm_start"][0]["rows"] == 0 and
              st["warm_start"][0]["mismatch"]["measure"]["rows"] > 0,
              f"a still's rows are not learnt along a sequence: {st and st['warm_start']}")
        r = host("--hybrid", "--camera-index", "0:0", "--epsilon", "0", "--objective",
                 "build+render", "--tune-params", PARAMS, "--warm-start", dbp, "--no-db",
                 "--res", "32x32", "--threads", "2", "--stats", j("still_h.json"), SCENE)
        try:
            with open(j("still_h.json")) as f:
                ws = json.load(f)["hybrid"]["warm_start"][0]
        except (OSError, ValueError, KeyError, IndexError) as e:
            ws = {"error": str(e), "stderr": r.stderr}
        check(ws.get("rows") == 0 and ws.get("mismatch", {}).get("measure", {}).get("rows"),
              f"a sequence's rows are not learnt by a still's hybrid loop: {ws}")
        # bad input
        bad = [
            (["--hybrid", STILL], "does not move"),
            (["--hybrid", "--tune-window", "0", SCENE], "--tune-window"),
            (["--hybrid", "--post", "post_taa", SCENE], "post-filter"),
            (["--hybrid", "--objective", "metric:foo", SCENE], "frames' times"),
            (["--predict", STILL], "does not move"),
        ]
        for args, want in bad:
            r = host("--sequence", "0:3", "--res", "16x16", "--no-db",
                     "--out-dir", j("bad"), *args)
            check(r.returncode == 2 and want in r.stderr,
                  f"{' '.join(args[:-1])}: exit {r.returncode}, expected 2 and '{want}': {r.stderr}")
    print(f"host_seq_hybrid: {checks} checks, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
