#!/usr/bin/env bash
# SDK and install end to end: install the build tree into a staging directory (meson install
# --destdir), copy the installed example plugin (PREFIX/share/tunetrace/examples), build and
# install it with its Makefile (which knows tunetrace only through pkg-config), then load it
# with a tiny loader-API program and with the installed program, `tunetrace`, run from a
# clean environment (no LD_LIBRARY_PATH, no TT_PLUGIN_PATH): --version, the plugin search
# (its own installed folder, never the build tree), a small render with the installed
# plugins, and the installed Python package. Exit 77 (skip) only when pkg-config or make is
# missing.
#
# Environment (set by tests/meson.build): TT_SOURCE_ROOT, TT_BUILD_ROOT.
set -euo pipefail

fail() { echo "FAIL: $*" >&2; exit 1; }

command -v pkg-config >/dev/null 2>&1 || { echo "SKIP: pkg-config not found"; exit 77; }
command -v make >/dev/null 2>&1 || { echo "SKIP: make not found"; exit 77; }
: "${TT_SOURCE_ROOT:?TT_SOURCE_ROOT not set}" "${TT_BUILD_ROOT:?TT_BUILD_ROOT not set}"
MESON=${MESON:-meson}

# Nothing from the source or build tree may leak in through the compiler's environment.
unset CPATH C_INCLUDE_PATH LIBRARY_PATH PKG_CONFIG_SYSROOT_DIR

tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_sdk.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
stage=$tmp/stage

# 1. Install into the staging dir (the build is up to date: meson test built it).
"$MESON" install -C "$TT_BUILD_ROOT" --destdir "$stage" --no-rebuild >"$tmp/install.log" 2>&1 ||
  { cat "$tmp/install.log" >&2; fail "meson install --destdir failed"; }

pc=$(find "$stage" -name tunetrace.pc -path '*/pkgconfig/*' | head -n 1)
[ -n "$pc" ] || fail "no tunetrace.pc under $stage"
prefix=$(sed -n 's/^prefix=//p' "$pc")
[ -n "$prefix" ] || fail "$pc has no prefix= line"
# The .pc names the final prefix; relocate it into the staging dir. Every other path in the
# file is written relative to ${prefix}, which this override checks too.
export PKG_CONFIG_PATH=$(dirname "$pc")
PKG_CONFIG="pkg-config --define-variable=prefix=$stage$prefix"
$PKG_CONFIG --exists tunetrace || fail "pkg-config cannot find tunetrace in $PKG_CONFIG_PATH"
cflags=$($PKG_CONFIG --cflags tunetrace)
libdir=$($PKG_CONFIG --variable=libdir tunetrace)
plugindir=$($PKG_CONFIG --variable=plugindir tunetrace)
echo "pkg-config: cflags '$cflags' libdir $libdir plugindir $plugindir"
case "$libdir" in "$stage"/*) ;; *) fail "libdir $libdir is not inside the staging dir";; esac
case "$plugindir" in "$stage"/*) ;; *) fail "plugindir $plugindir is not inside the staging dir";; esac
for h in tunetrace.h plugin.h tuner.h predictor.h indicators.h params.h loader.h host.h session.h tuning.h hybrid.h; do
  [ -f "$stage$prefix/include/tunetrace/$h" ] || fail "header tunetrace/$h not installed"
done
example="$stage$prefix/share/tunetrace/examples/tuner_random"
for f in tuner_random.c Makefile README.md; do
  [ -f "$example/$f" ] || fail "the SDK example's $f is not installed in $example"
done
bin="$stage$prefix/bin"
[ -x "$bin/tunetrace" ] || fail "no installed program $bin/tunetrace"
# Debian's /usr/bin/host is the DNS lookup tool: the installed name must not shadow it
[ ! -e "$bin/host" ] || fail "$bin/host is installed (it would shadow Debian's DNS tool)"

# 2. Build and install the example from the installed copy (nothing from the source tree).
cp -r "$example" "$tmp/src"
make -C "$tmp/src" PKG_CONFIG="$PKG_CONFIG" >"$tmp/make.log" 2>&1 ||
  { cat "$tmp/make.log" >&2; fail "make failed"; }
cat "$tmp/make.log"
grep -q -- "-Wall" "$tmp/make.log" || fail "make did not run the compiler"
if grep -qi "warning" "$tmp/make.log"; then fail "the example compiles with warnings"; fi
make -C "$tmp/src" install PKG_CONFIG="$PKG_CONFIG" >"$tmp/install-plugin.log" 2>&1 ||
  { cat "$tmp/install-plugin.log" >&2; fail "make install failed"; }
[ -f "$plugindir/tuner_random.so" ] || fail "make install did not put tuner_random.so in $plugindir"
# Only the entry point is exported.
if command -v nm >/dev/null 2>&1; then
  exported=$(nm -D --defined-only "$tmp/src/tuner_random.so" | awk '$2 ~ /[A-Z]/ {print $3}' | sort)
  [ "$exported" = "tt_plugin_entry" ] || fail "tuner_random.so exports more than tt_plugin_entry: $exported"
fi

# 3. Load it through the installed library's loader API, from a program also built with
#    pkg-config only.
cat >"$tmp/check.c" <<'EOF'
#include <tunetrace/loader.h>
#include <tunetrace/tuner.h>
#include <stdio.h>
#include <string.h>

static void quiet(tt_log_level l, const char *p, const char *f, ...) {}

int main(int argc, char **argv) {
  tt_host host = {.struct_size = sizeof host, .abi_major = TT_ABI_MAJOR,
                  .abi_minor = TT_ABI_MINOR, .host_name = "sdk check", .log = quiet};
  tt_registry *reg = tt_registry_create(&host);
  tt_registry_add_dir(reg, argv[1]);
  tt_loaded_plugin *p;
  if (tt_registry_load(reg, "tuner_random", &p) != TT_OK) {
    fprintf(stderr, "load: %s\n", tt_last_error());
    return 1;
  }
  const tt_tuner_iface *t = tt_loaded_plugin_iface(p);
  const tt_space *space = tt_loaded_plugin_space(p);
  char *json = tt_space_to_json(space);
  printf("loaded %s %s from %s\n%s\n", tt_loaded_plugin_entry(p)->name,
         tt_loaded_plugin_entry(p)->version, tt_loaded_plugin_path(p), json ? json : "(null)");
  tt_free(json);
  /* A few ask/tell rounds over its own settings space as a target. */
  tt_tuner *tu;
  tt_config *c = tt_config_create(space);
  if (t->create(space, NULL, 1, &tu) != TT_OK) return 1;
  for (int k = 0; k < 5; k++) {
    if (t->next(tu, c) != TT_OK || t->feedback(tu, (double)k) != TT_OK) return 1;
  }
  double cost = -1;
  if (t->best(tu, c, &cost) != TT_OK || cost != 0.0) return 1;
  t->destroy(tu);
  tt_config_destroy(c);
  tt_registry_destroy(reg);
  printf("ask/tell ok\n");
  return 0;
}
EOF
# shellcheck disable=SC2046
cc -std=c11 -Wall -Wextra -Wno-unused-parameter -o "$tmp/check" "$tmp/check.c" \
  $($PKG_CONFIG --cflags --libs tunetrace) || fail "cannot build the loader check with pkg-config flags"
