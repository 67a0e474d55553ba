#!/usr/bin/env bash
# tools/scenes/generate.py end to end: a small voxel world, a thin cylinder inserted into the
# Cornell box and the committed Cornell-box variants load and render with host at 32x32 with
# exit 0, no non-finite sample, rays > 0 and a non-black mean; the variants in
# scenes/cornell-box-variants/ are what the generator writes today; --camera-index gives a
# different image than index 0 on a scene with a path; --frames A:B writes B-A+1 numbered files;
# scenes/animated-stress is what tools/scenes/anim_stress.py writes and plays as a sequence;
# tools/tuning/cylinder_sweep.py measures its angles as the frames of one sequence.
set -euo pipefail
PY=/usr/bin/python3
if ! "$PY" -c 'import numpy' 2>/dev/null; then
  echo "SKIP: python3-numpy is not installed (tools/bootstrap.sh installs it)"
  exit 77
fi
HAVE_OIIO=0
"$PY" -c 'import OpenImageIO' 2>/dev/null && HAVE_OIIO=1
HOST="$TT_BUILD_ROOT/host/host"
INFO="$TT_BUILD_ROOT/tools/tests/scenes_info"
GEN=("$PY" -m tools.scenes.generate)
CAM=("$PY" -m tools.scenes.camera_path)
CBOX="$TT_SOURCE_ROOT/scenes/cornell-box/scene.json"
dir=$(mktemp -d /tmp/tt_scenes_genXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }
jnum() { "$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d[sys.argv[2]])' "$1" "$2"; }
exr_mean() { "$PY" -c 'import OpenImageIO as o,sys; b=o.ImageBuf(sys.argv[1]); import numpy as n; print(float(n.mean(b.get_pixels(o.FLOAT))))' "$1"; }
exr_diff() { "$PY" -c 'import OpenImageIO as o,sys,numpy as n; a=o.ImageBuf(sys.argv[1]).get_pixels(o.FLOAT); b=o.ImageBuf(sys.argv[2]).get_pixels(o.FLOAT); print(float(n.mean(n.abs(a-b))))' "$1" "$2"; }

# render NAME SCENE [host options...]: renders, checks exit 0, nonfinite 0, rays > 0, mean > 0
render() {
  local name=$1 scene=$2
  shift 2
  local rc=0
  "$HOST" --quiet --res 32x32 --spp 4 --threads 2 --seed 3 --out "$dir/$name.exr" \
    --stats "$dir/$name.json" "$@" "$scene" || rc=$?
  check "[ $rc = 0 ]"
  [ $rc = 0 ] || return 0
  check "[ \"$(jnum "$dir/$name.json" nonfinite)\" = 0 ]"
  check "[ \"$(jnum "$dir/$name.json" rays | cut -d. -f1)\" -gt 0 ]"
  if [ $HAVE_OIIO = 1 ]; then
    local m
    m=$(exr_mean "$dir/$name.exr")
    echo "$name: mean $m"
    check "\"$PY\" -c 'import sys; sys.exit(not ($m > 1e-4 and $m < 1e4))'"
  fi
}

# 1. voxel world (small) -----------------------------------------------------------------
"${GEN[@]}" voxel "$dir/vox" --size 40 --seed 5 >"$dir/vox.log"
cat "$dir/vox.log"
check '[ -f "$dir/vox/scene.json" ] && [ -f "$dir/vox/voxel_grass.ply" ]'
info=$("$INFO" "$dir/vox/scene.json")
echo "$info"
vox_tris=$(sed -n 's/.*voxel: \([0-9]*\) triangles in.*/\1/p' "$dir/vox.log")
check "grep -q '\"triangles\": $vox_tris,' <<<'$info'"
check "grep -q '\"path_keys\": 6}' <<<'$info'"
check "grep -q '\"environment\": 1, \"point\": 0, \"spot\": 0, \"distant\": 1' <<<'$info'"
# every triangle of a unit-box face: the bounds are whole numbers inside the 40 x 64 x 40 grid
check "grep -q '\"bounds\": \[\[0, [0-9]*, 0\], \[40, [0-9]*, 40\]\]' <<<'$info'"
render vox "$dir/vox/scene.json"
# the same seed gives the same world
"${GEN[@]}" voxel "$dir/vox2" --size 40 --seed 5 >/dev/null
check 'cmp -s "$dir/vox/voxel_grass.ply" "$dir/vox2/voxel_grass.ply"'

# 2. thin cylinder in the Cornell box ------------------------------------------------------
"${GEN[@]}" cylinder "$CBOX" "$dir/cyl/scene.json" --theta 45 >"$dir/cyl.log"
cat "$dir/cyl.log"
info=$("$INFO" "$dir/cyl/scene.json")
check "grep -q '\"triangles\": 48,' <<<'$info'"      # 32 + 16 cylinder triangles
check "grep -q '\"meshes\": 9,' <<<'$info'"
check 'grep -q "length 480.37" "$dir/cyl.log"'        # half of the box's 960.74 mm diagonal
render cyl "$dir/cyl/scene.json"
# a scene with mesh files: the copy elsewhere still finds them
mkdir -p "$dir/other"
"${GEN[@]}" cylinder "$dir/vox/scene.json" "$dir/other/deep/cyl_vox.json" --theta 10 >/dev/null
render cylvox "$dir/other/deep/cyl_vox.json"

# 3. Cornell-box variants: committed == generated, and each renders -----------------------
"${GEN[@]}" cornell-variants "$dir/cv" >/dev/null
for v in specular-plastic box-plastic specular-box; do
  committed="$TT_SOURCE_ROOT/scenes/cornell-box-variants/$v/scene.json"
  check "cmp -s '$committed' '$dir/cv/$v/scene.json'"
  render "cv_$v" "$committed"
done

# 4. camera path samples ------------------------------------------------------------------
SCENE="$TT_SOURCE_ROOT/scenes/cornell-box-variants/box-plastic/scene.json"
render idx0 "$SCENE" --camera-index 0
render idx40 "$SCENE" --camera-index 40
if [ $HAVE_OIIO = 1 ]; then
  d=$(exr_diff "$dir/idx0.exr" "$dir/idx40.exr")
  echo "camera-index 0 vs 40: mean |difference| $d"
  check "\"$PY\" -c 'import sys; sys.exit(not $d > 1e-3)'"
  # sample 0 is the still camera of this scene (its path starts there): same image
  render still "$SCENE"
  d=$(exr_diff "$dir/idx0.exr" "$dir/still.exr")
  check "\"$PY\" -c 'import sys; sys.exit(not $d == 0)'"
fi
# the Python sampler agrees with the path's ends
"${CAM[@]}" sample "$SCENE" >"$dir/samples.jsonl"
check '[ "$(wc -l <"$dir/samples.jsonl")" = 100 ]'
check 'grep -q "\"index\": 99, \"t\": 10.0, \"position\": \[278.0, 273.0, -800.0\]" "$dir/samples.jsonl"'
mkdir -p "$dir/fr"
"$HOST" --quiet --res 8x8 --spp 1 --threads 2 --frames 97:100 --out "$dir/fr/out.exr" \
  --stats "$dir/fr/st.json" "$SCENE"
check '[ -f "$dir/fr/out_0097.exr" ] && [ -f "$dir/fr/out_0098.png" ] && [ -f "$dir/fr/out_0100.exr" ]'
check '[ -f "$dir/fr/st_0100.json" ] && [ ! -e "$dir/fr/out_0096.exr" ] && [ ! -e "$dir/fr/out_0101.exr" ]'
rc=0; "$HOST" --quiet --frames 5:4 "$SCENE" 2>/dev/null || rc=$?
check '[ $rc = 2 ]'
rc=0; "$HOST" --quiet --camera-index 100 "$SCENE" 2>/dev/null || rc=$?
check '[ $rc = 2 ]'
# camera_path.py auto + merge on a scene without a path: a 5-key path host renders along
"${CAM[@]}" auto "$CBOX" >"$dir/frag.json"
"${CAM[@]}" merge "$CBOX" "$dir/frag.json" "$dir/merged/scene.json"
check "grep -q '\"path_keys\": 5}' <<<\"\$(\"$INFO\" \"$dir/merged/scene.json\")\""
render merged "$dir/merged/scene.json" --camera-index 30

# 5. the animated stress scene (tools/scenes/anim_stress.py): committed == generated; its
# sequence poses every frame (an update per frame) and stays inside the camera path --------
"$PY" -m tools.scenes.anim_stress "$dir/as/scene.json" >/dev/null
check "cmp -s '$TT_SOURCE_ROOT/scenes/animated-stress/scene.json' '$dir/as/scene.json'"
"$HOST" --quiet --no-db --res 16x12 --spp 1 --threads 2 --sequence 117:119 --out-dir "$dir/as/seq" \
  "$TT_SOURCE_ROOT/scenes/animated-stress/scene.json"
check '[ "$(grep -c "\"update\": \"rebuild\"" "$dir/as/seq/manifest.json")" = 3 ]'
rc=0; "$PY" -m tools.scenes.anim_stress "$dir/as/bad.json" --grid 1 2>"$dir/as/bad.log" || rc=$?
check '[ $rc = 2 ] && grep -q -- "--grid: expected 2..2000" "$dir/as/bad.log" && [ ! -e "$dir/as/bad.json" ]'

# 6. cylinder_sweep.py: the angles are the frames of one sequence per configuration ---------
rc=0; "$PY" -m tools.tuning.cylinder_sweep --host "$HOST" --scene "$CBOX" --angles 3 --reps 1 \
  --res 8x8 --backends native --work "$dir/sweep" >"$dir/sweep.log" 2>&1 || rc=$?
check '[ $rc = 0 ]'
check '[ "$(wc -l <"$dir/sweep/runs.csv")" = 7 ]'                  # header + 2 qualities x 3 angles
check 'grep -q "^native,3,120.0,0," "$dir/sweep/runs.csv"'
check "\"$PY\" -c 'import json,sys; d=json.load(open(sys.argv[1])); c=d[\"stress\"][\"cylinder\"]; sys.exit(not (c[\"time\"] == [0, 3] and c[\"to\"] == 180 and d[\"camera\"][\"path\"] == []))' '$dir/sweep/cylinder.json'"

[ $HAVE_OIIO = 1 ] || echo "note: python3-openimageio missing: image means and differences not checked"
exit $fail
