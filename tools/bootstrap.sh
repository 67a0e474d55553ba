#!/usr/bin/env bash
# Installs tunetrace's build dependencies from Debian 12 packages (when missing) and
# builds into ./build. Safe to run again: it only installs what is missing and rebuilds.
#   tools/bootstrap.sh             build + test dependencies (what CI and the README need)
#   tools/bootstrap.sh --training  the same (kept for old instructions: PyTorch for
#                                  tools/taa/train.py is now in PACKAGES)
#   tools/bootstrap.sh --peers     also PEER_PACKAGES: what the comparisons with other
#                                  renderers need (benchmarks, not tests)
set -euo pipefail
cd "$(dirname "$0")/.."
peers=0
for a in "$@"; do
  case $a in
    --training) ;;  # accepted: PACKAGES has everything now
    --peers) peers=1 ;;
    *) echo "bootstrap: unknown option $a (expected --training or --peers)" >&2; exit 2 ;;
  esac
done

PACKAGES=(
  meson ninja-build pkg-config gcc g++ make   # build tools
  libembree-dev                               # ray/triangle intersection, BVH builders
  libopenimageio-dev                          # EXR/PNG read and write
  libopencolorio-dev                          # display transform for PNG
  libcjson-dev                                # scene.json, parameter spaces, run records
  libassimp-dev                               # OBJ/PLY/glTF mesh import
  assimp-testmodels                           # glTF-Sample-Models' simple_skin, AnimatedMorphCube:
                                              # core/tests/gltf_anim.c, gltf_anim_render.c
  libsqlite3-dev                              # tuning database
  zlib1g-dev                                  # .ply.gz meshes in the pbrt importer
  python3-matplotlib                          # tools/tuning/ charts (tools/tests/tune_plot.sh)
  python3-numpy python3-openimageio           # tools/scenes/ generators (tools/tests/scenes_generate.sh)
  python3-numpy python3-scipy                 # tools/tuning/analyze.py (tools/tests/tune_analyze.sh)
  python3-numpy                               # the Python API's arrays (python/tests/python_api.py)
  python3-mesonpy python3-venv python3-pip    # pip install ./python (README "Installing",
                                              # python/tests/readme_install.sh)
  clang libclang-rt-14-dev                    # the ASan+UBSan build and the libFuzzer harnesses
                                              # (tools/test_sanitized.sh, tests/fuzz; .ci/run)
  llvm-14                                     # llvm-symbolizer: sanitizer reports with lines
  clang-format-14                             # the tree's one layout (tools/tests/code_format.sh)
  openmpi-bin libopenmpi-dev                  # mpi/ tunetrace-mpi (meson -Dmpi=auto finds it);
                                              # mpi/tests/mpi_driver.sh, mpi_baseline.sh, tools/mpi/
  python3-torch                               # tools/taa/ training, CPU (train.py, ablations.py,
                                              # eval_torch.py; tools/tests/taa_train.sh)
  chromium                                    # a real headless browser for the results page:
                                              # tools/evidence/check_page.py (tools/tests/evidence.sh)
)

PEER_PACKAGES=(
  blender                                     # Cycles references: tools/cycles/ (cycles_reference.py);
                                              # tools/scenes/blender_skinned.py (benchmark glTF)
  libopenexr-dev libgoogle-glog-dev           # pbrt-v3 built as the chapter-4 anchor:
                                              # tools/pssmlt/build_pbrt_v3.sh
)
[ "$peers" -eq 1 ] && PACKAGES+=("${PEER_PACKAGES[@]}")

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ "${#missing[@]}" -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  echo "bootstrap: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [ ! -f build/build.ninja ]; then
  meson setup build
fi
ninja -C build
