#!/usr/bin/env bash
# tools/pssmlt/chapter4.py with its quick settings on pbrt-v4's Cornell box: every step runs
# (BDPT reference, tuning "ours", Fig. 4.6 runs, error against CPU time for the five methods,
# crops, the light a long path-traced render lacks, BDPT's speed against PT's, plots), the summary holds both methods at both mutation counts with path lengths and
# every method's curve, the figures are PNGs, a step resumes without rendering again, and bad
# input (unknown scene, a step before its reference) fails naming what is missing.
set -euo pipefail
PY=/usr/bin/python3
if [ ! -f "$TT_SOURCE_ROOT/../shared/scenes/cornell-box-pbrt/cornell-box.pbrt" ]; then
  echo "FAIL: ../shared/scenes is missing (the worktree must sit beside /work/shared)"; exit 1
fi
dir=$(mktemp -d /tmp/tt_chapter4XXXXXX)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { if ! eval "$1"; then echo "FAIL: $1"; fail=1; fi; }
run() { "$PY" -m tools.pssmlt.chapter4 --quick --host "$TT_BUILD_ROOT/host/host" --out "$dir/run" --figures "$dir/fig" "$@"; }

out=$(run all cornell-box)
echo "$out" | tail -4
check '[ -f "$dir/run/refs/cornell-box.exr" ]'
check 'grep -q "\"spp\": 64" "$dir/run/refs/cornell-box.json"'
check 'grep -q "integrator_pssmlt.mode=mmlt" "$dir/run/tune/cornell-box.json"'
check 'grep -q "integrator_pssmlt.binning=true" "$dir/run/tune/cornell-box.json"'
for f in ch4_fig46.png ch4_error_vs_time.png ch4_error_vs_time_cornell-box.png ch4_crops_cornell-box.png \
         ch4_caustic_cornell-box.png; do
  check '[ "$(head -c 4 "$dir/fig/$f" | tail -c 3)" = "PNG" ]'
done
"$PY" - "$dir/fig/ch4_summary.json" <<'PYEOF' || fail=1
import json, sys
s = json.load(open(sys.argv[1]))['scenes']['cornell-box']
eq = s['equal_mutations']
assert [e['mpp'] for e in eq] == [4, 8], eq
for e in eq:
    assert e['reps'] == 2 and len(e['rel_diff']) == 2, e
    for m in ('original', 'ours'):
        assert e[m]['rrmse'] > 0 and e[m]['mean_path_length'] > 0 and 0 < e[m]['small_step_acceptance'] < 1, e[m]
assert sorted(s['curves']) == sorted(['pt', 'bdpt', 'pssmlt', 'original', 'ours']), s['curves'].keys()
for m, pts in s['curves'].items():
    assert len(pts) >= 3 and all(p[1] > 0 and p[2] > 0 for p in pts), (m, pts)
    errs = [p[2] for p in pts]
    assert errs[-1] < errs[0], (m, errs)   # more samples, less error
c = s['caustic']   # the light a long path-traced render lacks, per method at one count
assert c['pt_long_spp'] == 64 and c['count'] == 8 and sorted(c['methods']) == sorted(s['curves']), c
for m, v in c['methods'].items():
    assert v['fraction'] >= 0 and v['cpu_s'] > 0, (m, v)
for e in s['ours_vs_original_equal_time']:
    assert e['ours'] > 0 and e['original'] > 0 and e['rel_diff'] == (e['ours'] - e['original']) / e['original'], e
sp = s['speed']
assert sp['pt']['samples_per_s'] > 0 and sp['bdpt']['samples_per_s'] > 0, sp
assert sp['bdpt']['rays_per_sample'] > sp['pt']['rays_per_sample'], sp
print('summary ok')
PYEOF
# resuming: nothing is rendered again
again=$(run fig46 cornell-box)
check '[ -z "$again" ]'
# bad input
if msg=$(run fig46 no-such-scene 2>&1); then echo "FAIL: unknown scene accepted"; fail=1; fi
check 'grep -q "unknown scene" <<<"$msg"'
if msg=$(run fig46 caustic-glass 2>&1); then echo "FAIL: fig46 ran without a reference"; fail=1; fi
check 'grep -q "refs/caustic-glass.exr: missing" <<<"$msg"'
exit $fail
