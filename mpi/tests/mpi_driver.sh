#!/usr/bin/env bash
# tunetrace-mpi (issue 18) with 2 ranks on a tiny scene (16x16, 1 spp): tuning searches,
# explorations and a frame sequence cut into ranges.
#  - every job done once: the merged DB holds one tag per job and exactly the rows of the
#    tags (no row outside a job, no row twice); the frames are complete;
#  - the result equals single-process runs: the rows of the explorations (everything but
#    timings, machine and run ids) equal those of the same host commands run one by one, the
#    searches have the same number of rows per camera, and every frame has the pixels of one
#    host --sequence over the whole range (and the manifest its entries);
#  - a rank killed mid-run (SIGKILL of the rank process itself, while its job runs): under
#    mpirun --enable-recovery only that job is lost, the other rank finishes every other job
#    (7 of 8), --check names the lost one and exits 1, and a rerun completes the set; rank 0
#    killed: the worker stops within --liveness, nothing is left running, a rerun completes
#    it; without --enable-recovery Open MPI ends the run, the DB holds whole jobs only, and a
#    rerun completes the set (a third run has nothing to do);
#  - Ctrl-C (SIGINT to mpirun) stops every rank, keeps the finished jobs, leaves no process;
#  - bad job lists (unknown scene, empty range, a --post in a frame range, an option the
#    driver sets written --opt=value, an unknown key)
#    are refused before any rank starts work, naming the item, and create nothing.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
PY=/usr/bin/python3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_mpi_driver.XXXXXX")
pids=()
cleanup() { for p in "${pids[@]}"; do kill -9 "$p" 2>/dev/null || true; done; rm -rf "$tmp"; }
trap cleanup EXIT
host="$TT_BUILD_ROOT/host/host"
drv="${TT_MPI_DRIVER:-$TT_BUILD_ROOT/mpi/tunetrace-mpi}"
scene="$TT_SOURCE_ROOT/scenes/cornell-box/path.json"
MPIRUN=("${MPIRUN:-mpirun}" --allow-run-as-root --oversubscribe)
common=(--res 16x16 --threads 1 --spp 1 --clock cpu)
tune_args=(--plugin tuner_nm --tune accel_embree --iterations 4 --tune-spp 1 --seed 1)
explore_args=(--tune accel_embree)

jobs() {  # $1: the sequence folder; $2: the image size (default 16x16)
  cat <<JSON
{"host_args": ["--res", "${2:-16x16}", "--threads", "1", "--spp", "1", "--clock", "cpu"],
 "jobs": [
  {"kind": "tune", "scene": "$scene", "cameras": [0, 40], "objective": "render",
   "args": ["--plugin", "tuner_nm", "--tune", "accel_embree", "--iterations", "4", "--tune-spp", "1", "--seed", "1"]},
  {"kind": "explore", "scene": "$scene", "cameras": [10, 20, 30], "samples": 3, "seed": 7,
   "args": ["--tune", "accel_embree"]},
  {"kind": "frames", "scene": "$scene", "range": "0:5", "chunk": 2, "out_dir": "$1"}
 ]}
JSON
}
jobs "$tmp/seq2" >"$tmp/jobs2.json"
jobs "$tmp/seq1" >"$tmp/jobs1.json"
jobs "$tmp/seqk" >"$tmp/jobsk.json"

q() { "$PY" -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute(sys.argv[2]).fetchone()[0])' "$@"; }
# the rows of the cameras of mode $2 (their defaults included), without timings, ids, machine and time: one line per row, sorted
content() {
  "$PY" - "$1" "$2" <<'PYEOF'
import json, sqlite3, sys
con = sqlite3.connect(sys.argv[1])
rows = con.execute("SELECT scene_id, camera, context, plugin, plugin_version, config, objective,"
                   " status, mode, iteration FROM samples WHERE camera IN (SELECT camera FROM samples"
                   " WHERE mode = ?)", (sys.argv[2],)).fetchall()
for r in sorted(json.dumps(r) for r in rows):
    print(r)
PYEOF
}
check_complete() {  # $1: DB, $2: sequence folder, $3: label
  local db=$1
  [ "$(q "$db" "SELECT count(*) FROM merges")" = 8 ] || fail "$3: $(q "$db" "SELECT count(*) FROM merges") tags, expected 8 jobs"
  [ "$(q "$db" "SELECT count(*) FROM samples")" = "$(q "$db" "SELECT sum(rows) FROM merges")" ] ||
    fail "$3: rows outside the jobs' tags"
  # no row twice: (camera, objective, mode, iteration) is unique per job and cameras differ
  [ "$(q "$db" "SELECT count(*) FROM (SELECT DISTINCT camera, objective, mode, iteration FROM samples)")" = \
    "$(q "$db" "SELECT count(*) FROM samples")" ] || fail "$3: a row is in the DB twice"
  [ "$(q "$db" "SELECT count(*) FROM samples WHERE rank IS NULL OR host IS NULL")" = 0 ] ||
    fail "$3: rows without rank or host"
  [ "$(q "$db" "SELECT count(*) FROM samples WHERE mode = 'explore'")" = 9 ] || fail "$3: explore rows"
  for f in 0 1 2 3 4 5; do
    [ -s "$2/color_000$f.exr" ] || fail "$3: frame $f missing"
  done
  [ -s "$2/manifest.json" ] || fail "$3: no manifest"
  [ ! -e "$2/.tunetrace-mpi/0-1" ] || fail "$3: a range's work folder was left"
}

