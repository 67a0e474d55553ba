#!/usr/bin/env bash
# tools/hybrid/baseline.py --mpi 2 (issue 18): the hybrid baseline's jobs on 2 MPI ranks, one
# merged DB. Stopped after 2 jobs (--max-jobs), run again: it does the rest; the finished jobs
# are hybrid_jobs rows like those of a single-process run (trajectory, stats), every sample
# row names its rank; a single-process run of the same settings then has nothing to do, and
# evaluate.py's input (hybrid_jobs) is complete.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
PY=/usr/bin/python3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_mpi_baseline.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
B=("$PY" -m tools.hybrid.baseline --host "$TT_BUILD_ROOT/host/host"
   --mpi-driver "$TT_BUILD_ROOT/mpi/tunetrace-mpi" --mpirun "${MPIRUN:-mpirun} --oversubscribe"
   --db "$tmp/b.db" --work "$tmp/w" --cameras 3 --iterations 3 --res 16x16
   --scene "box=$TT_SOURCE_ROOT/scenes/cornell-box/path.json")
q() { "$PY" -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute(sys.argv[2]).fetchone()[0])' "$@"; }
"${B[@]}" --mpi 2 --max-jobs 2 >"$tmp/b1.log" 2>&1 || { cat "$tmp/b1.log"; fail "baseline --mpi 2 --max-jobs 2"; }
[ "$(q "$tmp/b.db" "SELECT count(*) FROM hybrid_jobs")" = 2 ] || { cat "$tmp/b1.log"; fail "2 jobs should be recorded"; }
"${B[@]}" --mpi 2 >"$tmp/b2.log" 2>&1 || { cat "$tmp/b2.log"; fail "baseline --mpi 2 (resumed)"; }
grep -q "6 jobs, 2 already in" "$tmp/b2.log" || { cat "$tmp/b2.log"; fail "the rerun did not skip the 2 jobs done"; }
n=$(q "$tmp/b.db" "SELECT count(*) FROM hybrid_jobs WHERE iterations = 3 AND resolution = '16x16' AND history LIKE '[%' AND wall_s > 0 AND cpu_s > 0")
[ "$n" = 6 ] || fail "hybrid_jobs has $n complete rows, expected 6"
[ "$(q "$tmp/b.db" "SELECT count(*) FROM merges")" = 6 ] || fail "merges"
[ "$(q "$tmp/b.db" "SELECT count(*) FROM samples")" = "$(q "$tmp/b.db" "SELECT sum(rows) FROM merges")" ] || fail "rows outside jobs"
[ "$(q "$tmp/b.db" "SELECT count(*) FROM samples WHERE rank IS NULL")" = 0 ] || fail "rows without a rank"
n=$(q "$tmp/b.db" "SELECT count(*) FROM samples WHERE camera NOT LIKE '%\"path_index\":%' OR context NOT LIKE '%\"clock\":\"cpu\"%'")
[ "$n" = 0 ] || fail "$n rows without path_index or clock"
# every job's history has its 3 iterations, like a single-process job
"$PY" - "$tmp/b.db" <<'PYEOF' || fail "histories"
import json, sqlite3, sys
for job, hist in sqlite3.connect(sys.argv[1]).execute("SELECT job, history FROM hybrid_jobs"):
    its = sorted(h["iteration"] for h in json.loads(hist))
    assert its == [0, 1, 2], (job, its)
PYEOF
"${B[@]}" >"$tmp/b3.log" 2>&1 || { cat "$tmp/b3.log"; fail "single-process run after MPI"; }
grep -q "6 jobs, 6 already in .* 0 to run" "$tmp/b3.log" || { cat "$tmp/b3.log"; fail "a single-process run should find every MPI job done"; }
echo "mpi_baseline: ok"
