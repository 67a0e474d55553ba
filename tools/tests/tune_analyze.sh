#!/usr/bin/env bash
# tools/tuning/analyze.py on a small random exploration of the Cornell box (host --explore 12):
# every subcommand writes a real PNG, the correlation table has one row per parameter and
# time with r and p columns for each, the diagonal is 1, and bad input is refused with a
# message. Exit 77 (skip) when python3-matplotlib, -numpy or -scipy is missing.
set -euo pipefail
PY=/usr/bin/python3
if ! "$PY" -c 'import matplotlib, numpy, scipy' 2>/dev/null; then
  echo "SKIP: python3-matplotlib/numpy/scipy not installed (tools/bootstrap.sh installs them)"
  exit 77
fi
HOST="$TT_BUILD_ROOT/host/host"
TOOL=(-m tools.tuning.analyze)
SCENE="$TT_SOURCE_ROOT/scenes/cornell-box/scene.json"
dir=$(mktemp -d /tmp/tt_tune_analyzeXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }
is_png() { [ "$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] && [ "$(stat -c %s "$1")" -gt 5000 ]; }

"$HOST" --quiet --explore 12 --objective build+render --set accel_embree.backend=custom \
  --res 24x24 --spp 1 --threads 2 \
  --db "$dir/e.db" --out "$dir/e.exr" --stats "$dir/e.json" "$SCENE"
for mode in render build+render; do
  "$HOST" --quiet --plugin tuner_random --tune accel_embree --objective "$mode" --iterations 6 \
    --verify 3 --res 24x24 --spp 1 --threads 2 --db "$dir/t.db" --out "$dir/t.exr" \
    --stats "$dir/$mode.json" "$SCENE"
done

"$PY" "${TOOL[@]}" correlation --db "$dir/e.db" -o "$dir/corr.png" --table "$dir/corr.csv" | tee "$dir/corr.txt"
"$PY" "${TOOL[@]}" correlation --db "$dir/e.db" --method pearson --table "$dir/pearson.csv" >/dev/null
"$PY" "${TOOL[@]}" leafsize --db "$dir/e.db" -o "$dir/leaf.png"
"$PY" "${TOOL[@]}" costs --db "$dir/e.db" --metric total -o "$dir/costs.png"
"$PY" "${TOOL[@]}" blocksize --db "$dir/e.db" -o "$dir/block.png"
"$PY" "${TOOL[@]}" convergence "$dir/render.json" "$dir/build+render.json" -o "$dir/conv.png" | tee "$dir/conv.txt"
# convergence from the database too (#17 defect 17): one line per run, each labelled with
# what it was tuned for
"$PY" "${TOOL[@]}" convergence --db "$dir/t.db" -o "$dir/convdb.png" | tee "$dir/convdb.txt"
for png in corr leaf costs block conv convdb; do check "is_png '$dir/$png.png'"; done
for f in conv convdb; do
  check "grep -q 'tuner_random, tuned for render' '$dir/$f.txt'"
  check "grep -q 'tuner_random, tuned for build+render' '$dir/$f.txt'"
  check "[ \"\$(grep -c 'tuned for' '$dir/$f.txt')\" = 2 ]"
done
check '! "$PY" "${TOOL[@]}" convergence --db "$dir/t.db" "$dir/render.json" -o "$dir/x.png" 2>"$dir/err"'
check 'grep -q "not both" "$dir/err"'
check '! "$PY" "${TOOL[@]}" convergence --db "$dir/e.db" --mode tune -o "$dir/x.png" 2>"$dir/err"'
check 'grep -q "no rows match" "$dir/err"'
check '"$PY" "${TOOL[@]}" --help | grep -q "Input, for every subcommand"'


# what the charts show (the figures as analyze.run returns them): leafsize's and costs' red
# markers have legend entries; costs' log ticks read as plain numbers (no "6x10^-1");
# blocksize draws points at the sampled sahBlockSize values only (no steps between them),
# ticked at those values; convergence's default lines are what tuning measured (the stats'
# default_cost, not the verify median) and each run has a best-so-far line (the running
# minimum of convergence.best_so_far)
check '"$PY" -m tools.tests.tune_analyze_charts "$dir"'

# the table: the accel's parameters + render_ms, build_ms, total_ms; r and p for each
nparams=$("$HOST" --describe accel_embree | "$PY" -c 'import json,sys; print(len(json.load(sys.stdin)["parameters"]))')
nvars=$((nparams + 3))
check '[ "$nparams" -ge 11 ]'
check '[ "$(wc -l <"$dir/corr.csv")" = $((nvars + 1)) ]'
check '[ "$(head -1 "$dir/corr.csv" | tr , "\n" | wc -l)" = $((2 * nvars + 1)) ]'
check '[ "$(cut -d, -f1 "$dir/corr.csv" | tail -n 3 | tr "\n" " ")" = "render_ms build_ms total_ms " ]'
# r(x, x) = 1 for a variable that varies, |r| <= 1, 0 <= p <= 1 everywhere else (nan: constant)
check "\"$PY\" - \"$dir/corr.csv\" \"$dir/pearson.csv\" <<'PYEOF'
import csv, math, sys
for path in sys.argv[1:]:
    rows = list(csv.reader(open(path)))
    names, n = rows[0][1:], len(rows) - 1
    assert len(names) == 2 * n, (len(names), n)
    for i, row in enumerate(rows[1:]):
        r = [float(v) for v in row[1:n + 1]]
        p = [float(v) for v in row[n + 1:]]
        assert row[0] == names[i], (row[0], names[i])
        assert math.isnan(r[i]) or abs(r[i] - 1) < 1e-9, (row[0], r[i])
        assert all(math.isnan(v) or -1 - 1e-9 <= v <= 1 + 1e-9 for v in r)
        assert all(math.isnan(v) or 0 <= v <= 1 + 1e-9 for v in p)
    # symmetric
    for i in range(n):
        for j in range(n):
            a, b = float(rows[i + 1][j + 1]), float(rows[j + 1][i + 1])
            assert (math.isnan(a) and math.isnan(b)) or abs(a - b) < 1e-9
    # the times vary across 13 configurations: total correlates with itself and is finite
    t = n - 1
    assert not math.isnan(float(rows[t + 1][t + 1]))
PYEOF"
check 'grep -q "over 13 rows" "$dir/corr.txt"'
check 'grep -q "verify render ratio" "$dir/conv.txt"'

# bad input: a message, not a traceback
check '! "$PY" "${TOOL[@]}" leafsize --db "$dir/nope.db" -o "$dir/x.png" 2>"$dir/err"'
check 'grep -q "no such database" "$dir/err"'
check '! "$PY" "${TOOL[@]}" blocksize --db "$dir/e.db" --plugin integrator_pt -o "$dir/x.png" 2>"$dir/err"'
check 'grep -q "no rows match" "$dir/err"'
check '! grep -q Traceback "$dir/err"'

[ "$fail" = 0 ] && echo "tune_analyze: ok"
exit "$fail"
