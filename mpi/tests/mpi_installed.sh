#!/usr/bin/env bash
# The installed tunetrace-mpi (issue 18): `meson install --destdir` puts it in PREFIX/bin beside
# the installed host `tunetrace`, with its docs in PREFIX/share/doc/tunetrace; run from the
# staging copy in a clean environment (no LD_LIBRARY_PATH, no TT_PLUGIN_PATH) under mpirun
# -np 2 with no --host, it runs the installed `tunetrace` beside it (never the build tree's
# host), which loads the installed plugins: every job of a small list merged once, with the
# rows of the same jobs run by the build tree's driver.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
MESON=${MESON:-meson}
PY=/usr/bin/python3
MPIRUN=("${MPIRUN:-mpirun}" --allow-run-as-root --oversubscribe)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_mpi_installed.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
stage=$tmp/stage
"$MESON" install -C "$TT_BUILD_ROOT" --destdir "$stage" --no-rebuild >"$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log" >&2; fail "meson install --destdir failed"; }
drv=$(find "$stage" -path '*/bin/tunetrace-mpi' -type f | head -n 1)
[ -n "$drv" ] && [ -x "$drv" ] || fail "tunetrace-mpi is not installed under $stage"
bin=$(dirname "$drv")
[ -x "$bin/tunetrace" ] || fail "no installed tunetrace beside $drv"
doc=$(dirname "$bin")/share/doc/tunetrace
for f in tunetrace-mpi.md tunetrace-mpi-100-nodes.md; do
  [ -s "$doc/$f" ] || fail "$doc/$f not installed"
done
# the installed program's help names the installed host beside it
env -u LD_LIBRARY_PATH -u TT_PLUGIN_PATH "$drv" --help 2>"$tmp/help.txt" || true
grep -qF -- "--host PATH   the host program the jobs run (default $bin/tunetrace)" "$tmp/help.txt" ||
  { cat "$tmp/help.txt"; fail "the installed tunetrace-mpi should default to $bin/tunetrace"; }
scene="$TT_SOURCE_ROOT/scenes/cornell-box/path.json"
cat >"$tmp/jobs.json" <<JSON
{"host_args": ["--res", "16x16", "--threads", "1", "--spp", "1", "--clock", "cpu"],
 "jobs": [
  {"kind": "explore", "scene": "$scene", "cameras": [10, 20, 30], "samples": 3, "seed": 7,
   "args": ["--tune", "accel_embree"]}
 ]}
JSON
env -u LD_LIBRARY_PATH -u TT_PLUGIN_PATH "${MPIRUN[@]}" -np 2 "$drv" --jobs "$tmp/jobs.json" \
  --db "$tmp/inst.db" --scratch "$tmp" >"$tmp/inst.log" 2>&1 || { cat "$tmp/inst.log"; fail "installed tunetrace-mpi under mpirun -np 2"; }
"$drv" --jobs "$tmp/jobs.json" --db "$tmp/inst.db" --check >/dev/null 2>&1 || fail "--check: jobs todo after the installed run"
"${MPIRUN[@]}" -np 2 "$TT_BUILD_ROOT/mpi/tunetrace-mpi" --jobs "$tmp/jobs.json" --db "$tmp/tree.db" \
  --scratch "$tmp" >"$tmp/tree.log" 2>&1 || { cat "$tmp/tree.log"; fail "build tree's tunetrace-mpi"; }
# the jobs' rows equal (all but timings and ids)
rows() {
  "$PY" - "$1" <<'PYEOF'
import json, sqlite3, sys
con = sqlite3.connect(sys.argv[1])
for r in sorted(json.dumps(r) for r in con.execute(
        "SELECT scene_id, camera, context, plugin, plugin_version, config, objective, status, mode,"
        " iteration FROM samples")):
    print(r)
PYEOF
}
rows "$tmp/inst.db" >"$tmp/inst.txt"
rows "$tmp/tree.db" >"$tmp/tree.txt"
[ "$(wc -l <"$tmp/inst.txt")" = 12 ] || fail "installed run: $(wc -l <"$tmp/inst.txt") rows, expected 12 (3 jobs x (default + 3 samples))"
cmp -s "$tmp/inst.txt" "$tmp/tree.txt" || { diff "$tmp/inst.txt" "$tmp/tree.txt" | head; fail "installed and build-tree rows differ"; }
echo "mpi_installed: ok ($drv)"