# --- 2 ranks, then 1 rank, then the single-process runs ---
"${MPIRUN[@]}" -np 2 "$drv" --jobs "$tmp/jobs2.json" --db "$tmp/np2.db" --host "$host" \
  --scratch "$tmp" >"$tmp/np2.log" 2>&1 || { cat "$tmp/np2.log"; fail "mpirun -np 2"; }
check_complete "$tmp/np2.db" "$tmp/seq2" "np 2"
[ "$(q "$tmp/np2.db" "SELECT count(DISTINCT rank) FROM samples")" = 2 ] || echo "note: one rank did every tuning job"
"${MPIRUN[@]}" -np 1 "$drv" --jobs "$tmp/jobs1.json" --db "$tmp/np1.db" --host "$host" \
  --scratch "$tmp" >"$tmp/np1.log" 2>&1 || { cat "$tmp/np1.log"; fail "mpirun -np 1"; }
check_complete "$tmp/np1.db" "$tmp/seq1" "np 1"
for cam in 10 20 30; do
  "$host" --quiet "${common[@]}" "${explore_args[@]}" --camera-index $cam --explore 3 --seed 7 \
    --db "$tmp/single.db" --out "$tmp/single.exr" "$scene" || fail "single explore $cam"
done
"$host" --quiet "${common[@]}" --sequence 0:5 --out-dir "$tmp/seqs" "$scene" || fail "single sequence"
content "$tmp/single.db" explore >"$tmp/single.txt"
content "$tmp/np2.db" explore >"$tmp/np2.txt"
content "$tmp/np1.db" explore >"$tmp/np1.txt"
[ -s "$tmp/single.txt" ] || fail "no single-process rows"
cmp -s "$tmp/single.txt" "$tmp/np2.txt" || { diff "$tmp/single.txt" "$tmp/np2.txt" | head; fail "np 2 explore rows differ from single-process runs"; }
cmp -s "$tmp/np1.txt" "$tmp/np2.txt" || fail "np 1 and np 2 explore rows differ"
per_cam="SELECT group_concat(n) FROM (SELECT camera, count(*) n FROM samples WHERE mode = 'tune' GROUP BY camera ORDER BY camera)"
[ "$(q "$tmp/np2.db" "$per_cam")" = "$(q "$tmp/np1.db" "$per_cam")" ] || fail "tune rows per camera differ"
[ "$(q "$tmp/np2.db" "SELECT count(*) FROM samples WHERE mode = 'tune'")" = 8 ] || fail "tune rows: 4 per camera"
"$PY" - "$tmp/seqs" "$tmp/seq2" "$tmp/seq1" <<'PYEOF' || fail "frames differ from one host --sequence"
import glob, json, os, sys
import numpy as np
import OpenImageIO as oiio
ref, outs = sys.argv[1], sys.argv[2:]
def px(p):
    i = oiio.ImageInput.open(p)
    assert i, p
    a = i.read_image("float")
    i.close()
    return a
def entries(d):
    m = json.load(open(os.path.join(d, "manifest.json")))
    for f in m["frames"]:
        for k in ("render_ms", "reference_ms", "post_ms"):
            f.pop(k, None)
    return m
files = sorted(os.path.basename(p) for p in glob.glob(os.path.join(ref, "*.exr")))
assert len(files) == 24, files
for out in outs:
    got = sorted(os.path.basename(p) for p in glob.glob(os.path.join(out, "*.exr")))
    assert got == files, (out, got)
    for f in files:
        assert np.array_equal(px(os.path.join(ref, f)), px(os.path.join(out, f))), (out, f)
    assert entries(ref) == entries(out), out
PYEOF

