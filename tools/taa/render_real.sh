#!/bin/sh
# Renders the real-scene TAA sequences (pbrt scenes of ../shared/scenes with the camera
# paths of scenes/paths, played 2x fast) like render_dataset.sh: 8 spp at the fixed
# jitter position, maxDepth 1, 4x4-supersampled reference, VCTAA output; the scenes go to
# OUT/scenes/NAME/scene.json (resolution, spp and maxDepth baked in, for evaluate.sh).
#   tools/taa/render_real.sh BUILD_DIR OUT_DIR [SCENES_DIR]
# staircase and bathroom are training data, living-room is validation. The camera path is
# scenes/NAME/scene.json's; the shipped dataset used the earlier fragments
# scenes/paths/NAME.json of commit 5bcc6a6 (PATHS=DIR takes DIR/NAME.json instead).
# Environment: ONLY="living-room ..." renders only these; SPP (8), REF_SCALE (4: the
# reference takes SPP samples per pixel at REF_SCALE^2 the pixels, so SPP*REF_SCALE^2 per
# output pixel), THREADS (2).
set -eu
build=$1
out=$2
shared=${3:-$(dirname "$0")/../../../shared/scenes}
here=$(cd "$(dirname "$0")" && pwd)
for spec in staircase:72x128:96 bathroom:96x96:96 living-room:128x72:72; do
  s=${spec%%:*}; rest=${spec#*:}; r=${rest%%:*}; n=${rest#*:}
  case " ${ONLY:-$s} " in *" $s "*) ;; *) continue ;; esac
  mkdir -p "$out/scenes/$s"
  "$build/host/host" --quiet --convert "$shared/$s/$s.pbrt" --out "$out/scenes/$s/scene.json"
  if [ -n "${PATHS:-}" ]; then path=$PATHS/$s.json; else path=$here/../../scenes/$s/scene.json; fi
  "$here/../run" taa.real_scenes "$out/scenes/$s/scene.json" "$path" \
    "$out/scenes/$s/scene.json" --speed 2 \
    --res "$r" --spp "${SPP:-8}" --max-depth 1
  TT_PLUGIN_PATH="$build/plugins" "$build/host/host" --quiet --threads "${THREADS:-2}" --spp "${SPP:-8}" \
    --sequence "$n" --out-dir "$out/$s" --reference-scale "${REF_SCALE:-4}" \
    --set integrator_pt.maxDepth=1 --post post_taa --set post_taa.mode=vctaa \
    "$out/scenes/$s/scene.json"
done
