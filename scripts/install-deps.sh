#!/usr/bin/env bash
# Installs every Debian 12 package envpis needs to build, test, benchmark and render.
# Idempotent: packages already present are left alone. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  # toolchain
  build-essential cmake ninja-build pkg-config git ca-certificates
  clang libclang-rt-14-dev
  # libraries (see DESIGN.md section 6)
  libopenimageio-dev openimageio-tools libembree-dev libtbb-dev libhwy-dev
  libcli11-dev nlohmann-json3-dev libboost-math-dev libassimp-dev
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # real HDR environment maps (CC0): /usr/share/blender/datafiles/studiolights/world/*.exr
  blender-data
  # report plots and the browser test
  python3 python3-matplotlib python3-numpy chromium
)

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
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