# the checking script users run (tools/mpi/check_db.py): 0 jobs lost, 0 rows duplicated or
# outside the jobs, np 2 = np 1 in everything but timings; and it fails on a run cut short
"$PY" -m tools.mpi.check_db --driver "$drv" --jobs "$tmp/jobs2.json" \
  --db "$tmp/np2.db" --against "$tmp/np1.db" >"$tmp/check.log" 2>&1 || { cat "$tmp/check.log"; fail "check_db.py np2 against np1"; }
grep -q "8 of 8 jobs merged .* 0 jobs lost, 0 rows duplicated, +0 rows outside the jobs" "$tmp/check.log" || { cat "$tmp/check.log"; fail "check_db.py summary"; }
"$PY" -m tools.mpi.check_db --driver "$drv" --jobs "$tmp/jobs2.json" \
  --db "$tmp/np1.db" >/dev/null 2>&1 && fail "check_db.py accepted np1.db against the list of np2 (other frame tags)"

# --- a rank killed mid-run, then reruns ---
# (64x64 jobs for the recovery cases: each runs long enough for the kill to land while it
# renders)
jobs "$tmp/seqr" 64x64 >"$tmp/jobsr.json"
jobs "$tmp/seq0" 64x64 >"$tmp/jobs0.json"
# rank $2's process of the run on DB $1, once it runs a job (its host child exists) and at
# least $3 jobs are merged; killed with SIGKILL
kill_rank() {
  local victim="" n
  for _ in $(seq 1 1200); do
    victim=""
    for p in $(pgrep -f -- "--db $1" || true); do
      [ "$(cat "/proc/$p/comm" 2>/dev/null)" = tunetrace-mpi ] || continue
      tr '\0' '\n' <"/proc/$p/environ" 2>/dev/null | grep -qx "OMPI_COMM_WORLD_RANK=$2" || continue
      pgrep -P "$p" >/dev/null && victim=$p
    done
    n=$(q "$1" "SELECT count(*) FROM merges" 2>/dev/null || echo 0)
    [ -n "$victim" ] && [ "${n:-0}" -ge "$3" ] && break
    victim=""
    sleep 0.05
  done
  [ -n "$victim" ] || fail "rank $2 of $1 not found running a job"
  kill -9 "$victim"
}
no_leftovers() {
  sleep 1
  if pgrep -f -- "$1" >/dev/null; then pgrep -af -- "$1"; fail "$2: processes of the run remain"; fi
}
whole_jobs() {
  [ "$(q "$1" "SELECT count(*) FROM samples")" = "$(q "$1" "SELECT sum(rows) FROM merges")" ] ||
    fail "$2: rows of an unfinished job in the DB"
}
DRV=("$drv" --host "$host" --scratch "$tmp")

# (a) mpirun --enable-recovery: only the dead rank's job is lost, the other rank goes on
"${MPIRUN[@]}" --enable-recovery -np 2 "${DRV[@]}" --jobs "$tmp/jobsr.json" --db "$tmp/r.db" \
  --liveness 10 >"$tmp/r1.log" 2>&1 &
mp=$!
pids+=("$mp")
kill_rank "$tmp/r.db" 1 1
rc=0; wait "$mp" || rc=$?
[ "$rc" = 0 ] || { cat "$tmp/r1.log"; fail "recovery: mpirun exit $rc (Open MPI 4.1 exits 0 under --enable-recovery)"; }
grep -q "rank 1 silent for [0-9]* s: taken as dead; its job .* is lost" "$tmp/r1.log" ||
  { cat "$tmp/r1.log"; fail "recovery: rank 0 did not report rank 1's job lost"; }
grep -q "7 of 8 jobs done, 0 failed and 1 lost with their rank" "$tmp/r1.log" ||
  { cat "$tmp/r1.log"; fail "recovery: the other jobs should all be done (7 of 8)"; }
[ "$(q "$tmp/r.db" "SELECT count(*) FROM merges")" = 7 ] || fail "recovery: expected 7 jobs merged"
whole_jobs "$tmp/r.db" recovery
no_leftovers "$tmp/r.db" recovery
rc=0; "${DRV[@]}" --jobs "$tmp/jobsr.json" --db "$tmp/r.db" --check >"$tmp/rc.log" 2>&1 || rc=$?
[ "$rc" = 1 ] && [ "$(grep -c '^todo ' "$tmp/rc.log")" = 1 ] || { cat "$tmp/rc.log"; fail "--check should exit 1 naming the one lost job"; }
"${MPIRUN[@]}" --enable-recovery -np 2 "${DRV[@]}" --jobs "$tmp/jobsr.json" --db "$tmp/r.db" \
  >"$tmp/r2.log" 2>&1 || { cat "$tmp/r2.log"; fail "recovery: rerun"; }
