#!/usr/bin/env bash
# The quick evidence pass (tools/evidence/run.py --quick: every figure tool at toy sizes, the
# committed-data figures redrawn, the results page written) into a temporary folder, then
# the page opened in headless chromium (tools/evidence/check_page.py): every image loads,
# every link resolves. The checker must catch a broken page: a copy with one image pointing
# at a missing PNG, one link to a missing anchor and one to a missing file must fail,
# naming each. A figure tool that stops working fails here.
set -euo pipefail
PY=/usr/bin/python3
cd "$TT_SOURCE_ROOT"
dir=$(mktemp -d /tmp/tt_evidenceXXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }
command -v chromium >/dev/null || { echo "FAIL: no chromium (tools/bootstrap.sh installs it)"; exit 1; }

if ! "$PY" -m tools.evidence.run --quick --host "$TT_BUILD_ROOT/host/host" --out "$dir/page"; then
  echo "FAIL: the quick evidence pass failed"; fail=1
fi
page=$dir/page/index.html
check '[ -s "$page" ]'
# the steps' figures are there and are PNGs
for f in hybrid/fig3_17_speedup_render.png hybrid/speed_vs_roofline.png accel/render_split_t1d3.png \
         quick/tuning_correlation.png quick/cylinder_cornell-box.png quick/theta_cornell-box.png \
         quick/pssmlt_tuning_cornell-box.png quick/pssmlt_equal_mutations.png \
         quick/pssmlt_error_vs_time.png quick/pssmlt_sigma_sweep.png quick/gains_cornell-box.png \
         quick/taa_speed.png quick/error_vs_time_cornell.png taa/speed_vs_rmse.png taa/darkening.png \
         charts/sampler_choice.png charts/sampler_heldout_integrator_bdpt.png quick/hybrid_roofline_speed.png hybrid/roofline_speed.png \
         accel/anim_update_living-room-cylinder.png quick/anim_update_animated-stress.png \
         hybrid/sequence_hybrid.png hybrid/sequence_hybrid-stress-detail.png; do
  check '[ "$(head -c 4 "$dir/page/$f" | tail -c 3)" = "PNG" ]'
done
# every chapter, the outcome table, no failed step
for id in ch3 ch4 ch5 outcomes quick-pass ch3-hybrid ch3-sequence-hybrid; do check "grep -q 'id=\"$id\"' '$page'"; done
check '! grep -q "FAILED" "$page"'
# the hybrid table is read from the committed summary (nn on build+render: 2.51x)
check 'grep -q "2.51x" "$page"'
# the re-measured rooflines from their committed JSON (nn on build+render, all test states)
check 'grep -q "build+render, all</td><td>28</td><td>0.548 (0.558)</td><td>0 of 28</td><td>0.516 / 0.550</td><td>1.94x / 0.967" "$page"'
# and the TAA test set from its committed JSON (cornell-box at 1 spp: the default c6 0.78 x VCTAA's RMSE, then c12 0.90 x)
check 'grep -q "cornell-box-spp1</td><td>0.0178 / 0.0089 / 0.802</td><td>0.78 / 1.10 / 0.916</td><td>0.90 / 1.34 / 0.960" "$page"'
# and the validation choice of the default network from its committed JSON (c6: 2 of 4 sequences)
check 'grep -q "c6 (chosen: the default)</td><td>19093</td><td>2 / 4</td><td>0.0329</td><td>0.74 / 0.91" "$page"'
# and the TAA speed table from its committed JSON (the default network at 640x480: 36.4 CPU ms)
check 'grep -q "c6 (default network)</td><td>640x480</td><td>2</td><td>52.7 (43.2-59.0)</td><td>36.4</td>" "$page"'
# and the Cycles comparison from its committed JSON (the glossy variant at depth 8)
check 'grep -q "cornell-glossy</td><td>8</td><td>+0.09%</td><td>0.2470 / 0.1988</td>" "$page"'

out=$("$PY" -m tools.evidence.check_page "$page" 2>&1) || { echo "$out"; echo "FAIL: the page does not pass the browser check"; fail=1; }
echo "$out"

# the checker fails on a broken page, naming each problem
bad=$dir/page/bad.html
sed -e '0,/src="hybrid\/fig3_17_speedup_render.png"/s//src="hybrid\/missing.png"/' \
    -e '0,/href="#ch3-hybrid"/s//href="#no-such-anchor"/' \
    -e '0,/href="[^"#]*README.md"/s//href="..\/no-such-file.md"/' "$page" >"$bad"
if "$PY" -m tools.evidence.check_page "$bad" >"$dir/bad.txt" 2>&1; then
  echo "FAIL: the checker passed a page with a broken image and broken links"; fail=1
fi
sed "s/^/  (expected) /" "$dir/bad.txt"
check 'grep -q "image does not load: hybrid/missing.png" "$dir/bad.txt"'
check 'grep -q "missing anchor: #no-such-anchor" "$dir/bad.txt"'
check 'grep -q "missing file: ../no-such-file.md" "$dir/bad.txt"'
[ "$fail" = 0 ] && echo "evidence: ok"
exit "$fail"
