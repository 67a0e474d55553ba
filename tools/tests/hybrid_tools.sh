#!/usr/bin/env bash
# tools/hybrid end to end on two small scenes with camera paths (16x16, 6 cameras, 4
# iterations): the baseline generator is resumable (stopped after 5 jobs, run again: it does
# the rest, a third run has nothing to do) and its jobs are self-describing rows; the
# evaluation runs every protocol and model and two studies (the RBF's reward, its argmax
# candidates), measures side by side and writes the summary and the figures; epsilon.py runs
# two seeds; predict_cost.py times predict() on the protocols and compares two hosts' answers.
# Numbers are not asserted (a 16x16 image times noise); the pipeline is.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
PY=/usr/bin/python3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_hybrid_tools.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
host="$TT_BUILD_ROOT/host/host"
B=("$PY" -m tools.hybrid.baseline --host "$host" --db "$tmp/b.db" --work "$tmp/w"
   --cameras 6 --iterations 4 --res 16x16
   --scene "box=$TT_SOURCE_ROOT/scenes/cornell-box/path.json"
   --scene "spec=$TT_SOURCE_ROOT/scenes/cornell-box-variants/specular-box/scene.json")

"${B[@]}" --max-jobs 5 >"$tmp/b1.log" 2>&1 || { cat "$tmp/b1.log"; fail "baseline (first 5 jobs)"; }
[ "$("${B[@]}" --list | grep -c '^done')" = 5 ] || fail "5 jobs should be done after --max-jobs 5"
"${B[@]}" >"$tmp/b2.log" 2>&1 || { cat "$tmp/b2.log"; fail "baseline (resumed)"; }
grep -q "24 jobs, 5 already in" "$tmp/b2.log" || { cat "$tmp/b2.log"; fail "the rerun did not skip the 5 jobs done"; }
"${B[@]}" >"$tmp/b3.log" 2>&1
grep -q "24 jobs, 24 already in .* 0 to run" "$tmp/b3.log" || { cat "$tmp/b3.log"; fail "a third run should have nothing to do"; }
# self-describing rows: every sample row says its scene, path sample and clock
q() { "$PY" -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute(sys.argv[2]).fetchone()[0])' "$@"; }
n=$(q "$tmp/b.db" "SELECT count(*) FROM samples WHERE camera NOT LIKE '%\"path_index\":%' OR context NOT LIKE '%\"clock\":\"cpu\"%'")
[ "$n" = 0 ] || fail "$n rows without path_index or clock"
n=$(q "$tmp/b.db" "SELECT count(*) FROM hybrid_jobs WHERE iterations = 4 AND resolution = '16x16' AND history LIKE '[%'")
[ "$n" = 24 ] || fail "hybrid_jobs has $n complete rows, expected 24"
"${B[@]}" --job nosuch:3:render >/dev/null 2>&1 && fail "--job of an unknown scene should be refused"
"${B[@]}" --scenes nosuch >/dev/null 2>&1 && fail "--scenes nosuch should be refused"
# --dump / --restore: the same jobs and rows in a new file (schema version kept: the host
# adds to it), refused over an existing file or where a scene is not the recorded one
"${B[@]}" --dump "$tmp/b.sql.xz" >/dev/null || fail "--dump"
R=("${B[@]}" --db "$tmp/r.db")
"${R[@]}" --restore "$tmp/b.sql.xz" >"$tmp/r.log" 2>&1 || { cat "$tmp/r.log"; fail "--restore"; }
grep -q "24 jobs, $(q "$tmp/b.db" "SELECT count(*) FROM samples") samples" "$tmp/r.log" || { cat "$tmp/r.log"; fail "restored counts"; }
[ "$("${R[@]}" --list | grep -c '^done')" = 24 ] || fail "the restored DB should have its 24 jobs done"
[ "$(q "$tmp/r.db" "PRAGMA user_version")" = "$(q "$tmp/b.db" "PRAGMA user_version")" ] || fail "user_version"
"${R[@]}" --restore "$tmp/b.sql.xz" >/dev/null 2>&1 && fail "--restore over an existing file should be refused"
"${R[@]}" --cameras 7 --max-jobs 1 >"$tmp/r2.log" 2>&1 || { cat "$tmp/r2.log"; fail "a job into the restored DB"; }
[ "$(q "$tmp/r.db" "SELECT count(*) FROM hybrid_jobs")" = 25 ] || fail "the restored DB did not take a new job"
if "${B[@]}" --db "$tmp/r3.db" --scene "box=$TT_SOURCE_ROOT/scenes/cornell-box-variants/specular-box/scene.json" \
     --restore "$tmp/b.sql.xz" >"$tmp/r3.log" 2>&1; then fail "--restore with another scene should fail"; fi
