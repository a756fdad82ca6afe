#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The BENCHMARKS.md comparison table: `envpis compare` of fig1 (direct lighting) under each of the eight
# blender-data maps (/usr/share/blender/datafiles/studiolights/world/*.exr), strategies mis, mis-comp,
# product and oracle at equal spp and at equal time, then scripts/paper_table.py aggregates the eight
# metrics.json files into OUT/table.md (relMSE ratios per roughness, overhead, gap to the oracle, targets).
# Each map's full report is in OUT/<map>/index.html.
#
# Sizes are modest so the whole table runs in about 16 minutes on 2 free cores (build not included):
# 384x64 pixels, 32 spp, reference mis at 4096 spp with another seed (cached under ~/.cache/envpis),
# the oracle at the renderer's defaults (48x48 cells, render/oracle.h; it is most of the time: about
# 600 us of CPU per sample, docs/analyzer.md "The oracle").
# Override with SPP, REF_SPP, WIDTH, HEIGHT, ORACLE_RES, MAPS, OUT, BUILD (REBUILD=0: use BUILD as is),
# STRATEGIES (default mis,mis-comp,product,oracle), SEEDS (renders per strategy; relMSE is their
# median, default 1), SAMPLER (sobol, padded or independent; default: the renderer's, sobol) and EXTRA (more
# `envpis compare` options, e.g. EXTRA="--subcells 4" for the refined product).
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${OUT:-out/paper-table}
SPP=${SPP:-32}
REF_SPP=${REF_SPP:-4096}
WIDTH=${WIDTH:-384}
HEIGHT=${HEIGHT:-64}
ORACLE_RES=${ORACLE_RES:-48}
MAPS=${MAPS:-/usr/share/blender/datafiles/studiolights/world/*.exr}
STRATEGIES=${STRATEGIES:-mis,mis-comp,product,oracle}
SEEDS=${SEEDS:-1}
SAMPLER=${SAMPLER:-sobol}
read -r -a EXTRA_ARGS <<<"${EXTRA:-}"
if [ ! -x "$BUILD/apps/envpis/envpis" ] || [ "${REBUILD:-1}" = 1 ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DENVPIS_BUILD_BENCH=OFF >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
fi
PY=/usr/bin/python3
[ -x "$PY" ] || PY=python3
start=$(date +%s)
mkdir -p "$OUT"
for map in $MAPS; do
  name=$(basename "$map" .exr)
  echo "paper-table: $name"
  "$BUILD/apps/envpis/envpis" compare --scene fig1 --env "$map" --integrator direct \
    --strategies "$STRATEGIES" --seeds "$SEEDS" --sampler "$SAMPLER" --spp "$SPP" --ref-spp "$REF_SPP" --equal-time auto \
    --width "$WIDTH" --height "$HEIGHT" --oracle-res "$ORACLE_RES" --oracle-dirs "${ORACLE_DIRS:-4}" --no-convergence \
    --quiet --out "$OUT/$name" "${EXTRA_ARGS[@]}" | sed 's/^/  /'
done
"$PY" scripts/paper_table.py "$OUT"/*/metrics.json > "$OUT/table.md"
echo "paper-table: done in $(( $(date +%s) - start )) s; table in $OUT/table.md"
