#!/usr/bin/env bash
# The committed baseline (tools/hybrid/data/baseline.sql.xz) restores on a checkout whose
# ../shared lies elsewhere (scene ids count textures by content, not by path): two of its
# scenes, veach-ajar (textured) and killeroos, copied to a new folder, restore with every row;
# a texture swapped in the copy is refused, naming the part that changed (textures), and
# --remap-scenes keeps the rows under the new id with a warning.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
shared="$TT_SOURCE_ROOT/../shared/scenes"
[ -d "$shared/veach-ajar" ] || { echo "SKIP: $shared/veach-ajar not found"; exit 77; }
PY=/usr/bin/python3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_hybrid_restore.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
# another checkout: repo/scenes/NAME/scene.json reaching repo/../shared/scenes/NAME
for s in veach-ajar killeroos; do
  mkdir -p "$tmp/repo/scenes/$s" "$tmp/shared/scenes"
  cp "$TT_SOURCE_ROOT/scenes/$s/scene.json" "$tmp/repo/scenes/$s/"
  cp -r "$shared/$s" "$tmp/shared/scenes/"
done
chmod -R u+w "$tmp/shared"
B=("$PY" -m tools.hybrid.baseline --host "$TT_BUILD_ROOT/host/host"
   --work "$tmp/w" --restore "$TT_SOURCE_ROOT/tools/hybrid/data/baseline.sql.xz"
   --scene "veach-ajar=$tmp/repo/scenes/veach-ajar/scene.json"
   --scene "killeroos=$tmp/repo/scenes/killeroos/scene.json")
"${B[@]}" --db "$tmp/a.db" >"$tmp/a.log" 2>&1 || { cat "$tmp/a.log"; fail "restore from another folder"; }
grep -q "restored from .*: 28 jobs" "$tmp/a.log" || { cat "$tmp/a.log"; fail "expected 28 jobs (14 per scene)"; }
count=$("$PY" -c "import sqlite3,sys; c=sqlite3.connect(sys.argv[1]); print(c.execute(
  'SELECT count(*) FROM samples s JOIN (SELECT DISTINCT scene_id FROM hybrid_jobs) j USING (scene_id)').fetchone()[0],
  c.execute('SELECT count(*) FROM samples').fetchone()[0])" "$tmp/a.db")
set -- $count
[ "$1" -gt 0 ] && [ "$1" = "$2" ] || fail "samples of the kept scenes: $1 of $2 rows match a job's scene id"
# a repainted texture (one pixel of the uncompressed TGA's data, after its 18-byte header):
# refused with what changed, then re-mapped on request
"$PY" -c "import sys; f=open(sys.argv[1],'r+b'); f.seek(1000); b=f.read(1); f.seek(1000); f.write(bytes([b[0]^0xff]))" \
  "$tmp/shared/scenes/veach-ajar/textures/cherry-wood-texture.tga"
if "${B[@]}" --db "$tmp/b.db" >"$tmp/b.log" 2>&1; then cat "$tmp/b.log"; fail "a changed texture restored silently"; fi
grep -q "veach-ajar: .* has scene id .*, the dump's rows .*changed: textures)" "$tmp/b.log" ||
  { cat "$tmp/b.log"; fail "the refusal does not name the changed part"; }
[ ! -e "$tmp/b.db" ] || fail "a refused restore left $tmp/b.db"
"${B[@]}" --db "$tmp/c.db" --remap-scenes >"$tmp/c.log" 2>&1 || { cat "$tmp/c.log"; fail "--remap-scenes"; }
grep -q "warning: --remap-scenes: veach-ajar: .*changed: textures" "$tmp/c.log" ||
  { cat "$tmp/c.log"; fail "--remap-scenes did not warn"; }
grep -q "restored from .*: 28 jobs" "$tmp/c.log" || { cat "$tmp/c.log"; fail "--remap-scenes lost jobs"; }
echo "ok: the committed baseline restores from another folder; a changed texture is named"
