#!/usr/bin/env bash
# The README's install commands ("## Installing"), read from README.md and run as written
# from the repository root, with $HOME a temporary folder: they reconfigure build/ for the
# prefix $HOME/.local, install it, and pip-install ./python into a venv there. Then, from a
# clean environment, the installed pieces are used from that prefix alone:
#   - the program `tunetrace` (--version, --list-plugins finds the installed plugins only,
#     a small render);
#   - pkg-config: libdir and plugindir inside the prefix, and a program built with
#     `pkg-config --cflags --libs tunetrace` that loads an installed plugin;
#   - the Python package `meson install` put in PREFIX/lib/python3/dist-packages and the one
#     pip put in the venv: both load the prefix's libtunetrace and render; the pip package's
#     version is the library's.
# build/ gets its prefix back afterwards (a trap; only loader.c and the install paths depend
# on it). The test runs alone (is_parallel: false in python/tests/meson.build): it rebuilds
# the library twice. Exit 77 when this build is not the README's build/.
#
# Environment (set by tests/meson.build): TT_SOURCE_ROOT, TT_BUILD_ROOT.
set -euo pipefail
fail() { echo "FAIL: $*" >&2; exit 1; }
: "${TT_SOURCE_ROOT:?}" "${TT_BUILD_ROOT:?}"
src=$(realpath "$TT_SOURCE_ROOT")
if [ "$(realpath "$TT_BUILD_ROOT")" != "$src/build" ]; then
  echo "SKIP: the README's commands name build/; this build is $TT_BUILD_ROOT"
  exit 77
fi
block=$(awk '/^## Installing/ { f = 1 } f && /^```sh/ { g = 1; next } g && /^```/ { exit } g { print }' \
  "$src/README.md")
grep -q 'meson install -C build' <<<"$block" || fail "no install command under ## Installing: $block"

py_opt() {  # one build option's value
  meson introspect "$src/build" --buildoptions |
    /usr/bin/python3 -c "import json, sys; print({o['name']: o['value'] for o in json.load(sys.stdin)}['$1'])"
}
old_prefix=$(py_opt prefix)
tmp=$(mktemp -d "${TMPDIR:-/tmp}/tt_readme_install.XXXXXX")
restore() {
  meson configure "$src/build" --prefix "$old_prefix" >/dev/null 2>&1 || echo "FAIL: restoring the prefix $old_prefix of build/" >&2
  ninja -C "$src/build" >/dev/null 2>&1 || echo "FAIL: rebuilding build/ for the prefix $old_prefix" >&2
  rm -rf "$tmp"
}
trap restore EXIT

export HOME=$tmp/home
mkdir -p "$HOME"
echo "readme_install: running, from $src, with HOME=$HOME:"
echo "$block"
(cd "$src" && bash -euo pipefail -c "$block") >"$tmp/install.log" 2>&1 ||
  { tail -n 40 "$tmp/install.log" >&2; fail "the README's install commands failed"; }
prefix=$HOME/.local
[ "$(py_opt prefix)" = "$prefix" ] || fail "build/ has prefix $(py_opt prefix), not $prefix"
version=$(sed -n "s/^  version : '\(.*\)',/\1/p" "$src/meson.build" | head -n 1)
grep -q " $version (plugin ABI" "$tmp/install.log" ||
  fail "tunetrace --version did not print version $version: $(grep -i abi "$tmp/install.log" | head -n 3)"

# From here on nothing from the source or build tree may be found by accident.
clean() { env -i PATH=/usr/bin:/bin HOME="$HOME" "$@"; }
bin=$prefix/bin/tunetrace
[ -x "$bin" ] || fail "no $bin"
plugins=$(cd "$tmp" && clean "$bin" --list-plugins 2>/dev/null)
grep -q "accel_embree .*$prefix/lib/" <<<"$plugins" || fail "installed plugins not listed from $prefix: $plugins"
if grep -q "$src" <<<"$plugins"; then fail "the installed program lists plugins from the source tree: $plugins"; fi
(cd "$tmp" && clean "$bin" --quiet --no-db --res 16x16 --spp 2 --out "$tmp/box.exr" \
  "$src/scenes/cornell-box/scene.json") || fail "the installed program cannot render"
[ -s "$tmp/box.exr" ] || fail "no image from the installed program"

pcdir=$prefix/lib/$(gcc -print-multiarch)/pkgconfig
pc() { clean PKG_CONFIG_PATH="$pcdir" pkg-config "$@" tunetrace; }
libdir=$(pc --variable=libdir) && plugindir=$(pc --variable=plugindir) || fail "pkg-config: no tunetrace in $pcdir"
case "$libdir:$plugindir" in "$prefix"/*:"$prefix"/*) ;; *) fail "pkg-config: libdir $libdir, plugindir $plugindir";; esac
cat >"$tmp/load.c" <<'EOF'
#include <tunetrace/loader.h>
#include <stdio.h>
int main(void) {
  tt_registry *reg = tt_registry_create(tt_default_host());
  tt_loaded_plugin *p = NULL;
  if (tt_registry_load(reg, "integrator_pt", &p) != TT_OK) {
    fprintf(stderr, "%s\n", tt_last_error());
    return 1;
  }
  printf("%s\n", tt_loaded_plugin_path(p));
  tt_registry_destroy(reg);
  return 0;
}
EOF
# shellcheck disable=SC2046
gcc -o "$tmp/load" "$tmp/load.c" $(pc --cflags --libs) -Wl,-rpath,"$libdir" ||
  fail "a program built with pkg-config does not compile"
loaded=$(clean "$tmp/load") || fail "the pkg-config program cannot load integrator_pt"
case "$loaded" in "$plugindir"/*) ;; *) fail "integrator_pt loaded from $loaded, not $plugindir";; esac

render_py='
import os, sys, tunetrace as tt
prefix = sys.argv[1]
assert tt.library_path().startswith(prefix), tt.library_path()
assert os.path.realpath(tt.__file__).startswith(os.path.realpath(sys.argv[2])), tt.__file__
with tt.Session(sys.argv[3], resolution=(8, 8), seed=3) as s:
    img = s.render(spp=2)
assert img.shape == (8, 8, 3) and float(img.mean()) > 0, img.mean()
if len(sys.argv) > 4:
    from importlib.metadata import version
    assert version("tunetrace") == tt.__version__, (version("tunetrace"), tt.__version__)
print("python:", tt.__file__, tt.library_path(), tt.__version__)
'
site=$prefix/lib/python3/dist-packages
clean PYTHONPATH="$site" /usr/bin/python3 -c "$render_py" "$prefix" "$site" \
  "$src/scenes/cornell-box/scene.json" || fail "the Python package meson installed"
venv=$prefix/venvs/tunetrace
[ -x "$venv/bin/python" ] || fail "no venv at $venv"
clean "$venv/bin/python" -c "$render_py" "$prefix" "$venv" "$src/scenes/cornell-box/scene.json" \
  metadata || fail "the Python package pip installed"
echo "readme_install: ok"
