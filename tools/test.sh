#!/usr/bin/env bash
# Builds tunetrace (installing Debian packages if missing) and runs the whole test suite:
# unit, render and sdk suites (the bench suite only prints figures: run it with
# `meson test -C build --suite bench`). Ends with one line "N passed, N failed, N skipped".
set -uo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh || exit 1

meson test -C build --suite unit --suite render --suite sdk --print-errorlogs \
  --num-processes "$(nproc)" 2>&1 | tee build/test-output.txt
rc=${PIPESTATUS[0]}

count() { awk -v k="$1" '$1 == k":" {print $2}' build/test-output.txt | tail -n 1; }
ok=$(count Ok); fail=$(count Fail); skip=$(count Skipped); timeout=$(count Timeout)
ok=${ok:-0}; fail=${fail:-0}; skip=${skip:-0}; timeout=${timeout:-0}
echo
echo "tests: ${ok} passed, $((fail + timeout)) failed, ${skip} skipped"
exit "$rc"
