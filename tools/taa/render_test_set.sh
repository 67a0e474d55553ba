#!/bin/sh
# Renders the TAA test set (tools/taa/README, "Three sets"): the make_test_set.py scenes at
# full path depth, 1 and 8 spp, 24 frames, each against a 4 x 4 supersampled reference with
# REF_SPP (8) samples per film pixel (128 per output pixel), through render_noisy.sh.
#   tools/taa/render_test_set.sh BUILD_DIR OUT_DIR [SCENES]
# writes OUT_DIR/scenes/NAME/scene.json, OUT_DIR/NAME-ref, OUT_DIR/NAME-spp1, OUT_DIR/NAME-spp8
# (resumable: finished folders are kept). Environment: SET (test; train and val render the
# training and validation sequences of the same kind from other scenes), OFFSET (0: the
# camera path keys K..K+3, sequences named NAME-kK), RES (160x90), SPPS ("1 8"), REF_SPP,
# THREADS (render_noisy.sh's).
set -eu
build=$1
out=$2
set=${SET:-test}
here=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$out/scenes"
scenes=$(cd "$here/../.." && /usr/bin/python3 -m tools.taa.make_test_set "$out/scenes" \
  --res "${RES:-160x90}" --set "$set" --offset "${OFFSET:-0}" ${3:+--scenes "$3"})
for sc in $scenes; do
  name=$(basename "$(dirname "$sc")")
  SPPS=${SPPS:-1 8} REF_SPP=${REF_SPP:-8} sh "$here/render_noisy.sh" "$build" "$out" "$name" "$sc" 24
done
