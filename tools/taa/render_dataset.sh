#!/bin/sh
# Renders the TAA dataset: the synthetic scenes of make_scenes.py as 24 fps sequences with
# the Halton jitter cycle, depth/motion AOVs and the 4x4-supersampled Blackman-Harris
# reference (thesis 5.5.1), plus the VCTAA output of post_taa for comparison.
#   tools/taa/render_dataset.sh BUILD_DIR OUT_DIR [FRAMES]
set -eu
build=$1
out=$2
frames=${3:-120}
here=$(dirname "$0")
/usr/bin/python3 "$here/make_scenes.py" "$out/scenes"
for s in stairs fence pillars; do
  TT_PLUGIN_PATH="$build/plugins" "$build/host/host" --quiet --threads 2 \
    --sequence "$frames" --out-dir "$out/$s" --reference-scale 4 \
    --set integrator_pt.maxDepth=1 --post post_taa --set post_taa.mode=vctaa \
    "$out/scenes/$s/scene.json"
done