grep -q "8 jobs in .*, 7 already in .* 1 to run" "$tmp/r2.log" || { cat "$tmp/r2.log"; fail "recovery: the rerun should run the lost job only"; }
"${DRV[@]}" --jobs "$tmp/jobsr.json" --db "$tmp/r.db" --check >"$tmp/rc.log" 2>&1 || { cat "$tmp/rc.log"; fail "--check after the rerun"; }
check_complete "$tmp/r.db" "$tmp/seqr" "recovery rerun"

# (b) rank 0 killed (under --enable-recovery): the worker notices within --liveness, stops its
#     job and exits; the DB holds whole jobs; a rerun completes the set
"${MPIRUN[@]}" --enable-recovery -np 2 "${DRV[@]}" --jobs "$tmp/jobs0.json" --db "$tmp/z.db" \
  --liveness 5 >"$tmp/z1.log" 2>&1 &
mp=$!
pids+=("$mp")
kill_rank "$tmp/z.db" 0 1
for _ in $(seq 1 300); do kill -0 "$mp" 2>/dev/null || break; sleep 0.1; done
kill -0 "$mp" 2>/dev/null && { cat "$tmp/z1.log"; fail "rank 0 killed: the run did not end within 30 s"; }
wait "$mp" || true
grep -q "rank 1: rank 0 silent for 5 s: taken as dead; this rank stops" "$tmp/z1.log" ||
  { cat "$tmp/z1.log"; fail "rank 0 killed: rank 1 did not notice"; }
whole_jobs "$tmp/z.db" "rank 0 killed"
no_leftovers "$tmp/z.db" "rank 0 killed"
"${MPIRUN[@]}" --enable-recovery -np 2 "${DRV[@]}" --jobs "$tmp/jobs0.json" --db "$tmp/z.db" \
  >"$tmp/z2.log" 2>&1 || { cat "$tmp/z2.log"; fail "rank 0 killed: rerun"; }
check_complete "$tmp/z.db" "$tmp/seq0" "rank 0 killed, rerun"

# (c) plain mpirun: Open MPI ends the whole run; finished jobs are kept, reruns complete it
"${MPIRUN[@]}" -np 2 "${DRV[@]}" --jobs "$tmp/jobsk.json" --db "$tmp/k.db" >"$tmp/k1.log" 2>&1 &
mp=$!
pids+=("$mp")
kill_rank "$tmp/k.db" 1 3
rc=0; wait "$mp" || rc=$?
[ "$rc" != 0 ] || fail "mpirun (no recovery) should fail when a rank is killed"
grep -q "note: mpirun without --enable-recovery" "$tmp/k1.log" || fail "no note about --enable-recovery"
done1=$(q "$tmp/k.db" "SELECT count(*) FROM merges")
[ "$done1" -ge 3 ] && [ "$done1" -lt 8 ] || fail "$done1 jobs done before the kill (expected 3..7)"
whole_jobs "$tmp/k.db" "killed run"
no_leftovers "$tmp/k.db" "killed run"
"${MPIRUN[@]}" -np 2 "${DRV[@]}" --jobs "$tmp/jobsk.json" --db "$tmp/k.db" >"$tmp/k2.log" 2>&1 ||
  { cat "$tmp/k2.log"; fail "rerun after the kill"; }
grep -q "8 jobs in .*, $done1 already in" "$tmp/k2.log" || { cat "$tmp/k2.log"; fail "the rerun did not skip the $done1 jobs done"; }
check_complete "$tmp/k.db" "$tmp/seqk" "after the kill"
"${MPIRUN[@]}" -np 2 "${DRV[@]}" --jobs "$tmp/jobsk.json" --db "$tmp/k.db" >"$tmp/k3.log" 2>&1 ||
  { cat "$tmp/k3.log"; fail "third run"; }
grep -q "8 already in .* 0 to run" "$tmp/k3.log" || { cat "$tmp/k3.log"; fail "a third run should have nothing to do"; }
"$drv" --jobs "$tmp/jobsk.json" --db "$tmp/k.db" --host "$host" --list | grep -c '^done ' | grep -qx 8 ||
  fail "--list (one process, no mpirun) should show 8 jobs done"

# --- Ctrl-C (SIGINT to mpirun): every rank stops, finished jobs saved, no process left ---
# (larger images: jobs of ~0.3 s could all finish before the signal arrived, as they did in
# the sanitizer build)
jobs "$tmp/seqi" 160x160 >"$tmp/jobsi.json"
"${MPIRUN[@]}" -np 2 "$drv" --jobs "$tmp/jobsi.json" --db "$tmp/i.db" --host "$host" \
  --scratch "$tmp" >"$tmp/i.log" 2>&1 &
