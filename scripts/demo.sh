#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The main job: installs the Debian packages, builds the envpis command in Release and runs the default
# comparison: fig1 (eight spheres, GGX roughness 0.02 to 0.5, diffuse, glass) under blender-data's
# sunset.exr, direct lighting, strategies mis, mis-comp, product and oracle at equal spp and at equal
# time, and the exact variance analysis at 2 shading points per object (compare's default; about 10-20 s
# of it). Writes OUT/compare/ (override OUT=dir): metrics.json, images/, plots/ and the report index.html.
# About 1.5 minutes on 2 free cores after the build (BENCHMARKS.md, "The main job": 92 s measured cold
# at 50247c3, with the oracle's batched prepare and fused BSDF evaluation); the reference
# is cached under ~/.cache/envpis/references (or $ENVPIS_CACHE_DIR), so a second run is faster.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
BUILD=${BUILD:-build}
OUT=${OUT:-out}
start=$(date +%s)
cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DENVPIS_BUILD_TESTS=OFF -DENVPIS_BUILD_BENCH=OFF
cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
ENV_MAP=${ENV_MAP:-/usr/share/blender/datafiles/studiolights/world/sunset.exr}
# 384x64 (half of fig1's 768x128), 16 spp, reference: mis at 1024 spp with another seed. Equal time:
# every strategy gets the time mis took for 16 spp. The oracle uses a 32x32 top level (4 first-pass
# points per cell) instead of the renderer's 48x48: per sample it is the cheaper of the two (its
# texel weights cost (N/32)^2 BSDF evaluations per visited cell, but its prepare visits 2.25x fewer
# cells; 0.73-0.83 against 0.92-1.22 ms of CPU per sample, fig1 x sunset, 192x32, two loaded runs each).
# It is still by far the slowest strategy, and its 16-spp render is most of the run (docs/analyzer.md,
# "The oracle").
# Measured (BENCHMARKS.md, "The main job"; Zen 5 VM, 2 vCPUs, loaded, reference not cached): the
# compare step took 636 s of CPU before the convergence series came from prefixes of the equal-spp
# renders (the oracle was rendered 16 + 15 + 1 spp) and 287 s after (16 + 1 spp), 237 s of it the
# oracle's equal-spp render; then 16-27% less CPU with the oracle's batched prepare and fused BSDF
# evaluation (two interleaved rounds, loaded).
"$BUILD/apps/envpis/envpis" compare --scene fig1 --env "$ENV_MAP" --integrator direct \
  --strategies mis,mis-comp,product,oracle --spp 16 --ref-spp 1024 --equal-time auto \
  --width 384 --height 64 --oracle-res 32 --oracle-dirs 4 --out "$OUT/compare"
echo "envpis demo: done in $(( $(date +%s) - start )) s (build + comparison)"
echo "envpis demo: report at $(cd "$OUT/compare" && pwd)/index.html"
