# Sourced by tools/test.sh and tools/test_sanitized.sh: what both do around `meson test`.

# The real scenes the render suite reads lie in ../shared beside the checkout
# (../shared/scenes/README.md). A clone made elsewhere (a clean clone in /tmp, as CI makes)
# gets ../shared linked to the one beside the repository it was cloned from, so the suite runs
# the same tests there; without either, the tests that need the scenes skip (and fail in CI).
tt_link_shared() {
  local parent origin
  parent=$(cd .. && pwd)
  [ -d "$parent/shared/scenes" ] && return 0
  origin=$(git remote get-url origin 2>/dev/null) || origin=
  case $origin in
    file://*) origin=${origin#file://} ;;
    /*) ;;
    *) origin= ;;
  esac
  if [ -n "$origin" ] && [ -d "$origin/../shared/scenes" ] && [ ! -e "$parent/shared" ]; then
    local target
    target=$(cd "$origin/../shared" && pwd)
    ln -s "$target" "$parent/shared" && echo "test data: linked $parent/shared -> $target"
  else
    echo "test data: warning: $parent/shared/scenes not found; the tests that read it will skip" >&2
  fi
}

# The summary line of a `meson test` output file and the exit status: with CI set, a skipped
# test fails the run (bootstrap installs everything a test needs, so a skip there hides a
# missing install step), naming the skipped tests.
#   tt_summarize LOG LABEL MESON_STATUS
tt_summarize() {
  local log=$1 label=$2 rc=$3 ok fail skip timeout
  count() { awk -v k="$1" '$1 == k":" {print $2}' "$log" | tail -n 1; }
  ok=$(count Ok); fail=$(count Fail); skip=$(count Skipped); timeout=$(count Timeout)
  ok=${ok:-0}; fail=${fail:-0}; skip=${skip:-0}; timeout=${timeout:-0}
  echo
  echo "${label}: ${ok} passed, $((fail + timeout)) failed, ${skip} skipped"
  if [ -n "${CI:-}" ] && [ "$skip" -gt 0 ]; then
    echo "${label}: CI is set and these tests skipped (each must run in CI):" >&2
    grep -E '^ *[0-9]+/[0-9]+ .* SKIP ' "$log" >&2 || true
    [ "$rc" -ne 0 ] || rc=1
  fi
  return "$rc"
}
