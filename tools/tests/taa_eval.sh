#!/usr/bin/env bash
# The TAA evaluation end to end through the issue's interface: host renders a short
# sequence (--frames A:B --out DIR/frame_%04d.exr), its supersampled reference
# (--supersample 2) and the VCTAA-filtered frames (--plugin post_taa); tools/taa/eval.py
# prints RMSE, temporal error and FLIP. Checks: FLIP's self-test (tools/taa/flip.py:
# identical -> 0, black/white, monotone in noise, values against an independent
# implementation); the reference against itself scores exactly 0 on every metric; the raw
# frames score > 0 and FLIP lies in (0, 1]; bad input is refused naming the file.
# Exit 77 (skip) without python3-numpy/-scipy/-openimageio.
set -euo pipefail
PY=/usr/bin/python3
if ! "$PY" -c 'import numpy, scipy, OpenImageIO' 2>/dev/null; then
  echo "SKIP: python3-numpy/scipy/openimageio not installed (tools/bootstrap.sh installs them)"
  exit 77
fi
HOST="$TT_BUILD_ROOT/host/host"
SCENE="$TT_SOURCE_ROOT/scenes/cornell-box/scene.json"
dir=$(mktemp -d /tmp/tt_taa_evalXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }

"$PY" -m tools.taa.flip --selftest || { echo "FAIL: flip.py --selftest"; fail=1; }

common=(--quiet --threads 2 --res 48x36 --spp 2 --frames 0:11 --set integrator_pt.maxDepth=1)
"$HOST" "${common[@]}" --out "$dir/ref/frame_%04d.exr" --supersample 2 "$SCENE"
"$HOST" "${common[@]}" --out "$dir/raw/frame_%04d.exr" "$SCENE"
"$HOST" "${common[@]}" --out "$dir/vc/frame_%04d.exr" --plugin post_taa \
  --set post_taa.mode=vctaa "$SCENE"
"$PY" -m tools.taa.eval --ref "$dir/ref" --test "$dir/ref" --key reference --skip 4 \
  --json "$dir/self.json"
"$PY" -m tools.taa.eval --ref "$dir/ref" --test "$dir/raw" --test "$dir/vc" --skip 4 \
  --json "$dir/eval.json" | tee "$dir/eval.txt"
check "grep -q 'raw:color .*RMSE .*temporal .*FLIP' '$dir/eval.txt'"
check "grep -q 'vc:post (post_taa) .*FLIP' '$dir/eval.txt'"
# by default a filtered sequence is scored on its input frames too, not only the filtered
check "grep -q 'vc:color .*RMSE .*temporal .*FLIP' '$dir/eval.txt'"
check "[ \$(grep -c RMSE '$dir/eval.txt') = 3 ]"
# --help says what every option does
"$PY" -m tools.taa.eval --help > "$dir/help.txt"
"$PY" - "$dir/help.txt" <<'PYEOF' || fail=1
import re, sys
text = open(sys.argv[1]).read()
usage = text.split("\n\n")[0]
opts = sorted(set(re.findall(r"--[a-z-]+", usage)))
bad = [o for o in opts if not re.search(r"^  " + re.escape(o) + r"\b[^\n]*\S\s{2,}\S", text, re.M)]
if len(opts) < 7 or bad:
    print("FAIL: eval.py --help describes no text for", bad or opts)
    sys.exit(1)
PYEOF
"$PY" - "$dir/self.json" "$dir/eval.json" <<'PYEOF' || fail=1
import json, sys
rows = {r["label"].split(":")[0]: r for f in sys.argv[1:] for r in json.load(open(f))}
ok = True
def want(cond, what):
    global ok
    if not cond:
        print("FAIL:", what); ok = False
r, raw, vc = rows["ref"], rows["raw"], rows["vc"]
want(r["rmse"] == 0 and r["temporal"] == 0 and r["flip"] == 0, f"reference vs itself: {r}")
for name, x in (("raw", raw), ("vctaa", vc)):
    want(x["rmse"] > 1e-4 and x["temporal"] > 0, f"{name}: RMSE/temporal not > 0")
    want(0 < x["flip"] <= 1, f"{name}: FLIP {x['flip']} outside (0, 1]")
    want(len(x["flip_per_frame"]) == 12 - 4, f"{name}: {len(x['flip_per_frame'])} FLIP frames")
sys.exit(0 if ok else 1)
PYEOF

# bad input: a folder without manifest, a key the manifest lacks
if out=$("$PY" -m tools.taa.eval --ref "$dir/nothing" --test "$dir/raw" 2>&1); then
  echo "FAIL: eval.py accepted a missing reference folder"; fail=1
fi
check "grep -q 'nothing/manifest.json' <<<\"\$out\""
if out=$("$PY" -m tools.taa.eval --ref "$dir/raw" --test "$dir/vc" 2>&1); then
  echo "FAIL: eval.py accepted a reference folder without reference frames"; fail=1
fi
check "grep -q 'no \"reference\" file' <<<\"\$out\""
exit $fail
