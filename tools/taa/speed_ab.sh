#!/bin/bash
# post_taa speed of two builds side by side: runs taa_bench binaries (e.g. main's and this
# branch's, each copied with its libtunetrace) alternately, N runs of R interleaved rounds
# each, at nice -n -5 (root), and prints per binary and variant the medians of the per-run
# medians of wall and CPU ms per 640x480 frame and the CPU split, with the load average.
#   speed_ab.sh BENCH_A BENCH_B [...]        environment: T (threads, 2), N (runs, 4),
#   R (rounds, 7), W (TT_BENCH_WEIGHTS, default: the shipped c12 and c6), LD_LIBRARY_PATH
# e.g. cp build/plugins/post_taa/tests/taa_bench /tmp/ab/new (and main's as /tmp/ab/main,
# build/core/libtunetrace.so.1 beside them), then LD_LIBRARY_PATH=/tmp/ab speed_ab.sh
# /tmp/ab/main /tmp/ab/new
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: speed_ab.sh BENCH_A BENCH_B [...]" >&2; exit 2; }
for b in "$@"; do [ -x "$b" ] || { echo "speed_ab.sh: $b: not an executable" >&2; exit 2; }; done
root=$(cd "$(dirname "$0")/../.." && pwd)
T=${T:-2} N=${N:-4} R=${R:-7}
W=${W:-c12=$root/plugins/post_taa/post_taa_c12.ttw,c6=$root/plugins/post_taa/post_taa_c6.ttw}
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for r in $(seq "$N"); do
  for b in "$@"; do
    echo "load $(cut -d' ' -f1 /proc/loadavg)" >> "$out"
    nice -n -5 env TT_BENCH_WEIGHTS="$W" TT_BENCH_THREADS="$T" TT_BENCH_QUICK=1 \
      TT_BENCH_ROUNDS="$R" TT_SOURCE_ROOT="$root" "$b" | grep '^BENCH' | sed "s|^|$b |" >> "$out"
  done
  echo "speed_ab.sh: run $r/$N done" >&2
done
/usr/bin/python3 - "$out" <<'PY'
import collections, statistics as st, sys
d = collections.defaultdict(list); loads = []
for l in open(sys.argv[1]):
    f = l.split()
    if f[0] == "load":
        loads.append(float(f[1])); continue
    d[(f[2], f[0])].append([float(x) for x in f[5:]])
print("variant  binary  runs  wall ms [range]  CPU ms  reprojection  network  mix (CPU ms)")
for (var, b), rows in sorted(d.items()):
    c = list(zip(*rows))
    med = lambda i: st.median(c[i])
    print(f"{var:6s} {b} {len(rows)}  {med(0):6.1f} [{min(c[0]):.1f}-{max(c[0]):.1f}]  {med(1):6.1f}"
          f"  {med(3):5.1f}  {med(4):6.1f}  {med(5):5.1f}")
print(f"load average {min(loads):.1f}-{max(loads):.1f} (2 cores)")
PY
