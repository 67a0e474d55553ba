#!/usr/bin/env bash
# tools/taa/train.py end to end on tiny data: host renders a 12-frame 32x24 sequence with its
# 2x2 reference and VCTAA; train.py trains a 6-channel network for a few steps and writes
# the weights file; post_taa (the C plugin) loads that file and filters the sequence. Checks:
# training ran the asked steps (its log), the plugin loaded the file (host exits 0 and
# writes every filtered frame), and the plugin computes what PyTorch computes with the same
# weights (eval_torch.py's RMSE / temporal error of the network equal eval.py's of the
# plugin's frames to 1e-4 relative: a file the plugin read differently would not match);
# eval_torch.py --nets (several networks, evaluate.py's eval.json for select_val.py) gives the
# same network figures as its one-file form and VCTAA's from the sequence's own post frames;
# a truncated weights file is refused naming the file. The only test that imports torch:
# tests/support/bootstrap_python blocks it elsewhere so the evaluation tools stay torch-free.
set -euo pipefail
export TT_TEST_ALLOW_TORCH=1
PY=/usr/bin/python3
HOST="$TT_BUILD_ROOT/host/host"
SCENE="$TT_SOURCE_ROOT/scenes/cornell-box/path.json"
dir=$(mktemp -d /tmp/tt_taa_trainXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }

common=(--quiet --threads 1 --sequence 12 --res 32x24 --spp 1 --set integrator_pt.maxDepth=1)
"$HOST" "${common[@]}" --out-dir "$dir/data/box" --reference-scale 2 --post post_taa \
  --set post_taa.mode=vctaa "$SCENE"
# 4-frame windows: 12 frames give a window start at each of the 8 jitter indices
"$PY" -m tools.taa.train --data "$dir/data" --scenes box --out "$dir/w.ttw" --width 6 \
  --hidden 5 --steps 3 --batch 1 --patch 16 --frames 4 --minutes 5 | tee "$dir/train.txt"
check "[ -s '$dir/w.ttw' ]"
check "$PY -c 'import json,sys; sys.exit(json.load(open(\"$dir/w.ttw.train.json\"))[\"steps\"] != 3)'"

"$HOST" "${common[@]}" --out-dir "$dir/c" --reference-scale 2 --post post_taa \
  --set post_taa.mode=network --set post_taa.weights="$dir/w.ttw" "$SCENE" ||
  { echo "FAIL: post_taa did not load train.py's weights"; fail=1; }
check "[ \$(ls '$dir'/c/post_*.exr 2>/dev/null | wc -l) = 12 ]"
"$PY" -m tools.taa.eval_torch "$dir/w.ttw" "$dir/data" box --skip 2 --json "$dir/torch.json"
"$PY" -m tools.taa.eval --ref "$dir/c" --test "$dir/c" --skip 2 --no-flip --json "$dir/c.json" \
  | tee "$dir/c.txt"
"$PY" - "$dir/torch.json" "$dir/c.json" <<'PYEOF' || fail=1
import json, sys
t = json.load(open(sys.argv[1]))["box"]
row = [r for r in json.load(open(sys.argv[2])) if r["label"].startswith("c:post")][0]
rmse, tmp = row["rmse"], row["temporal"]
print(f"PyTorch RMSE {t['rmse']:.6f} temporal {t['temporal']:.6f}; C plugin {rmse:.6f} / {tmp:.6f}")
ok = rmse > 0 and abs(rmse - t["rmse"]) <= 1e-4 * t["rmse"] and \
    abs(tmp - t["temporal"]) <= 1e-4 * t["temporal"]
if not ok:
    print("FAIL: the C plugin's output differs from PyTorch's with train.py's weights")
sys.exit(0 if ok else 1)
PYEOF

"$PY" -m tools.taa.eval_torch --nets "w=$dir/w.ttw,c6=$TT_SOURCE_ROOT/plugins/post_taa/post_taa_c6.ttw" \
  "$dir/data" box --skip 2 --eval-json "$dir/multi.json" > /dev/null
"$PY" -m tools.taa.eval --ref "$dir/data/box" --test "$dir/data/box" --key post --skip 2 --no-flip \
  --json "$dir/vc.json" > /dev/null
"$PY" - "$dir/torch.json" "$dir/multi.json" "$dir/vc.json" <<'PYEOF' || fail=1
import json, sys
t = json.load(open(sys.argv[1]))["box"]
res = json.load(open(sys.argv[2]))[0]
by = {r["method"]: r for r in res["methods"]}
vc = json.load(open(sys.argv[3]))[0]
ok = (set(by) == {"vctaa", "input", "w", "c6"} and by["w"]["rmse"] == t["rmse"] and
      by["w"]["temporal"] == t["temporal"] and abs(by["vctaa"]["rmse"] - vc["rmse"]) <= 1e-9 and
      by["c6"]["rmse"] != t["rmse"] and all(0 < r["brightness"] < 10 for r in by.values()))
print(("" if ok else "FAIL: ") + f"eval_torch --nets: w {by['w']['rmse']:.6f} (one-file form "
      f"{t['rmse']:.6f}), vctaa {by['vctaa']['rmse']:.6f} (eval.py {vc['rmse']:.6f})")
sys.exit(0 if ok else 1)
PYEOF

head -c 1000 "$dir/w.ttw" > "$dir/bad.ttw"
if "$HOST" "${common[@]}" --out-dir "$dir/bad" --post post_taa --set post_taa.mode=network \
  --set post_taa.weights="$dir/bad.ttw" "$SCENE" 2> "$dir/bad.txt"; then
  echo "FAIL: a truncated weights file was accepted"; fail=1
fi
check "grep -q 'bad.ttw: truncated' '$dir/bad.txt'"
exit $fail