mp=$!
pids+=("$mp")
for _ in $(seq 1 600); do
  n=$(q "$tmp/i.db" "SELECT count(*) FROM merges" 2>/dev/null || echo 0)
  [ "${n:-0}" -ge 2 ] && break
  sleep 0.1
done
kill -INT "$mp"
rc=0; wait "$mp" || rc=$?
[ "$rc" != 0 ] || fail "an interrupted run should not exit 0"
# rank 0's summary: 0 lost, and "run again" while jobs are left. On a loaded machine the last
# jobs can finish between the signal and its handling (seen: 8 of 8 done, exit non-zero);
# then there is nothing left and no hint, which is also a clean stop.
grep -qE "jobs done, 0 failed and 0 lost with their rank in this run( \(run the same command again|\$)" "$tmp/i.log" ||
  { cat "$tmp/i.log"; fail "rank 0 did not stop cleanly"; }
[ "$(q "$tmp/i.db" "SELECT count(*) FROM samples")" = "$(q "$tmp/i.db" "SELECT sum(rows) FROM merges")" ] ||
  fail "the interrupted run left rows of an unfinished job"
sleep 1
if pgrep -f -- "$tmp/i.db" >/dev/null; then pgrep -af -- "$tmp/i.db"; fail "processes of the interrupted run remain"; fi

# --- bad job lists: refused before any work, naming the item ---
bad() {  # $1: label, $2: expected text, $3: JSON
  printf '%s\n' "$3" >"$tmp/bad.json"
  rc=0
  "${MPIRUN[@]}" -np 2 "$drv" --jobs "$tmp/bad.json" --db "$tmp/bad.db" --host "$host" \
    --scratch "$tmp" >"$tmp/bad.log" 2>&1 || rc=$?
  [ "$rc" != 0 ] || fail "$1: accepted"
  grep -qF -- "$2" "$tmp/bad.log" || { cat "$tmp/bad.log"; fail "$1: message should contain: $2"; }
  [ ! -e "$tmp/bad.db" ] && [ ! -e "$tmp/badseq" ] || fail "$1: work started (DB or folder created)"
}
ok_item='{"kind": "tune", "scene": "'"$scene"'", "camera": 1, "args": ["--plugin", "tuner_nm", "--tune", "accel_embree"]}'
bad "unknown scene" 'jobs[1].scene: ' '{"jobs": ['"$ok_item"', {"kind": "explore", "scene": "'"$tmp"'/nosuch.json", "camera": 2, "samples": 2}]}'
grep -q "nosuch.json" "$tmp/bad.log" || fail "the unknown scene's path is not named"
bad "empty range" 'jobs[1].range: expected frames "A:B" with A <= B' '{"jobs": ['"$ok_item"', {"kind": "frames", "scene": "'"$scene"'", "range": "5:3", "out_dir": "'"$tmp"'/badseq"}]}'
bad "post-filter" 'jobs[0].args: --post' '{"jobs": [{"kind": "frames", "scene": "'"$scene"'", "range": "0:3", "out_dir": "'"$tmp"'/badseq", "args": ["--post", "post_taa"]}]}'
# an option the driver sets, written --opt=value or by its short name (the host's option table)
bad "--opt=value" 'jobs[0].args: --sequence ("--sequence=0:9") is set by tunetrace-mpi for a tune job' '{"jobs": [{"kind": "tune", "scene": "'"$scene"'", "camera": 1, "args": ["--sequence=0:9"]}]}'
bad "short name" 'jobs[0].args: --out ("-o") is set by tunetrace-mpi' '{"jobs": [{"kind": "explore", "scene": "'"$scene"'", "camera": 1, "samples": 2, "args": ["-q", "-o", "x.exr"]}]}'
bad "unknown key" 'jobs[0].cam: unknown key' '{"jobs": [{"kind": "tune", "scene": "'"$scene"'", "cam": 1}]}'
bad "camera range" 'jobs[0].cameras: [1]: expected an integer in 0..99' '{"jobs": [{"kind": "tune", "scene": "'"$scene"'", "cameras": [1, 100]}]}'
bad "repeated job" 'jobs[1]: repeats a job of jobs[0]' '{"jobs": ['"$ok_item"', '"$ok_item"']}'
bad "not JSON" 'not valid JSON (line 1' '{"jobs": [}'
echo "mpi_driver: ok"
