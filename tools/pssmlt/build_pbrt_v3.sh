#!/usr/bin/env bash
# Builds pbrt-v3 (github.com/mmp/pbrt-v3, tested at 13d871f) for the side-by-side anchor
# (tools/pssmlt/pbrt_v3_anchor.py) without its git submodules, against Debian's OpenEXR 3,
# Imath and glog (bash tools/bootstrap.sh --peers installs libopenexr-dev libgoogle-glog-dev) and without Ptex (no
# Debian package: api.cpp's two ptex texture constructors are replaced by an error). One
# file at a time with the configuration defines pbrt-v3's CMake sets on Linux; resumable.
#
#   git clone https://github.com/mmp/pbrt-v3 /tmp/pbrt-v3   # no --recursive needed
#   bash tools/pssmlt/build_pbrt_v3.sh /tmp/pbrt-v3          # -> /tmp/pbrt-v3/pbrt
set -uo pipefail
src=$(cd "${1:?usage: build_pbrt_v3.sh PBRT_V3_CHECKOUT}" && pwd)/src
obj="$src/../obj"
mkdir -p "$obj"
cd "$src"
sed -i 's|#include "textures/ptex.h"|/* ptex: not built (no Debian package) */|; s|tex = CreatePtexFloatTexture(tex2world, tp);|Error("ptex textures are not supported in this build");|; s|tex = CreatePtexSpectrumTexture(tex2world, tp);|Error("ptex textures are not supported in this build");|' core/api.cpp
FLAGS="-O2 -std=gnu++11 -DNDEBUG -DPBRT_CONSTEXPR=constexpr -DPBRT_HAVE_OPENEXR -DPBRT_HAVE_ALIGNAS
 -DPBRT_THREAD_LOCAL=thread_local -DPBRT_HAVE_POSIX_MEMALIGN -DPBRT_HAVE_CONSTEXPR
 -DPBRT_HAVE_HEX_FP_CONSTANTS -DPBRT_HAVE_BINARY_CONSTANTS -DPBRT_HAVE_ITIMER -DPBRT_IS_LINUX
 -DPBRT_HAVE_NONPOD_IN_UNIONS -DPBRT_NOINLINE= -DPBRT_HAVE_MMAP -I. -Icore -Iext
 -I/usr/include/OpenEXR -I/usr/include/Imath -w"
fail=0
for f in $(find . -name "*.cpp" -not -path "./tests/*" -not -path "./tools/*" -not -name "ptex.cpp" \
             -not -path "./ext/*/*"; find ./ext -maxdepth 1 -name "*.c"); do
  o="$obj/$(echo "$f" | sed 's|^\./||; s|/|_|g').o"
  [ -f "$o" ] && continue
  case $f in
    *.c) cc -O2 -w -I. -Iext -c "$f" -o "$o" || { echo "FAIL $f"; fail=1; } ;;
    *) g++ $FLAGS -c "$f" -o "$o" || { echo "FAIL $f"; fail=1; } ;;
  esac
done
[ $fail = 0 ] || exit 1
g++ -o "$src/../pbrt" "$obj"/*.o -lOpenEXR-3_1 -lImath-3_1 -lIex-3_1 -lIlmThread-3_1 -lglog -lz -lpthread &&
  echo "built $src/../pbrt"
