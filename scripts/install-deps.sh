#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Installs every Debian 12 package envpis needs to build, test, benchmark and render.
# Idempotent: packages already present are left alone. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  clang libclang-rt-14-dev
  # llvm-symbolizer: clang's sanitizer runtime symbolizes reports with it (scripts/fuzz.sh needs them)
  llvm
  # libraries (see DESIGN.md section 6)
  libopenimageio-dev libopenexr-dev openimageio-tools libembree-dev libtbb-dev libhwy-dev
  libcli11-dev nlohmann-json3-dev libboost-math-dev libassimp-dev libpng-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # real HDR environment maps (CC0): /usr/share/blender/datafiles/studiolights/world/*.exr
  blender-data
  # glTF 2.0 models of the asset scenes and broken glTF files for the tests (docs/assets.md)
  assimp-testmodels
  # report plots and the browser test
  python3 python3-matplotlib python3-numpy chromium
  # the Python module (python/) and its tests
  python3-dev pybind11-dev python3-pybind11 python3-pytest
)

# The report's browser test drives chromium with playwright-core from npm: Debian's node and npm unless
# the machine already has a node (this workplace's images ship node 20 and npm 11 outside apt).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  PACKAGES+=(nodejs npm)
fi

SUDO=""
if [ "$(id -u)" != 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages already installed"
else
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -q
  $SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# The asset scenes' models and HDRIs from npm (@pmndrs/assets), decoded into a cache outside the tree.
"$(dirname "$0")/fetch-assets.sh"