grep -q "box: .* has scene id" "$tmp/r3.log" && [ ! -e "$tmp/r3.db" ] || { cat "$tmp/r3.log"; fail "scene id check"; }

E=("$PY" -m tools.hybrid.evaluate --db "$tmp/b.db" --work "$tmp/e" --out "$tmp/f"
   --host "$host" --splits 2 --rounds 1 --min-cameras 4 --nice 0 --jobs 2
   --variants reward,candidates --variant-splits 1)
"${E[@]}" >"$tmp/e.log" 2>&1 || { cat "$tmp/e.log"; fail "evaluate"; }
for f in summary.json summary.md rows.json fig3_16_example.png fig3_17_speedup_render.png fig3_18_roofline_render.png \
         fig3_19_break_even_render.png fig3_20_speedup_total.png fig3_21_roofline_total.png \
         loso_render.png; do
  [ -s "$tmp/f/$f" ] || { cat "$tmp/e.log"; fail "evaluate did not write $f"; }
done
"$PY" - "$tmp/f/summary.json" <<'EOF' || fail "summary.json"
import json, math, sys
s = json.load(open(sys.argv[1]))
for key in ("render/nn", "render/rbf", "render/static", "build+render/nn"):
    t = s["table"][key]
    assert t["n"] > 0 and math.isfinite(t["speedup"]) and t["speedup"] > 0, (key, t)
    assert math.isfinite(t["roofline"]) and math.isfinite(t["loso_speedup"]), (key, t)
assert s["scenes"] == {"box": 6, "spec": 6}, s["scenes"]
# the studies: the relative reward measured beside the default on the same split, the
# argmax candidates compared against the largest set from the predictions alone
st = s["studies"]["reward-relative/render/rbf"]
assert st["n"] > 0 and math.isfinite(st["speedup"]) and math.isfinite(st["default_speedup"]), st
c = s["candidates"]["cand-4096-3/render"]
assert c["same_share"] == 1.0 and c["q_gap_max"] == 0.0, c
assert 0.0 <= s["candidates"]["cand-0-0/render"]["same_share"] <= 1.0
for o in ("render", "build+render"):
    r = s["reward_spread"][o]
    assert r["states"] == 12 and 0.0 <= r["within_share_inverse"] <= 1.0, r
EOF
grep -q "Argmax candidates" "$tmp/f/summary.md" || fail "summary.md has no candidates table"
# a second run measures nothing new (cached)
"${E[@]}" >"$tmp/e2.log" 2>&1 || fail "evaluate (cached)"
if grep -q "measuring" "$tmp/e2.log"; then cat "$tmp/e2.log"; fail "the second evaluation measured again"; fi
# too few cameras for the protocol: a clear error
if "$PY" -m tools.hybrid.evaluate --db "$tmp/b.db" --work "$tmp/e3" --host "$host" \
     --min-cameras 50 >"$tmp/e3.log" 2>&1; then fail "evaluate with too few cameras should fail"; fi
grep -q "no scene has 50 cameras" "$tmp/e3.log" || { cat "$tmp/e3.log"; fail "message"; }
# --train-scenes / --test-scenes: one held-out protocol (learn from every box camera, predict
# every spec camera); its training database holds box's rows only; overlapping or unknown
# sets are refused
"${E[@]}" --out "$tmp/fh" --train-scenes box --test-scenes spec >"$tmp/eh.log" 2>&1 \
  || { cat "$tmp/eh.log"; fail "evaluate --train-scenes box --test-scenes spec"; }
