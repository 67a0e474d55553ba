#!/usr/bin/env bash
# Builds tunetrace (installing Debian packages if missing) and runs the whole test suite:
# unit, render and sdk suites (the bench suite only prints figures: run it with
# `meson test -C build --suite bench`). Ends with one line "N passed, N failed, N skipped".
set -uo pipefail
cd "$(dirname "$0")/.."
bash tools/bootstrap.sh || exit 1
source tools/test_common.sh
tt_link_shared

meson test -C build --suite unit --suite render --suite sdk --print-errorlogs \
  --num-processes "$(nproc)" 2>&1 | tee build/test-output.txt
tt_summarize build/test-output.txt tests "${PIPESTATUS[0]}"
