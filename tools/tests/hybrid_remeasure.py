"""tools/hybrid/remeasure.py: the paired-rounds arithmetic on made-up costs, then the tool end
to end on a tiny baseline (two small scenes, 16x16, 3 cameras, 3 iterations; trained on one,
tested on the other): every test state re-measured in rounds, its ratios the per-round
ratios to the default of the same round (checked against the host's own median), the
roofline the fastest candidate or the default, fractions of it at most 1, the figures in the
summary the geo-means of the states, a rerun answered from the cache, bad input refused with
the option and what was expected. Numbers are not asserted (16x16 timings are noise); the
arithmetic and the bookkeeping are."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

from tools.hybrid import remeasure
from tools.tests.checks import check
from tools.tests import checks

PY = "/usr/bin/python3"
ROOT = os.environ.get("TT_SOURCE_ROOT") or os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))
BUILD = os.environ.get("TT_BUILD_ROOT") or os.path.join(ROOT, "build")
HOST = os.path.join(BUILD, "host", "host")


def close(a, b, tol=1e-9):
    return a is not None and b is not None and abs(a - b) <= tol * max(1.0, abs(a), abs(b))


def arithmetic():
    # paired ratios: a machine twice as slow in rounds 2-3 hits both alike, so the paired
    # ratio is 0.5 in every round, while a ratio of the raw medians would be 15/15 = 1
    r = remeasure.paired({"default": [10, 10, 20, 20], "search": [5, 5, 10, 10],
                          "nn": [12, 8, 30, None]})
    check(r["search"]["ratios"] == [0.5, 0.5, 0.5, 0.5] and r["search"]["median"] == 0.5,
          "paired ratios are per round, against the default of the same round")
    check(r["default"]["median"] == 1.0 and r["default"]["faster_rounds"] == 0, "the default is 1")
    check(close(r["nn"]["median"], 1.2) and r["nn"]["rounds"] == 3 and r["nn"]["faster_rounds"] == 1,
          "a missed round is left out of the median (1.2, 0.8, 1.5 -> 1.2)")
    check(r["nn"]["median_first"] == 1.0 and r["nn"]["median_second"] == 1.5,
          "half medians: rounds 1-2 and 3-4")
    check(remeasure.roofline(r) == ("search", 0.5), "the roofline is the fastest candidate")
    check(remeasure.roofline({"default": {"median": 1.0}, "search": {"median": 1.04},
                              "nn": {"median": 1.0}}) == ("default", 1.0),
          "the default is the roofline when nothing is faster (ties go to the default)")
    job = {"default_cost": 10.0, "best_cost": 8.0,
           "history": [{"cost": 12.0}, {"cost": 8.0}, {"cost": 1e300}]}
    ratios = {"default": {"median": 1.0, "faster_rounds": 0, "rounds": 4, "median_first": 1.0, "median_second": 1.0},
              "search": {"median": 1.05, "faster_rounds": 1, "rounds": 4, "median_first": 0.9, "median_second": 1.1},
              "nn": {"median": 0.95, "faster_rounds": 3, "rounds": 4, "median_first": 1.0, "median_second": 0.96}}
    f = remeasure.state_figures(job, {"nn": {"x": 1}}, ratios, ["nn"])
    # the search: default 10, 12, 8 (the infeasible 1e300 left out): n = 3, S = 3.0
    check(f["n"] == 3 and close(f["search_sum"], 3.0), "n and S from the baseline's trajectory")
    check(f["roofline_role"] == "nn" and close(f["roofline"], 0.95), "roofline: nn at 0.95")
    check(close(f["models"]["nn"]["speedup"], 3.0 / (3 * 0.95)) and close(f["models"]["nn"]["fraction"], 1.0),
          "speed-up S / (n p) and fraction r / p")
    check(close(f["models"]["search"]["fraction"], 0.95 / 1.05) and close(f["models"]["default"]["fraction"], 0.95),
          "the search's best and the default against the roofline")
    check(f["heldout_roofline_role"] == "search" and close(f["heldout_roofline"], 1.1),
          "held-out rounds: chosen on the first half (search 0.9), reported on the second (1.1)")
    check(close(f["search_best_baseline"], 0.8), "the search's best as the baseline measured it")


ENV = dict(os.environ, TT_HOST=HOST, MPLBACKEND="Agg")  # the binding of the host's build tree


def run(args, **kw):
    return subprocess.run([PY, "-m", "tools.hybrid.remeasure"] + args, cwd=ROOT, text=True, env=ENV,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, **kw)


def end_to_end(tmp):
    B = [PY, "-m", "tools.hybrid.baseline", "--host", HOST, "--db", f"{tmp}/b.db", "--work", f"{tmp}/w",
         "--cameras", "3", "--iterations", "3", "--res", "16x16",
         "--scene", f"box={ROOT}/scenes/cornell-box/path.json",
         "--scene", f"spec={ROOT}/scenes/cornell-box-variants/specular-box/scene.json"]
    p = subprocess.run(B, cwd=ROOT, text=True, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    check(p.returncode == 0, "a tiny baseline (2 scenes x 3 cameras x 2 objectives)")
    if p.returncode:
        print(p.stdout[-3000:])
        return
    rounds = 4
    common = ["--db", f"{tmp}/b.db", "--work", f"{tmp}/rm", "--host", HOST, "--nice", "0"]
    p = run(common + ["--out", f"{tmp}/out", "--train-scenes", "box", "--test-scenes", "spec",
                      "--rounds", str(rounds)])
    check(p.returncode == 0, "remeasure --train-scenes box --test-scenes spec")
    if p.returncode:
        print(p.stdout[-3000:])
        return
    res = json.load(open(f"{tmp}/out/remeasure.json"))
    rows = res["rows"]
    check(len(rows) == 6 and {r["scene"] for r in rows} == {"spec"} and res["states"] == 6,
          f"every test state (spec: 3 cameras x 2 objectives) and only those: {len(rows)}")
    check(res["measured_now"] == 6, "6 states measured")
    check(open(f"{tmp}/out/roofline_speed.png", "rb").read(8) == b"\x89PNG\r\n\x1a\n", "roofline_speed.png")
    md = open(f"{tmp}/out/remeasure.md").read()
    check("default is the roofline" in md and "| spec | 3 |" in md, "remeasure.md has the per-scene table")
    ok_rounds = ok_host = ok_roof = ok_frac = ok_def = True
    for r in rows:
        rec = json.load(open(os.path.join(tmp, "rm", "measure", f"spec_{r['camera']:03d}_{r['objective'].replace('+', '_')}.json")))
        d = rec["costs"][rec["roles"]["default"]]
        for role, i in rec["roles"].items():
            cs = rec["costs"][i]
            ok_rounds &= len(cs) == rounds and all(c is not None and c > 0 for c in cs)
            mine = r["ratios"][role]
            ok_rounds &= all(close(x, c / dc) for x, c, dc in zip(mine["ratios"], cs, d))
            # the host's median of its paired per-round ratios is the same figure
            ok_host &= close(mine["median"], rec["host_ratio_to_first"][i], 1e-6)
        meds = {role: v["median"] for role, v in r["ratios"].items()}
        ok_roof &= close(r["roofline"], min(meds.values())) and all(r["roofline"] <= v + 1e-12 for v in meds.values())
        ok_roof &= close(meds[r["roofline_role"]], r["roofline"]) and r["roofline"] <= 1.0
        ok_frac &= all(0 < m["fraction"] <= 1.0 + 1e-12 for m in r["models"].values())
        ok_frac &= set(r["models"]) == {"default", "search", "nn", "rbf", "static"}
        ok_def &= r["default_is_roofline"] == (r["roofline_role"] == "default")
        ok_def &= (r["roofline_role"] == "default") == all(v >= 1.0 for v in meds.values())
    check(ok_rounds, f"every candidate measured in all {rounds} rounds; ratios paired per round")
    check(ok_host, "each median equals the host's own median of the paired ratios (ratio_to_first)")
    check(ok_roof, "the roofline is the fastest re-measured candidate or the default (<= 1)")
    check(ok_frac, "every fraction of the roofline is in (0, 1]; every model and the references present")
    check(ok_def, "the default is the roofline exactly where no candidate is faster")
    for o in ("render", "build+render"):
        e = res["summary"][o]["spec"]
        sel = [r for r in rows if r["objective"] == o]
        g = math.exp(sum(math.log(r["models"]["nn"]["speedup"]) for r in sel) / len(sel))
        check(e["cameras"] == 3 and close(e["models"]["nn"]["speedup"], g) and
              e["default_is_roofline"] == sum(r["default_is_roofline"] for r in sel),
              f"{o}: the scene's figures are the geo-means / counts of its states")
    # a rerun measures nothing; other rounds measure again
    p = run(common + ["--train-scenes", "box", "--test-scenes", "spec", "--rounds", str(rounds)])
    check(p.returncode == 0 and "measured," not in p.stdout and p.stdout.count("cached") == 6,
          "a rerun is answered from the cache")
    # bad input: the option, the field, what was expected
    bad = [(common + ["--test-scenes", "spec", "--rounds", "3"], "--rounds 3: expected an even number"),
           (common + ["--test-scenes", "nosuch"], "--test-scenes: nosuch not among"),
           (common + ["--train-scenes", "box,spec", "--test-scenes", "spec"], "must be disjoint; spec in both"),
           (common + ["--test-scenes", "spec", "--res", "16"], "--res '16': expected WxH"),
           (common + ["--test-scenes", "spec", "--models", "nn,knn"], "--models: 'knn': expected some of"),
           (common + ["--test-scenes", "spec", "--objectives", "build"], "--objectives: 'build': expected"),
           (["--db", f"{tmp}/none.db", "--work", f"{tmp}/x", "--host", HOST, "--test-scenes", "spec"],
            f"--db {tmp}/none.db: no such file"),
           (["--db", f"{tmp}/out/remeasure.md", "--work", f"{tmp}/x", "--host", HOST, "--test-scenes", "spec"],
            "table hybrid_jobs: expected a baseline database")]
    for args, msg in bad:
        p = run(args)
        check(p.returncode != 0 and msg in p.stdout and "Traceback" not in p.stdout,
              f"refused: {msg}" + ("" if msg in p.stdout else f" (got: {p.stdout[-400:]!r})"))


def main():
    arithmetic()
    if not os.access(HOST, os.X_OK):
        check(False, f"{HOST}: the host is built")
    else:
        tmp = tempfile.mkdtemp(prefix="tt_remeasure.")
        try:
            end_to_end(tmp)
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
    print(f"hybrid_remeasure: {checks.failures} failed")
    return 1 if checks.failures else 0


if __name__ == "__main__":
    sys.exit(main())
