#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The shared set-up of the Cycles side-by-sides (scripts/cycles-compare.sh, scripts/cycles-assets.sh):
#
#   scripts/cycles-run.sh NAME PYTHON_SCRIPT [--install] [options of PYTHON_SCRIPT]
#
# Blender is large and CI never needs it, so it is installed only when asked: --install or CYCLES_INSTALL=1
# (apt-get install --no-install-recommends blender, as root or with sudo). Without it and without Blender,
# the script says so on one line and exits 1. BUILD (default build) is the envpis build directory: the
# script builds envpis_cmd there if the binary is missing. Then it runs PYTHON_SCRIPT with --envpis and
# --blender set, under Debian's python3 (ENVPIS_PYTHON overrides).
set -euo pipefail
cd "$(dirname "$0")/.."
name=$1
script=$2
shift 2

install=${CYCLES_INSTALL:-0}
args=()
for a in "$@"; do
  if [ "$a" = --install ]; then install=1; else args+=("$a"); fi
done

if [ "$install" = 1 ] && ! command -v blender >/dev/null 2>&1; then
  SUDO=""
  [ "$(id -u)" = 0 ] || SUDO=sudo
  echo "$name: installing blender (apt-get install --no-install-recommends blender)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends blender
fi
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null 2>&1; then
  echo "$name: error: blender is not installed ('$BLENDER' not found); run with --install (or CYCLES_INSTALL=1) to apt-get it" >&2
  exit 1
fi
if ! command -v oiiotool >/dev/null 2>&1; then
  echo "$name: error: oiiotool is missing (Debian: apt-get install openimageio-tools)" >&2
  exit 1
fi
# Debian's python3, where python3-numpy lives (Blender depends on it).
PY=${ENVPIS_PYTHON:-/usr/bin/python3}
[ -x "$PY" ] || PY=python3

BUILD=${BUILD:-build}
ENVPIS="$BUILD/apps/envpis/envpis"
if [ ! -x "$ENVPIS" ]; then
  echo "$name: building envpis in $BUILD"
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
fi

exec "$PY" "$script" --envpis "$ENVPIS" --blender "$BLENDER" ${args[@]+"${args[@]}"}
