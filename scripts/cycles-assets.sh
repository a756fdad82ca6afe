#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Cycles (Debian's Blender 3.4) side by side with envpis on the glTF asset scenes (scenes/assets-*.json):
# each renderer against its own converged reference, at equal time, per object and over the image. See
# docs/cycles.md, "The asset scenes", for the matched settings and what cannot match.
#
#   scripts/cycles-assets.sh [--install] [options of scripts/cycles_assets.py]
#   scripts/cycles-assets.sh --help
#
# As scripts/cycles-compare.sh: --install (or CYCLES_INSTALL=1) apt-gets Blender when it is missing,
# otherwise a missing Blender is one line and exit status 1; BUILD (default build) is the envpis build
# directory (envpis_cmd is built there if missing). The scenes' models come from Debian's
# assimp-testmodels and scripts/fetch-assets.sh (ENVPIS_ASSETS, ENVPIS_ASSIMP_MODELS as envpis reads
# them). Results go to out/cycles-assets/ (git-ignored) unless --out says otherwise.
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
  echo "cycles-assets: installing blender (apt-get install --no-install-recommends blender)"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y --no-install-recommends blender
fi
BLENDER=${BLENDER:-blender}
if ! command -v "$BLENDER" >/dev/null 2>&1; then
  echo "cycles-assets: error: blender is not installed ('$BLENDER' not found); run with --install (or CYCLES_INSTALL=1) to apt-get it" >&2
  exit 1
fi
for tool in oiiotool; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "cycles-assets: error: $tool is missing (Debian: apt-get install openimageio-tools)" >&2
    exit 1
  fi
done
# Debian's python3, where python3-numpy lives (Blender depends on it); ENVPIS_PYTHON overrides.
PY=${ENVPIS_PYTHON:-/usr/bin/python3}
[ -x "$PY" ] || PY=python3

BUILD=${BUILD:-build}
ENVPIS="$BUILD/apps/envpis/envpis"
if [ ! -x "$ENVPIS" ]; then
  echo "cycles-assets: building envpis in $BUILD"
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
fi

exec "$PY" scripts/cycles_assets.py --envpis "$ENVPIS" --blender "$BLENDER" ${args[@]+"${args[@]}"}