"$PY" - "$tmp/fh/summary.json" "$tmp/e/train" "$tmp/b.db" <<'EOF' || { cat "$tmp/eh.log"; fail "held-out summary"; }
import glob, json, math, sqlite3, sys
s = json.load(open(sys.argv[1]))
assert s["heldout"] == {"train": ["box"], "test": ["spec"]}, s.get("heldout")
for key in ("render/nn", "render/rbf", "render/static", "build+render/nn"):
    t = s["table"][key]
    assert t["n"] == 6 and math.isfinite(t["speedup"]), (key, t)  # every spec camera, once
    assert list(s["per_scene"][key]) == ["spec"], (key, s["per_scene"][key])
ids = dict(sqlite3.connect(sys.argv[3]).execute("SELECT scene, scene_id FROM hybrid_jobs GROUP BY scene"))
dbs = glob.glob(sys.argv[2] + "/heldout_*.db")
assert len(dbs) == 2, dbs  # one per objective
for db in dbs:
    got = [r[0] for r in sqlite3.connect(db).execute("SELECT DISTINCT scene_id FROM samples")]
    assert got == [ids["box"]], (db, got)
EOF
"${E[@]}" --train-scenes box,spec --test-scenes spec >"$tmp/eh2.log" 2>&1 && fail "overlapping scene sets should be refused"
grep -q "must be disjoint; spec in both" "$tmp/eh2.log" || { cat "$tmp/eh2.log"; fail "message (disjoint)"; }
"${E[@]}" --test-scenes nosuch >"$tmp/eh3.log" 2>&1 && fail "--test-scenes nosuch should be refused"
grep -q "test-scenes: nosuch not among" "$tmp/eh3.log" || { cat "$tmp/eh3.log"; fail "message (unknown)"; }
# predict_cost.py: predict() against the frame on the same protocols, and a reference host's
# answers compared (the same host here: every answer the same, exit 0)
PC=("$PY" -m tools.hybrid.predict_cost --db "$tmp/b.db" --work "$tmp/pc" --out "$tmp/fp"
    --host "$host" --reference-host "$host" --splits 1 --min-cameras 4 --models rbf,nn
    --set predictor_rbf.poolSize=1)
"${PC[@]}" >"$tmp/pc.log" 2>&1 || { cat "$tmp/pc.log"; fail "predict_cost.py"; }
"$PY" - "$tmp/fp/predict_cost.json" "$tmp/pc" <<'EOF' || fail "predict_cost.json"
import json, math, sys
s = json.load(open(sys.argv[1]))["summary"]
for key in ("render/rbf", "build+render/rbf", "render/nn"):
    t = s["table"][key]
    assert t["n"] == 2 + 12, (key, t)  # split 0: 2 scenes x 1 camera (20% of 6); LOSO: 12
    assert t["same_config"] == t["n"], (key, t)
    assert t["value_rel_diff_max"] == (0.0 if key.endswith("rbf") else None), (key, t)
    assert 0 < t["predict_ms_median"] and math.isfinite(t["share_of_frame"]), (key, t)
# --set reached the RBF's runs: a pool of 1 and the default are its argmax's candidates
import glob
for f in glob.glob(sys.argv[2] + "/pred_*/*_rbf.json"):
    assert all(x["candidates"] == 2 for x in json.load(open(f))["predictions"]), f
EOF
"$PY" -m tools.hybrid.predict_cost --db "$tmp/b.db" --work "$tmp/pc" --models nosuch \
  >"$tmp/pc2.log" 2>&1 && fail "predict_cost.py --models nosuch should be refused"
grep -q "unknown model 'nosuch'" "$tmp/pc2.log" || { cat "$tmp/pc2.log"; fail "message"; }
# epsilon.py: host --hybrid along the path at epsilon 0 and 1, warm-started without the
# scene's own rows: epsilon 1 explores every state, epsilon 0 none (one build each)
EP=("$PY" -m tools.hybrid.epsilon --db "$tmp/b.db" --work "$tmp/eps" --out "$tmp/fe"
    --host "$host" --scenes box --objectives render --epsilons 0,1 --models nn --states 3:5
    --iterations 3 --res 16x16 --nice 0 --seeds 1,2)