LD_LIBRARY_PATH="$libdir" "$tmp/check" "$plugindir" >"$tmp/check.out" 2>&1 || { cat "$tmp/check.out" >&2; fail "loader check failed"; }
cat "$tmp/check.out"
grep -q "loaded tuner_random" "$tmp/check.out" || fail "loader check did not load tuner_random"
grep -q '"samples"' "$tmp/check.out" || fail "tuner_random space lacks \"samples\""
grep -q '"lhs"' "$tmp/check.out" || fail "tuner_random space lacks \"lhs\""
grep -q "ask/tell ok" "$tmp/check.out" || fail "ask/tell rounds failed"

# 3b. The predictor example (examples/predictor_static) the same way: built out of tree with
#     its Makefile, loaded by a pkg-config-built program that trains and queries it through
#     the ABI 1.1 predictor table.
pexample="$stage$prefix/share/tunetrace/examples/predictor_static"
for f in predictor_static.c Makefile README.md; do
  [ -f "$pexample/$f" ] || fail "the SDK predictor example's $f is not installed in $pexample"
done
cp -r "$pexample" "$tmp/psrc"
make -C "$tmp/psrc" PKG_CONFIG="$PKG_CONFIG" >"$tmp/pmake.log" 2>&1 ||
  { cat "$tmp/pmake.log" >&2; fail "make (predictor_static) failed"; }
if grep -qi "warning" "$tmp/pmake.log"; then cat "$tmp/pmake.log" >&2; fail "predictor_static compiles with warnings"; fi
make -C "$tmp/psrc" install PKG_CONFIG="$PKG_CONFIG" >/dev/null 2>&1 || fail "make install (predictor_static) failed"
[ -f "$plugindir/predictor_static.so" ] || fail "predictor_static.so not installed in $plugindir"
if command -v nm >/dev/null 2>&1; then
  exported=$(nm -D --defined-only "$tmp/psrc/predictor_static.so" | awk '$2 ~ /[A-Z]/ {print $3}' | sort)
  [ "$exported" = "tt_plugin_entry" ] || fail "predictor_static.so exports more than tt_plugin_entry: $exported"
