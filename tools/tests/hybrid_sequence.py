"""tools/hybrid/sequence.py end to end on tiny settings (16x16, 8 frames, windows of 4, 2
iterations, 2 rounds; train animated-cornell, validation living-room-cylinder, test
animated-stress, whose windows have distinct indicators (its camera moves), so the nearest
searched state of each is its own): train, validation and test rows kept apart (one database per scene,
search_TEST.db only the test scene's), the predictor chosen on the validation sequence, the
per-window best replay runs exactly the configurations the test sequence's search found
(predictor_nn taught that search answers each window with its best), every method's runs
have every frame, --test among --train is refused, a search database left by an unfinished
search is started afresh; a generated sequence's name
(tools/accel/anim_update.py's stress-detail, skinned-detail) resolves to the file that tool
generates, and an unknown scene name is refused before anything runs, naming the field. Figures are not asserted (a 16x16
frame times noise); the pipeline is."""
import json
import os
import sqlite3
import subprocess
import sys
import tempfile

SRC = os.environ["TT_SOURCE_ROOT"]
HOST = os.path.join(os.environ["TT_BUILD_ROOT"], "host", "host")
failures = 0


def check(cond, what):
    global failures
    if not cond:
        failures += 1
        print(f"FAIL: {what}", file=sys.stderr)


def scene_ids(db):
    with sqlite3.connect(db) as c:
        return {r[0] for r in c.execute("SELECT DISTINCT scene_id FROM samples")}


def check_generated_names():
    """Every name anim_update generates goes to its generator (recorded, not run: generating
    skinned-detail needs Blender and minutes); scenes/ folders resolve to their scene.json."""
    from tools.accel import anim_update
    from tools.hybrid import sequence
    asked = []
    real = anim_update.generated_scene
    anim_update.generated_scene = lambda name: asked.append(name) or f"/generated/{name}"
    try:
        for name in anim_update.GENERATED:
            got = sequence.scene_path(name)
            check(got == f"/generated/{name}", f"{name} resolves to its generated file: {got}")
        check(asked == list(anim_update.GENERATED), f"generated names asked: {asked}")
        got = sequence.scene_path("animated-cornell")
        check(got == os.path.join(SRC, "scenes", "animated-cornell", "scene.json") and not
              asked[len(anim_update.GENERATED):], f"a scenes/ folder resolves to {got}")
    finally:
        anim_update.generated_scene = real


def main():
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "seq.json")
        work = os.path.join(tmp, "work")
        cmd = [sys.executable, "-m", "tools.hybrid.sequence", "--host", HOST, "--train",
               "animated-cornell", "--validation", "living-room-cylinder", "--test",
               "animated-stress", "--frames", "0:7", "--res",
               "16x16", "--window", "4", "--iterations", "2", "--rounds", "2", "--work", work,
               "--out", out]
        # what a search stopped half way leaves in a --work folder (a database without its
        # finished record) is started afresh, not appended to
        os.makedirs(work)
        with open(os.path.join(work, "search_animated-stress.db"), "wb") as f:
            f.write(b"rows of a search that never finished")
        r = subprocess.run(cmd, cwd=SRC, capture_output=True, text=True)
        check(not [n for n in os.listdir(work) if n.endswith(".part")],
              f"no partial search record left: {os.listdir(work)}")
        check(r.returncode == 0, f"sequence.py: exit {r.returncode}: {r.stderr[-2000:]}")
        if r.returncode:
            return 1
        with open(out) as f:
            data = json.load(f)
        check(data["train"] == ["animated-cornell"] and
              data["validation"] == "living-room-cylinder" and data["test"] == "animated-stress",
              "train, validation and test named")
        vrows = data["validation_rows"]
        check(data["chosen"] in ("predictor_nn", "predictor_rbf") and
              vrows[data["chosen"]]["speedup"] == max(vrows[p]["speedup"]
                                                      for p in ("predictor_nn", "predictor_rbf")),
              f"the validation chooses the faster predictor: {data['chosen']} of {vrows}")
        check(data["search"]["states"] == 2 and data["best_agree"] == 2,
              f"the per-window best replay runs the search's best: {data['best_agree']} of 2")
        for k, runs in data["runs"].items():
            check(len(runs) == 2 and all([f["index"] for f in run] == list(range(8))
                                         for run in runs), f"{k}: 2 rounds of 8 frames")
        other = "predictor_rbf" if data["chosen"] == "predictor_nn" else "predictor_nn"
        check(set(data["summary"]) == {"default rebuild", "hybrid-predicted",
                                       f"hybrid-predicted ({other})", "per-window best"},
              f"methods: {list(data['summary'])}")
        check(abs(data["summary"]["per-window best"]["of_best"] - 1.0) < 1e-12 and
              abs(data["summary"]["default rebuild"]["speedup"] - 1.0) < 1e-12,
              "ratios are taken against the right runs")
        ids = [scene_ids(os.path.join(work, n)) for n in
               ("train_animated-cornell.db", "train_living-room-cylinder.db", "search_animated-stress.db")]
        check(all(len(i) == 1 for i in ids) and len(set.union(*ids)) == 3,
              f"train, validation and test rows kept apart: {ids}")
        check("goal: hybrid-predicted >= 1.3x default rebuild:" in r.stdout and
              "goal: hybrid-predicted within 5% of the per-window best:" in r.stdout,
              "both goals printed")
        bad = subprocess.run(cmd[:-2] + ["--train", "animated-stress"], cwd=SRC,
                             capture_output=True, text=True)
        check(bad.returncode != 0 and "keep them apart" in bad.stderr,
              f"--test among --train refused: {bad.stderr}")
        bad = subprocess.run(cmd[:-2] + ["--test", "no-such-scene"], cwd=SRC,
                             capture_output=True, text=True)
        check(bad.returncode != 0 and "no-such-scene" in bad.stderr and "--test" in bad.stderr
              and "scene.json" in bad.stderr and "stress-detail" in bad.stderr and
              not os.path.exists(os.path.join(work, "train_no-such-scene.json")),
              f"an unknown scene refused with the field and the expectation: {bad.stderr}")
    check_generated_names()
    print("hybrid_sequence: " + ("ok" if not failures else f"{failures} failed"))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