"${EP[@]}" >"$tmp/ep.log" 2>&1 || { cat "$tmp/ep.log"; fail "epsilon.py"; }
[ -s "$tmp/fe/hybrid_epsilon.png" ] || fail "epsilon.py did not write its chart"
"$PY" - "$tmp/fe/epsilon.json" "$tmp/eps" <<'EOF' || fail "epsilon.json"
import json, math, sqlite3, sys
e = json.load(open(sys.argv[1]))
for seed in (1, 2):  # every seed's runs, each against its own epsilon-1 run
    rows = {r["epsilon"]: r for r in e["rows"] if r["seed"] == seed}
    assert rows[1.0]["explore"] == 3 and rows[1.0]["exploit"] == 0 and rows[1.0]["speedup"] == 1.0, rows
    assert rows[0.0]["explore"] == 0 and rows[0.0]["exploit"] == 3, rows
    assert math.isfinite(rows[0.0]["speedup"]) and rows[0.0]["speedup"] > 0, rows
m = {r["epsilon"]: r for r in e["mean_over_seeds"]}
assert m[0.0]["seeds"] == [1, 2] and m[0.0]["speedup_min"] <= m[0.0]["speedup"] <= m[0.0]["speedup_max"], m
# the warm start holds the other scene's rows only
n = sqlite3.connect(sys.argv[2] + "/without_box.db").execute(
    "SELECT count(DISTINCT scene_id) FROM samples").fetchone()[0]
assert n == 1, n
EOF
# with several test scenes the warm start holds none of them: a copy of the baseline with a
# third scene (spec's rows again under another scene id) tested beside box learns from spec only
cp "$tmp/b.db" "$tmp/b3.db"
"$PY" - "$tmp/b3.db" <<'EOF' || fail "a baseline with a third scene"
import sqlite3, sys
con = sqlite3.connect(sys.argv[1])
sid = con.execute("SELECT scene_id FROM hybrid_jobs WHERE scene = 'spec'").fetchone()[0]
cols = [r[1] for r in con.execute("PRAGMA table_info(samples)") if r[1] not in ("id", "scene_id")]
con.execute(f"INSERT INTO samples (scene_id, {','.join(cols)}) SELECT 'third', {','.join(cols)} "
            "FROM samples WHERE scene_id = ?", (sid,))
jcols = [r[1] for r in con.execute("PRAGMA table_info(hybrid_jobs)") if r[1] not in ("job", "scene", "scene_id")]
con.execute(f"INSERT INTO hybrid_jobs (job, scene, scene_id, {','.join(jcols)}) SELECT "
            f"'third' || substr(job, 5), 'third', 'third', {','.join(jcols)} FROM hybrid_jobs WHERE scene = 'spec'")
con.commit()
EOF
EP3=("$PY" -m tools.hybrid.epsilon --db "$tmp/b3.db" --work "$tmp/eps3" --host "$host" --objectives render
     --epsilons 1 --models nn --states 3:3 --iterations 1 --res 16x16 --nice 0)
"${EP3[@]}" --scenes box,third >"$tmp/ep3.log" 2>&1 || { cat "$tmp/ep3.log"; fail "epsilon.py --scenes box,third"; }
"$PY" - "$tmp/b3.db" "$tmp/eps3/without_box+third.db" <<'EOF' || fail "the warm start of box,third"
import sqlite3, sys
spec = sqlite3.connect(sys.argv[1]).execute("SELECT scene_id FROM hybrid_jobs WHERE scene = 'spec'").fetchone()[0]
got = [r[0] for r in sqlite3.connect(sys.argv[2]).execute("SELECT DISTINCT scene_id FROM samples")]
assert got == [spec], got
EOF
"${EP3[@]}" --scenes box,third,spec >"$tmp/ep4.log" 2>&1 && fail "epsilon.py with every scene tested should be refused"
grep -q "no scene is left to warm-start" "$tmp/ep4.log" || { cat "$tmp/ep4.log"; fail "message (no warm start)"; }
echo "hybrid_tools: ok"
