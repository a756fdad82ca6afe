#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cycles (Debian's Blender 3.4) side by side with envpis on matched sphere scenes: each renderer against its
# own converged reference, at equal time. See docs/cycles.md for the matched settings and the conventions.
#
#   scripts/cycles-compare.sh [--install] [options of scripts/cycles_compare.py]
#   scripts/cycles-compare.sh --help
#
# Blender is large and CI never needs it, so it is installed only when asked: --install or CYCLES_INSTALL=1
# (apt-get install --no-install-recommends blender, as root or with sudo). Without it and without Blender,
# the script says so on one line and exits 1. BUILD (default build) is the envpis build directory: the
# script builds envpis_cmd there if the binary is missing. Results go to out/cycles-compare/ (git-ignored)
# unless --out says otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."

install=${CYCLES_INSTALL:-0}
args=()
for a in "$@"; do
  if [ "$a" = --install ]; then install=1; else args+=("$a"); fi
done

if [ "$install" = 1 ] && ! command -v blender >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" = 0 ] || SUDO=sudo
  echo "cycles-compare: installing blender (apt-get install --no-install-recommends blender)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends blender
fi
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null 2>&1; then
  echo "cycles-compare: error: blender is not installed ('$BLENDER' not found); run with --install (or CYCLES_INSTALL=1) to apt-get it" >&2
  exit 1
fi
for tool in oiiotool; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "cycles-compare: error: $tool is missing (Debian: apt-get install openimageio-tools)" >&2
    exit 1
  fi
done
# Debian's python3, where python3-numpy lives (Blender depends on it); ENVPIS_PYTHON overrides.
PY=${ENVPIS_PYTHON:-/usr/bin/python3}
[ -x "$PY" ] || PY=python3

BUILD=${BUILD:-build}
ENVPIS="$BUILD/apps/envpis/envpis"
if [ ! -x "$ENVPIS" ]; then
  echo "cycles-compare: building envpis in $BUILD"
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
fi

exec "$PY" scripts/cycles_compare.py --envpis "$ENVPIS" --blender "$BLENDER" ${args[@]+"${args[@]}"}
