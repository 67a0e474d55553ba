#!/bin/sh
# Renders the whole TAA dataset of issue #19 into OUT (resumable: finished folders are kept).
#   tools/taa/render_all.sh BUILD_DIR OUT_DIR [SHARED_SCENES_DIR]
# 1. Full path depth at 1, 2, 4 and 8 spp (render_noisy.sh; one reference per scene):
#      validation: pillars (synthetic, 120 frames), living-room (real, 72 frames), with
#                  REF_SPP 16 (256 samples per output pixel)
#      training:   stairs, fence (120 frames), the four jumps scenes (96), staircase, bathroom
#                  (real, 96), with REF_SPP 8 (128 per output pixel)
#    -> OUT/full/NAME-ref, OUT/full/NAME-sppK
# 2. The maxDepth-1 sets of the earlier weights, re-rendered with the prevdepth AOV:
#    synthetic stairs / fence / pillars (120 frames), the fast set, the jumps set (96), and
#    the real staircase / bathroom / living-room at 8 spp (render_real.sh, with the camera
#    paths of commit 5bcc6a6 when the checkout has them) -> OUT/d1/NAME
# Environment: THREADS (2), ONLY="full" or "d1" to render one part.
set -eu
build=$1
out=$2
shared=${3:-$(dirname "$0")/../../../shared/scenes}
here=$(cd "$(dirname "$0")" && pwd)
root=$here/../..
paths=$out/paths
mkdir -p "$out/full/scenes" "$out/d1" "$paths"
for s in staircase bathroom living-room; do
  [ -f "$paths/$s.json" ] || git -C "$root" show "5bcc6a6:scenes/paths/$s.json" > "$paths/$s.json" 2>/dev/null ||
    cp "$root/scenes/$s/scene.json" "$paths/$s.json"
done

part() { case " ${ONLY:-full d1} " in *" $1 "*) return 0 ;; *) return 1 ;; esac; }

if part full; then
  sc=$out/full/scenes
  [ -f "$sc/pillars/scene.json" ] || "$here/../run" taa.make_scenes "$sc" > /dev/null
  [ -f "$sc/blocks-jumps/scene.json" ] || "$here/../run" taa.make_scenes "$sc" --set jumps > /dev/null
  for spec in staircase:72x128 bathroom:96x96 living-room:128x72; do
    s=${spec%%:*}; r=${spec#*:}
    if [ ! -f "$sc/$s/scene.json" ]; then
      mkdir -p "$sc/$s"
      "$build/host/host" --quiet --convert "$shared/$s/$s.pbrt" --out "$sc/$s/scene.json"
      "$here/../run" taa.real_scenes "$sc/$s/scene.json" "$paths/$s.json" \
        "$sc/$s/scene.json" --speed 2 --res "$r" --spp 1 --max-depth 64
    fi
  done
  noisy() { REF_SPP=$3 sh "$here/render_noisy.sh" "$build" "$out/full" "$1" "$sc/$1/scene.json" "$2"; }
  noisy pillars 120 16
  noisy stairs 120 8
  noisy fence 120 8
  for s in blocks-jumps stairs-jumps fence-jumps windows-jumps; do noisy $s 96 8; done
  noisy living-room 72 16
  noisy staircase 96 8
  noisy bathroom 96 8
fi

if part d1; then
  d=$out/d1
  [ -f "$d/pillars/manifest.json" ] || sh "$here/render_dataset.sh" "$build" "$d" 120
  [ -f "$d/fence-fast/manifest.json" ] || SET=fast sh "$here/render_dataset.sh" "$build" "$d" 96
  [ -f "$d/windows-jumps/manifest.json" ] || SET=jumps sh "$here/render_dataset.sh" "$build" "$d" 96
  [ -f "$d/living-room/manifest.json" ] || PATHS=$paths sh "$here/render_real.sh" "$build" "$d" "$shared"
fi
