#!/usr/bin/env bash
# tools/test_common.sh's summary: a skipped test fails the run when CI is set (bootstrap
# installs everything a test needs), passes otherwise; failures keep their status.
set -uo pipefail
: "${TT_SOURCE_ROOT:?}"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_skip_policy.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
cat >"$tmp/skip.txt" <<'LOG'
1/2 tunetrace:unit / a              OK               0.10s
2/2 tunetrace:render / b            SKIP             0.01s   exit status 77

Ok:                 1
Fail:               0
Skipped:            1
Timeout:            0
LOG
sed 's/^Skipped: .*/Skipped:            0/; /SKIP/d' "$tmp/skip.txt" >"$tmp/clean.txt"
summ() { (unset CI; [ -n "$1" ] && export CI=$1; source "$TT_SOURCE_ROOT/tools/test_common.sh"; tt_summarize "$2" tests "$3") >"$tmp/out.txt" 2>&1; }
summ "" "$tmp/skip.txt" 0 || fail "a skip outside CI failed the run"
grep -q "tests: 1 passed, 0 failed, 1 skipped" "$tmp/out.txt" || fail "summary line: $(cat "$tmp/out.txt")"
summ 1 "$tmp/skip.txt" 0 && fail "a skip with CI set passed the run"
grep -q "render / b .*SKIP" "$tmp/out.txt" || fail "the skipped test is not named: $(cat "$tmp/out.txt")"
summ 1 "$tmp/clean.txt" 0 || fail "a clean run failed with CI set"
summ 1 "$tmp/clean.txt" 3; [ $? -eq 3 ] || fail "meson's failure status was not kept"
echo "ok: skips fail only with CI set"
