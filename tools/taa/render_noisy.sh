#!/bin/sh
# Renders one scene's full-path-depth TAA sequences at several sample rates (issue #19: what
# a real-time path tracer feeds TAA): one reference, shared by every rate, and the input
# sequences, each folder a dataset sequence for train.py / eval.py / evaluate.sh.
#   tools/taa/render_noisy.sh BUILD_DIR OUT_DIR NAME SCENE.json FRAMES
# writes
#   OUT_DIR/NAME-ref/     frame_NNNN.exr: the pose at 4 x 4 the resolution with REF_SPP samples
#                         per pixel of that film (16 * REF_SPP per output pixel), random
#                         sub-pixel positions, Blackman-Harris downsampled (host --supersample)
#   OUT_DIR/NAME-sppK/    for K in SPPS: colour at K spp (all samples at the frame's Halton
#                         jitter), depth, motion, prevdepth AOVs, the VCTAA output, and a
#                         manifest whose "reference" entries point at NAME-ref; render.args
#                         holds the host arguments that reproduce the input (evaluate.sh)
# Environment: SPPS ("1 2 4 8"), REF_SPP (8), DEPTH (64: the path tracer's largest depth,
# i.e. full path depth with Russian roulette), THREADS (2), SEED (the scene's).
# A folder that already has a complete manifest is kept (rerun to resume after a stop).
set -eu
build=$1
out=$2
name=$3
scene=$4
frames=$5
here=$(cd "$(dirname "$0")" && pwd)
depth=${DEPTH:-64}
seed=${SEED:+--seed $SEED}
host() {
  TT_PLUGIN_PATH="$build/plugins" "$build/host/host" --quiet --threads "${THREADS:-2}" "$@"
}
done_dir() {  # a finished run closed its manifest and has every frame
  [ -f "$1/manifest.json" ] && [ "$(grep -c '"index"' "$1/manifest.json")" -eq "$frames" ] &&
    tail -n 1 "$1/manifest.json" | grep -q '}' && ! grep -q '"incomplete"' "$1/manifest.json"
}
last=$((frames - 1))
ref="$out/$name-ref"
if ! done_dir "$ref"; then
  host --frames "0:$last" --out "$ref/frame_%04d.exr" --supersample 4 --spp "${REF_SPP:-8}" \
    --set integrator_pt.maxDepth="$depth" $seed "$scene"
fi
for k in ${SPPS:-1 2 4 8}; do
  dir="$out/$name-spp$k"
  if ! done_dir "$dir"; then
    host --sequence "$frames" --out-dir "$dir" --spp "$k" --set integrator_pt.maxDepth="$depth" \
      $seed --post post_taa --set post_taa.mode=vctaa "$scene"
  fi
  printf '%s\n' "--spp $k --set integrator_pt.maxDepth=$depth $seed $(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")" \
    > "$dir/render.args"
  "$here/../run" taa.link_reference "$dir" "$ref"
done
