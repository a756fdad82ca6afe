#!/usr/bin/env bash
# The main job: installs the Debian packages, builds envpis in Release and runs the default
# demonstration, writing its outputs under out/ (override with OUT=dir).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
BUILD=${BUILD:-build}
OUT=${OUT:-out}
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DENVPIS_BUILD_TESTS=OFF -DENVPIS_BUILD_BENCH=OFF
cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
ENV_MAP=${ENV_MAP:-/usr/share/blender/datafiles/studiolights/world/sunset.exr}
"$BUILD/apps/envpis/envpis" table --env "$ENV_MAP" --out "$OUT/table"
echo "envpis: importance table images written to $OUT/table/"
