#!/bin/sh
# One-command evaluation on the held-out sequence(s): renders each through post_taa in
# modes none / vctaa / network (12 and 6 channels) with the C plugin and prints RMSE and
# temporal error against the dataset's references (tools/taa/eval.py).
#   tools/taa/evaluate.sh BUILD_DIR DATA_DIR OUT_DIR [W12.ttw] [W6.ttw] [SEQUENCES]
# (THREADS=N: render threads, default 2)
set -eu
build=$1
data=$2
out=$3
w12=${4:-$(dirname "$0")/../../plugins/post_taa/post_taa_c12.ttw}
w6=${5:-$(dirname "$0")/../../plugins/post_taa/post_taa_c6.ttw}
seqs=${6:-pillars}
here=$(dirname "$0")
for s in $seqs; do
  n=$(grep -c '"index"' "$data/$s/manifest.json")
  for m in none vctaa net12 net6; do
    case $m in
      net12) set -- --set post_taa.mode=network; export TT_POST_TAA_WEIGHTS="$w12" ;;
      net6) set -- --set post_taa.mode=network; export TT_POST_TAA_WEIGHTS="$w6" ;;
      *) set -- --set post_taa.mode=$m; unset TT_POST_TAA_WEIGHTS || true ;;
    esac
    TT_PLUGIN_PATH="$build/plugins" "$build/host/host" --quiet --threads "${THREADS:-2}" \
      --sequence "$n" --out-dir "$out/$s/$m" --set integrator_pt.maxDepth=1 \
      --post post_taa "$@" "$data/scenes/$s/scene.json"
  done
  unset TT_POST_TAA_WEIGHTS || true
  echo "== $s (frames 8..$((n - 1)); tonemapped space)"
  /usr/bin/python3 "$here/eval.py" --ref "$data/$s" --json "$out/$s/eval.json" \
    --test "$out/$s/none" --test "$out/$s/vctaa" --test "$out/$s/net12" --test "$out/$s/net6"
done