fi
cat >"$tmp/pcheck.c" <<'PCHECK'
#include <tunetrace/loader.h>
#include <tunetrace/predictor.h>
#include <math.h>
#include <stdio.h>

static void quiet(tt_log_level l, const char *p, const char *f, ...) {}

int main(int argc, char **argv) {
  tt_host host = {.struct_size = sizeof host, .abi_major = TT_ABI_MAJOR,
                  .abi_minor = TT_ABI_MINOR, .host_name = "sdk check", .log = quiet};
  tt_registry *reg = tt_registry_create(&host);
  tt_registry_add_dir(reg, argv[1]);
  tt_loaded_plugin *lp;
  if (tt_registry_load(reg, "predictor_static", &lp) != TT_OK) {
    fprintf(stderr, "load: %s\n", tt_last_error());
    return 1;
  }
  const tt_predictor_iface *pi = tt_loaded_plugin_iface(lp);
  if (!TT_PREDICTOR_HAS(pi, create_ex) || !TT_PREDICTOR_HAS(pi, predict_ex)) return 2;
  tt_space *t = tt_space_create("target", "1");
  tt_space_add_int(t, "leaf", 1, 32, 8, "leaf size");
  tt_predictor_setup su = {.struct_size = sizeof su, .target = t, .state_dim = 1,
                           .state_space = "sdk", .seed = 1};
  tt_predictor *p;
  if (pi->create_ex(&su, &p) != TT_OK) return 3;
  tt_config *c = tt_config_create(t);
  for (int leaf = 1; leaf <= 32; leaf++)
    for (int s = 0; s < 4; s++) {
      double state = s, cost = 10 + (leaf - 5) * (leaf - 5);
      tt_config_set_number(c, 0, leaf);
      tt_predictor_sample x = {.struct_size = sizeof x, .state = &state, .config = c,
                               .cost = cost, .default_cost = 19};
      if (pi->observe_ex(p, &x, 1, TT_PREDICTOR_ONLINE) != TT_OK) return 4;
    }
  double q0 = 0;
  tt_predictor_query q = {.struct_size = sizeof q, .state = &q0, .default_cost = NAN};
  if (pi->predict_ex(p, &q, c, NULL) != TT_OK) return 5;
  printf("predicted leaf %lld\n", (long long)tt_config_get_int(c, "leaf", -1));
  if (pi->save(p, argv[2]) != TT_OK) return 6;
  pi->destroy(p);
  tt_config_destroy(c);
  tt_space_destroy(t);
  tt_registry_destroy(reg);
  return 0;
}
PCHECK
# shellcheck disable=SC2046
cc -std=c11 -Wall -Wextra -Wno-unused-parameter -o "$tmp/pcheck" "$tmp/pcheck.c" \
  $($PKG_CONFIG --cflags --libs tunetrace) -lm || fail "cannot build the predictor check with pkg-config flags"
LD_LIBRARY_PATH="$libdir" "$tmp/pcheck" "$plugindir" "$tmp/static.model" >"$tmp/pcheck.out" 2>&1 ||
  { cat "$tmp/pcheck.out" >&2; fail "predictor check failed"; }
cat "$tmp/pcheck.out"
grep -q "predicted leaf 5" "$tmp/pcheck.out" || fail "predictor_static did not answer the best static leaf size"
grep -q "^predictor_static 1" "$tmp/static.model" || fail "predictor_static wrote no versioned model file"

# 4. The installed program from a clean environment: no LD_LIBRARY_PATH (its RUNPATH finds
#    the library), no TT_PLUGIN_PATH (the library finds its installed plugins beside itself).
clean() { env -i PATH=/usr/bin:/bin HOME="$tmp/home" "$@"; }
tunetrace="$bin/tunetrace"
if command -v readelf >/dev/null 2>&1; then
  readelf -d "$tunetrace" | grep -Eq 'RUNPATH.*\$ORIGIN' || fail "$tunetrace has no \$ORIGIN RUNPATH"
fi
clean "$tunetrace" --version >"$tmp/version.out" 2>&1 || { cat "$tmp/version.out" >&2; fail "tunetrace --version failed"; }
cat "$tmp/version.out"
grep -q "tunetrace host $($PKG_CONFIG --modversion tunetrace)" "$tmp/version.out" ||
  fail "tunetrace --version does not print the installed version"
clean "$tunetrace" --list-plugins >"$tmp/list.out" 2>&1 || { cat "$tmp/list.out" >&2; fail "tunetrace --list-plugins failed"; }
cat "$tmp/list.out"
for p in accel_embree integrator_pt tuner_nm tuner_random predictor_nn predictor_rbf predictor_static; do
  grep -q "^$p .*$plugindir/$p.so" "$tmp/list.out" || fail "tunetrace --list-plugins does not find the installed $p in $plugindir"
