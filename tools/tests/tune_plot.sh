#!/usr/bin/env bash
# tools/tuning/convergence.py on two real tuning runs (render and build+render objectives):
# the summary reports every iteration and a best no worse than the default, the PNG is a
# real PNG, and reading the same runs back from the tuning database gives the same runs.
set -euo pipefail
PY=/usr/bin/python3
if ! "$PY" -c 'import matplotlib' 2>/dev/null; then
  echo "SKIP: python3-matplotlib is not installed (tools/bootstrap.sh installs it)"
  exit 77
fi
HOST="$TT_BUILD_ROOT/host/host"
TOOL=(-m tools.tuning.convergence)
SCENE="$TT_SOURCE_ROOT/scenes/cornell-box/scene.json"
dir=$(mktemp -d /tmp/tt_tune_plotXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }

for obj in render build+render; do
  "$HOST" --quiet --plugin tuner_nm --tune accel_embree --objective "$obj" --iterations 6 \
    --res 16x16 --spp 1 --threads 2 --db "$dir/t.db" --out "$dir/t.exr" \
    --stats "$dir/$obj.json" "$SCENE"
done

summary=$("$PY" "${TOOL[@]}" "$dir/render.json" "$dir/build+render.json" --summary -o "$dir/c.png")
echo "$summary"
check '[ "$(grep -c "iterations 6, cached 0" <<<"$summary")" = 2 ]'
check 'grep -q "^accel_embree / render:" <<<"$summary"'
check 'grep -q "^accel_embree / build+render:" <<<"$summary"'
# gain = 1 - best/default is never negative: the default competes for best
check '! grep -q "gain -" <<<"$summary"'
check '[ "$(head -c 8 "$dir/c.png" | od -An -tx1 | tr -d " \n")" = "89504e470d0a1a0a" ]'
check '[ "$(stat -c %s "$dir/c.png")" -gt 10000 ]'

dbsum=$("$PY" "${TOOL[@]}" --db "$dir/t.db" --last 2 --summary -o "$dir/d.png")
echo "$dbsum"
check '[ "$(grep -c "iterations 6" <<<"$dbsum")" = 2 ]'
check '[ -s "$dir/d.png" ]'
# bad input is refused with a message, not a traceback
check '! "$PY" "${TOOL[@]}" "$SCENE" --summary 2>"$dir/err"'
check 'grep -q "no \"tuning\" object" "$dir/err"'

[ "$fail" = 0 ] && echo "tune_plot: ok"
exit "$fail"
