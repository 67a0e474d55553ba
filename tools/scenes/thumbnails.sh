#!/usr/bin/env bash
# Renders the benchmark set's thumbnails (scenes/README.md "Benchmark scene set") with host:
# 128 px wide PNGs in scenes/thumbnails/, and prints one scenes_info JSON line per scene plus
# the render's build/render times. Generated scenes are written to $WORK (default
# /tmp/tt_scene_set) first. The pbrt scenes are rendered through their wrappers
# scenes/<name>/scene.json (the pbrt file's scene, still camera; living-room and staircase
# at maxDepth 64 where the pbrt files' 65 makes host fall back to integrator_pt's default 3).
#   tools/scenes/thumbnails.sh [BUILD_DIR] [SPP]     (defaults: build, 64)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${1:-$ROOT/build}
SPP=${2:-64}
HOST="$BUILD/host/host"
INFO="$BUILD/tools/tests/scenes_info"
PY=/usr/bin/python3
GEN=("$ROOT/tools/run" scenes.generate)
S="$ROOT/../shared/scenes"
WORK=${WORK:-/tmp/tt_scene_set}
OUT="$ROOT/scenes/thumbnails"
mkdir -p "$WORK" "$OUT"
[ -f "$WORK/voxel/scene.json" ] || "${GEN[@]}" voxel "$WORK/voxel"
[ -f "$WORK/tessellated/far.json" ] || "${GEN[@]}" tessellated "$WORK/tessellated"
"${GEN[@]}" cylinder "$ROOT/scenes/cornell-box/scene.json" \
  "$WORK/cornell-cylinder/scene.json" --theta 30 --radius 0.01 >/dev/null

# name  scene  [extra host options]
list=(
  "cornell-box|$ROOT/scenes/cornell-box/scene.json"
  "cornell-specular-plastic|$ROOT/scenes/cornell-box-variants/specular-plastic/scene.json"
  "cornell-box-plastic|$ROOT/scenes/cornell-box-variants/box-plastic/scene.json"
  "cornell-specular-box|$ROOT/scenes/cornell-box-variants/specular-box/scene.json"
  "cornell-cylinder|$WORK/cornell-cylinder/scene.json"
  "veach-mis|$ROOT/scenes/veach-mis/scene.json"
  "killeroos|$ROOT/scenes/killeroos/scene.json"
  "caustic-glass|$ROOT/scenes/caustic-glass/scene.json"
  "living-room|$ROOT/scenes/living-room/scene.json"
  "veach-ajar|$ROOT/scenes/veach-ajar/scene.json"
  "staircase|$ROOT/scenes/staircase/scene.json"
  "bathroom|$ROOT/scenes/bathroom/scene.json"
  "bmw-m6|$ROOT/scenes/bmw-m6/scene.json"
  "voxel-world|$WORK/voxel/scene.json"
  "tessellated-far|$WORK/tessellated/far.json"
  "tessellated-near|$WORK/tessellated/near.json"
)
for entry in "${list[@]}"; do
  name=${entry%%|*}
  scene=${entry#*|}
  if [ ! -f "$scene" ]; then echo "skip $name: $scene missing" >&2; continue; fi
  # the pbrt wrappers scenes/<name>/scene.json import ../shared/scenes
  if grep -q '"import"' "$scene" && [ ! -d "$S" ]; then echo "skip $name: $S missing" >&2; continue; fi
  info=$("$INFO" "$scene" 2>/dev/null)
  res=$("$PY" -c 'import json,sys; w,h=json.loads(sys.argv[1])["camera"]["resolution"]; print("128x%d" % max(1, round(128*h/w)))' "$info")
  "$HOST" --quiet --res "$res" --spp "$SPP" --out "$WORK/$name.exr" --stats "$WORK/$name.stats.json" \
    "$scene" 2>/dev/null
  # noise costs PNG bytes: re-render with 4x the samples when over 60 KiB
  if [ "$(stat -c %s "$WORK/$name.png")" -ge 61440 ]; then
    "$HOST" --quiet --res "$res" --spp $((SPP * 4)) --out "$WORK/$name.exr" \
      --stats "$WORK/$name.stats.json" "$scene" 2>/dev/null
  fi
  cp "$WORK/$name.png" "$OUT/$name.png"
  times=$("$PY" -c 'import json,sys; d=json.load(open(sys.argv[1])); print("\"build_ms\": %.0f, \"render_ms\": %.0f, \"spp\": %d, \"nonfinite\": %d, \"threads\": %d" % (d["build_ms"], d["render_ms"], d["spp"], d["nonfinite"], d["threads"]))' "$WORK/$name.stats.json")
  echo "{\"name\": \"$name\", ${info#\{}" | sed "s/}\$/, $times, \"thumb_bytes\": $(stat -c %s "$OUT/$name.png")}/"
done