done
if grep "search path" "$tmp/list.out" | grep -qF "$TT_BUILD_ROOT"; then
  fail "the installed library searches the build tree: $(grep 'search path' "$tmp/list.out")"
fi
clean "$tunetrace" --describe tuner_random >"$tmp/describe.out" 2>"$tmp/describe.err" ||
  { cat "$tmp/describe.out" "$tmp/describe.err" >&2; fail "tunetrace --describe tuner_random failed"; }
grep -q '"samples"' "$tmp/describe.out" || fail "tunetrace --describe does not print the space"
clean "$tunetrace" --describe predictor_static >"$tmp/pdescribe.out" 2>&1 ||
  { cat "$tmp/pdescribe.out" >&2; fail "tunetrace --describe predictor_static failed"; }
grep -q '"minShare"' "$tmp/pdescribe.out" || fail "tunetrace --describe predictor_static does not print its space"
# the installed SDK READMEs' commands, as written (they name the installed program)
readme_cmds=0
for readme in "$example/README.md" "$stage$prefix/share/tunetrace/examples/predictor_static/README.md"; do
  while IFS= read -r line; do
    cmd=${line%%#*}
    read -r -a words <<<"$cmd"
    clean "$bin/${words[0]}" "${words[@]:1}" >"$tmp/readme.out" 2>&1 ||
      { cat "$tmp/readme.out" >&2; fail "$readme: '$cmd' failed"; }
    readme_cmds=$((readme_cmds + 1))
  done < <(grep -E '^tunetrace ' "$readme")
done
[ "$readme_cmds" -ge 3 ] || fail "the installed SDK READMEs show $readme_cmds tunetrace commands, expected 3"
# the program names itself as it was installed, in its usage line and its messages
clean "$tunetrace" --help >"$tmp/help.out" 2>&1 || fail "tunetrace --help failed"
grep -q "^usage: tunetrace " "$tmp/help.out" || fail "tunetrace --help: $(head -n 1 "$tmp/help.out")"
rc=0
clean "$tunetrace" --outfile x.exr >"$tmp/bad.out" 2>&1 || rc=$?
[ "$rc" = 2 ] && grep -q '^tunetrace: unknown option "--outfile"; did you mean --out?' "$tmp/bad.out" ||
  { cat "$tmp/bad.out" >&2; fail "tunetrace --outfile: exit $rc"; }
# a small render, with a short exploration by the installed third-party tuner
scene="$TT_SOURCE_ROOT/scenes/cornell-box/scene.json"
clean "$tunetrace" --quiet --res 16x16 --spp 2 --plugin tuner_random --iterations 2 --no-db \
  --stats "$tmp/render.json" --out "$tmp/render.exr" "$scene" >"$tmp/render.out" 2>&1 ||
  { cat "$tmp/render.out" >&2; fail "a render with the installed program failed"; }
[ -s "$tmp/render.exr" ] && [ -s "$tmp/render.png" ] || fail "the installed program wrote no image"
used=$(grep -o '"path":[^,}]*' "$tmp/render.json")
[ -n "$used" ] || fail "the run record names no plugin path"
if echo "$used" | grep -vqF "$plugindir/"; then fail "the render used plugins outside $plugindir: $used"; fi
echo "render: ok, plugins $(echo "$used" | tr '\n' ' ')"

# 5. The installed Python package, from the same clean environment.
pydir=$(find "$stage$prefix" -type d -name tunetrace -path '*/dist-packages/*' | head -n 1)
[ -n "$pydir" ] && [ -f "$pydir/__init__.py" ] && [ -f "$pydir/_paths.py" ] ||
  fail "the Python package is not installed under $stage$prefix"
cat >"$tmp/api.py" <<'PY'
import sys
import tunetrace as tt
stage, plugindir, scene = sys.argv[1:]
assert tt.library_path().startswith(stage), f"loaded {tt.library_path()}, not the installed library"
with tt.Session(scene, resolution=(8, 8), seed=3) as s:
    img = s.render(spp=2)
    paths = [p["path"] for p in s.plugins]
assert img.shape == (8, 8, 3) and img.mean() > 0, img.shape
assert all(p.startswith(plugindir + "/") for p in paths), f"plugins outside the install: {paths}"
names = [p["name"] for p in tt.list_plugins()]
assert "tuner_random" in names, names
print("python:", tt.version(), tt.library_path(), paths)
PY
clean PYTHONPATH="$(dirname "$pydir")" /usr/bin/python3 "$tmp/api.py" "$stage" "$plugindir" "$scene" \
  >"$tmp/python.out" 2>&1 || { cat "$tmp/python.out" >&2; fail "the installed Python API failed"; }
cat "$tmp/python.out"
echo "sdk_out_of_tree: ok"
