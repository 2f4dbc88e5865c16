#!/usr/bin/env bash
# One command from a fresh Debian 12 machine to a rendered picture:
# installs the build and runtime packages, builds opsila in ./build, and
# renders the default scene to ./out/default.png.
#   tools/setup.sh            (as root, or with sudo available)
#   OPSILA_NO_APT=1 tools/setup.sh   (packages already installed)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake pkg-config
  ocl-icd-opencl-dev opencl-headers opencl-clhpp-headers pocl-opencl-icd clinfo
  libstb-dev libtinyobjloader-dev nlohmann-json3-dev libassimp-dev zlib1g-dev libopenexr-dev
  libgtest-dev googletest
  libopenmpi-dev openmpi-bin
  libembree-dev mesa-opencl-icd
  universal-ctags
  assimp-testmodels python3-matplotlib python3-numpy
)

if [[ "${OPSILA_NO_APT:-0}" != 1 ]]; then
  SUDO=""
  if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "setup: run as root or install sudo" >&2; exit 1; }
    SUDO="sudo"
  fi
  missing=()
  for p in "${PACKAGES[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed" || missing+=("$p")
  done
  if ((${#missing[@]})); then
    echo "setup: installing ${missing[*]}"
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  fi
fi

export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/build/pocl-cache}"
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
mkdir -p out
./build/opsila render scenes/default.json -o out/default.png --stats out/default.json
echo "setup: wrote out/default.png"
