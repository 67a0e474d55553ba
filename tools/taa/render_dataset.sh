#!/bin/sh
# Renders the TAA dataset: the synthetic scenes of make_scenes.py as 24 fps sequences with
# the Halton jitter cycle, depth/motion AOVs and the 4x4-supersampled Blackman-Harris
# reference (thesis 5.5.1), plus the VCTAA output of post_taa for comparison.
#   tools/taa/render_dataset.sh BUILD_DIR OUT_DIR [FRAMES]
# SET=fast renders make_scenes.py's fast-motion set (windows, blinds, windows-pan,
# blinds-dolly, stairs-fast, fence-fast) instead of stairs, fence, pillars; SET=jumps its
# small-sudden-turn set (blocks-jumps, stairs-jumps, fence-jumps, windows-jumps); THREADS (2).
set -eu
build=$1
out=$2
frames=${3:-120}
here=$(dirname "$0")
if [ "${SET:-}" = fast ]; then
  "$here/../run" taa.make_scenes "$out/scenes" --set fast
  names="windows blinds windows-pan blinds-dolly stairs-fast fence-fast"
elif [ "${SET:-}" = jumps ]; then
  "$here/../run" taa.make_scenes "$out/scenes" --set jumps
  names="blocks-jumps stairs-jumps fence-jumps windows-jumps"
else
  "$here/../run" taa.make_scenes "$out/scenes"
  names="stairs fence pillars"
fi
for s in $names; do
  TT_PLUGIN_PATH="$build/plugins" "$build/host/host" --quiet --threads "${THREADS:-2}" \
    --sequence "$frames" --out-dir "$out/$s" --reference-scale 4 \
    --set integrator_pt.maxDepth=1 --post post_taa --set post_taa.mode=vctaa \
    "$out/scenes/$s/scene.json"
done
