#!/usr/bin/env bash
# The README's hybrid warm start, run as written: the commands are read from README.md (the
# line restoring the committed baseline and the --hybrid --warm-start line), with the
# checkout's paths for tools/, scenes/ and build/ and, for the hybrid run only, three
# states of the path (--camera-index 0:2) so the test takes seconds. The restore must bring
# every job of the dump, and the model must learn rows from it (a warm start whose settings
# do not match the baseline's learns 0 rows: the README's options are the ones that match).
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
README="$TT_SOURCE_ROOT/README.md"
restore=$(grep -m1 -E '^/usr/bin/python3 -m tools\.hybrid\.baseline .*--restore ' "$README") ||
  fail "README.md has no 'python3 -m tools.hybrid.baseline ... --restore' line"
hybrid=$(grep -m1 -E '^build/host/host --hybrid .*--warm-start baseline\.db' "$README") ||
  fail "README.md has no 'build/host/host --hybrid ... --warm-start baseline.db' line"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_readme_hybrid.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
# the hybrid run records into the user's database: keep it in the test's folder
export HOME="$tmp/home" XDG_DATA_HOME="$tmp/home/.local/share"
mkdir -p "$HOME"
cd "$tmp"
paths() {
  local c=$1
  # relative paths only where a word starts (the root itself may contain "scenes/")
  local d=$'\001'
  c=$(printf '%s' "$c" | sed -E "s${d}(^|[[:space:]=])(tools/hybrid/data/|scenes/)${d}\1$TT_SOURCE_ROOT/\2${d}g")
  c=${c/#build\/host\/host/$TT_BUILD_ROOT/host/host}
  printf '%s' "$c"
}
# python3 -m tools... runs from the repository root's package (PYTHONPATH), the host as built
(export PYTHONPATH="$TT_SOURCE_ROOT${PYTHONPATH:+:$PYTHONPATH}" TT_HOST="$TT_BUILD_ROOT/host/host"
 eval "$(paths "$restore")") >restore.log 2>&1 || { cat restore.log; fail "the README's restore: $restore"; }
grep -q "restored from .*: 112 jobs, 4592 samples" restore.log ||
  { cat restore.log; fail "the restore did not bring the dump's 112 jobs and 4592 samples"; }
eval "$(paths "$hybrid") --camera-index 0:2 --stats s.json" >hybrid.log 2>&1 ||
  { cat hybrid.log; fail "the README's hybrid command: $hybrid"; }
learnt=$(sed -n 's/.*predictor_rbf learnt \([0-9]*\) of the [0-9]* rows.*/\1/p' hybrid.log | head -1)
[ -n "$learnt" ] || { cat hybrid.log; fail "no 'learnt N of the M rows' line"; }
[ "$learnt" -gt 0 ] || { cat hybrid.log; fail "the README's warm start learnt 0 rows"; }
/usr/bin/python3 - s.json <<'PYEOF' || fail "hybrid stats"
import json, math, sys
h = json.load(open(sys.argv[1]))["hybrid"]
assert h["states_done"] == 3, h["states_done"]
assert h["explored"] + h["exploited"] == 3, h
assert math.isfinite(h["sum_cost"]) and h["sum_cost"] > 0, h["sum_cost"]
PYEOF
echo "ok: README's baseline restore (112 jobs) and hybrid warm start (learnt $learnt rows) run as written"
