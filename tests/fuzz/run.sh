#!/usr/bin/env bash
# Runs libFuzzer harnesses of tests/fuzz on their committed corpora and reports, per harness,
# the executions and what was found (crashes, leaks, timeouts, out-of-memory), one line each:
#   tests/fuzz/run.sh --time SECONDS HARNESS...   smoke run (the 'fuzz' meson suite: 30 s)
#   tests/fuzz/run.sh --runs N HARNESS...         long run: N executions each
# Options: --jobs J (harnesses run side by side, default 1), --work DIR (keep the grown
# corpora, logs and artifacts there; default a temporary folder, removed unless something
# was found). HARNESS is a built executable (BUILD/tests/fuzz/fuzz_NAME). Exit 0 only if
# nothing was found. Smoke runs use seed 1, long runs a random seed; TT_FUZZ_SEED=N sets it.
# Long runs belong under `nice -n 19` in the background.
set -uo pipefail
shopt -s extglob
here=$(cd "$(dirname "$0")" && pwd)
mode="" limit="" jobs=1 work="" keep=0
harnesses=()
while [ $# -gt 0 ]; do
  case "$1" in
    --time) mode=time limit=$2; shift 2 ;;
    --runs) mode=runs limit=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --work) work=$2 keep=1; shift 2 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    *) # a glob over the build folder also matches meson's NAME.p object folders: skip them
       if [ -f "$1" ] && [ -x "$1" ]; then harnesses+=("$1"); fi; shift ;;
  esac
done
if [ -z "$mode" ] || [ ${#harnesses[@]} -eq 0 ]; then
  echo "usage: $0 (--time SECONDS | --runs N) [--jobs J] [--work DIR] HARNESS..." >&2
  exit 2
fi
[ -n "$work" ] || work=$(mktemp -d "${TMPDIR:-/tmp}/tt_fuzz_run.XXXXXX")
mkdir -p "$work"

# Sanitizer settings (leaks on, UBSan stops at its first report, third-party suppressions)
source "$here/../support/sanitizers/env.sh"

run_one() {
  local exe=$1 name corpus dir log rc
  name=$(basename "$exe")
  corpus="$here/corpus/${name#fuzz_}"
  dir="$work/$name"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  rm -f "$dir/summary.txt"
  # scratch files of the harnesses that read paths (and fsync what they save): on tmpfs when
  # there is one, or a disk's fsync paces the run
  local scratch
  if [ -d /dev/shm ] && [ -w /dev/shm ]; then
    scratch=$(mktemp -d /dev/shm/tt_fuzz_run.XXXXXX)
  else
    scratch="$dir/tmp"
    mkdir -p "$scratch"
  fi
  log="$dir/log.txt"
  local args=(-timeout=25 -rss_limit_mb=3072 -malloc_limit_mb=3072 -close_fd_mask=2
              -print_final_stats=1 -artifact_prefix="$dir/artifacts/")
  [ -f "$here/$name.dict" ] && args+=(-dict="$here/$name.dict")
  # the smoke run (the suite, CI) starts from a fixed seed, so that a CI result can be
  # reproduced and a landing is not failed by whatever a random walk met that day; long runs
  # take a random one (libFuzzer prints it as "INFO: Seed:"); TT_FUZZ_SEED overrides both
  if [ -n "${TT_FUZZ_SEED:-}" ]; then args+=(-seed="$TT_FUZZ_SEED")
  elif [ "$mode" = time ]; then args+=(-seed=1); fi
  if [ "$mode" = time ]; then args+=(-max_total_time="$limit"); else args+=(-runs="$limit"); fi
  # the grown corpus goes to the work folder; the committed one is only read
  # fuzz_mesh reaches assimp's parsers, which leak on corrupt files they reject: their
  # suppression is added for this harness only (support/sanitizers/lsan-assimp.supp says why)
  if [ "$name" = fuzz_mesh ]; then
    cat "$here/../support/sanitizers/lsan.supp" "$here/../support/sanitizers/lsan-assimp.supp" \
      > "$scratch/lsan.supp"
    export LSAN_OPTIONS="${LSAN_OPTIONS/suppressions=*([^:])/suppressions=$scratch/lsan.supp}"
  fi
  local t0=$SECONDS
  TT_FUZZ_TMP="$scratch" "$exe" "${args[@]}" "$dir/corpus" "$corpus" >"$log" 2>&1
  rc=$?
  local execs crashes leaks timeouts ooms
  execs=$(awk '/stat::number_of_executed_units:/ {print $2}' "$log" | tail -n 1)
  crashes=$(find "$dir/artifacts" -name 'crash-*' | wc -l)
  leaks=$(find "$dir/artifacts" -name 'leak-*' | wc -l)
  timeouts=$(find "$dir/artifacts" -name 'timeout-*' | wc -l)
  ooms=$(find "$dir/artifacts" -name 'oom-*' | wc -l)
  local secs=$((SECONDS - t0))
  printf '%-18s %12s executions %6s s  crashes %s  leaks %s  timeouts %s  oom %s  exit %s\n' \
    "$name" "${execs:-?}" "${secs:-?}" "$crashes" "$leaks" "$timeouts" "$ooms" "$rc" \
    | tee "$dir/summary.txt"
  # 72: libFuzzer's exit after SIGINT/SIGTERM (a long run stopped early): its counts stand
  if [ "$rc" -eq 72 ] && [ $((crashes + leaks + timeouts + ooms)) -eq 0 ]; then
    echo "$name: stopped early (signal); the figures above are what it ran"
    rm -rf "$scratch"
    return 0
  fi
  if [ "$rc" -ne 0 ] || [ $((crashes + leaks + timeouts + ooms)) -ne 0 ]; then
    echo "--- $name: log tail ($log) ---"
    tail -n 60 "$log"
    rm -rf "$scratch"
    return 1
  fi
  rm -rf "$scratch"
  return 0
}

for exe in "${harnesses[@]}"; do
  run_one "$exe" &
  while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n || true; done
done
wait
# the summaries of this invocation's harnesses (a --work folder may hold older ones)
summaries=()
for exe in "${harnesses[@]}"; do
  f="$work/$(basename "$exe")/summary.txt"
  [ -f "$f" ] && summaries+=("$f")
done
ran=${#summaries[@]}
found=0 bad=0
if [ "$ran" -gt 0 ]; then
  found=$(cat "${summaries[@]}" | awk '{s += $7 + $9 + $11 + $13} END {print s + 0}')
  bad=$(cat "${summaries[@]}" | awk '$15 != 0 && $15 != 72' | wc -l)
fi
bad=$((bad + ${#harnesses[@]} - ran))
echo "fuzz: ${#harnesses[@]} harness(es), $found finding(s), $bad failed run(s); work folder $work"
if [ "$found" -eq 0 ] && [ "$bad" -eq 0 ]; then
  [ "$keep" -eq 1 ] || rm -rf "$work"
  exit 0
fi
exit 1
