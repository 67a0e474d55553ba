#!/usr/bin/env bash
# Renders the same scenes with a fixed seed at two commits and compares the images byte for
# byte (cmp). A refactor that must not change behaviour (issue #14) passes when every image
# is identical. The EXR and PNG files carry the render time and date, so what is compared is
# each file's pixels in their stored format plus every other metadata field, dumped by
# OpenImageIO (/usr/bin/python3) into a .pixels file.
#
#   tools/check_bit_identical.sh [OLD_REV [NEW_REV]]      (defaults: main, HEAD)
#
# Each revision is exported with `git archive` into $TT_BITCHECK_DIR (default
# /tmp/tt-bitcheck/<commit>) and built there once (cached across runs); the scenes are the
# default scene (path tracer, PSSMLT, and PSSMLT tuned by tuner_nm towards its acceptance
# target: a timing-free objective, so the tuning loop's whole trajectory shows in the
# image), two pbrt-v4 scenes from ../shared/scenes and one scene.json wrapper that imports a
# pbrt file (../shared, or $TT_SHARED, is linked beside each exported tree). Exit status 0 when all images match, 1 when any differs, 2 on a build
# or render failure.
set -uo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
old=$(git rev-parse --verify "${1:-main}^{commit}") || exit 2
new=$(git rev-parse --verify "${2:-HEAD}^{commit}") || exit 2
root=${TT_BITCHECK_DIR:-/tmp/tt-bitcheck}
shared=$(cd "${TT_SHARED:-$repo/../shared}" && pwd) || exit 2
jobs=${TT_BITCHECK_JOBS:-2}

build_rev() {  # rev -> prints the build folder
  local sha dir
  sha=$(git rev-parse --verify "$1^{commit}") || return 1
  dir=$root/$sha
  if [ ! -f "$dir/build/build.ninja" ]; then
    rm -rf "$dir" && mkdir -p "$dir/src" || return 1
    git archive "$sha" | tar -x -C "$dir/src" || return 1
    ln -s "$shared" "$dir/shared" || return 1  # scenes reach ../shared from the tree's root
    meson setup "$dir/build" "$dir/src" >"$dir/setup.log" 2>&1 || {
      echo "meson setup of $1 ($sha) failed: see $dir/setup.log" >&2
      return 1
    }
  fi
  ninja -C "$dir/build" -j "$jobs" host/host plugins/accel_embree/accel_embree.so \
    plugins/integrator_pt/integrator_pt.so plugins/integrator_pssmlt/integrator_pssmlt.so \
    plugins/tuner_nm/tuner_nm.so >"$dir/build.log" 2>&1 || {
    echo "build of $1 ($sha) failed: see $dir/build.log" >&2
    return 1
  }
  echo "$dir/build"
}

# name | host arguments (scene paths relative to the repository root)
cases=(
  "cornell-pt|--plugin integrator_pt --spp 16 --res 96x96 --seed 7 scenes/cornell-box/scene.json"
  "cornell-pssmlt|--plugin integrator_pssmlt --spp 8 --res 96x96 --seed 11 scenes/cornell-box/scene.json"
  "cornell-pssmlt-tuned|--plugin integrator_pssmlt --plugin tuner_nm --iterations 8 --spp 12 --res 64x64 --seed 13 scenes/cornell-box/scene.json"
  "killeroo-pbrt|--plugin integrator_pt --spp 8 --res 96x96 --seed 3 ../shared/scenes/killeroos/killeroo-simple.pbrt"
  "cornell-pbrt|--plugin integrator_pt --spp 8 --res 96x96 --seed 5 ../shared/scenes/cornell-box-pbrt/cornell-box-specular.pbrt"
  "veach-mis-json|--plugin integrator_pt --spp 8 --res 96x72 --seed 9 scenes/veach-mis/scene.json"
)

dump_pixels() {  # image -> image.pixels: pixel bytes + metadata without time and date
  /usr/bin/python3 - "$1" <<'PY'
import sys
import OpenImageIO as oiio
path = sys.argv[1]
inp = oiio.ImageInput.open(path)
if inp is None:
    sys.exit(f"{path}: {oiio.geterror()}")
spec = inp.spec()
px = inp.read_image(spec.format)
inp.close()
if px is None:
    sys.exit(f"{path}: cannot read the pixels")
skip = {"DateTime", "tunetrace:render_ms", "render_ms"}
meta = [f"{a.name}={a.value}" for a in spec.extra_attribs if a.name not in skip]
with open(path + ".pixels", "wb") as f:
    f.write(f"{spec.width}x{spec.height}x{spec.nchannels} {spec.format}\n".encode())
    f.write(("\n".join(meta) + "\n").encode())
    f.write(px.tobytes())
PY
}

render_all() {  # build_dir src_dir out_dir
  local b=$1 src=$2 out=$3 c name args
  mkdir -p "$out"
  for c in "${cases[@]}"; do
    name=${c%%|*}; args=${c#*|}
    # shellcheck disable=SC2086  # args are split on purpose
    (cd "$src" && TT_PLUGIN_PATH="" "$b/host/host" --quiet --threads 2 --no-db $args \
      --out "$out/$name.exr") >"$out/$name.log" 2>&1 || {
      echo "render $name failed with $b: see $out/$name.log" >&2
      return 1
    }
    dump_pixels "$out/$name.exr" && dump_pixels "$out/$name.png" || return 1
  done
}

ob=$(build_rev "$old") || exit 2
nb=$(build_rev "$new") || exit 2
o_out=$(mktemp -d) && n_out=$(mktemp -d) || exit 2
trap 'rm -rf "$o_out" "$n_out"' EXIT
render_all "$ob" "$(dirname "$ob")/src" "$o_out" || exit 2
render_all "$nb" "$(dirname "$nb")/src" "$n_out" || exit 2
status=0
for c in "${cases[@]}"; do
  name=${c%%|*}
  for ext in exr png; do
    if cmp -s "$o_out/$name.$ext.pixels" "$n_out/$name.$ext.pixels"; then
      echo "identical  $name.$ext"
    else
      echo "DIFFERENT  $name.$ext"; status=1
    fi
  done
done
echo "old $(git rev-parse --short "$old") new $(git rev-parse --short "$new"): \
$([ $status = 0 ] && echo all images bit-identical || echo images differ)"
exit $status
