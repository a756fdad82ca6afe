#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# Issue 24, item 3: `envpis compare` on the interior rooms (scenes/interior-room.json,
# scenes/interior-two-windows.json; glTF from scripts/make-interiors.py) under a few maps, with the
# direct and the path integrator, and the table of the issue's targets (scripts/interiors_table.py):
# efficiency product-portal / product and product-portal / mis-portal, medians over seeds, the tail.
#
#   scripts/interiors-bench.sh [OUT]     (default out/interiors, git-ignored)
#
# Environment: BUILD (build), SIZE (64x48), SPP (64), REF_SPP (1024), SEEDS (3), MAPS (sunrise and city
# from the blender maps, park from the @pmndrs HDRIs), SCENES (room, two-windows),
# INTEGRATORS (direct path), STRATEGIES (the list below, for both integrators), EXTRA (more compare
# options, e.g. "--product-cache 0": product-portal prepared exactly per point, as before the cache
# learnt portals). Every render runs under nice -n 19 with 2 threads.
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=${1:-out/interiors}
BUILD=${BUILD:-build}
SIZE=${SIZE:-64x48}
SPP=${SPP:-64}
REF_SPP=${REF_SPP:-1024}
SEEDS=${SEEDS:-3}
WORLDS=/usr/share/blender/datafiles/studiolights/world
ASSETS=${ENVPIS_ASSETS:-${XDG_CACHE_HOME:-$HOME/.cache}/envpis/assets}
MAPS=${MAPS:-"$WORLDS/sunrise.exr $WORLDS/city.exr $ASSETS/hdri/park.exr"}
SCENES=${SCENES:-"room two-windows"}
INTEGRATORS=${INTEGRATORS:-"direct path"}
ENVPIS="$BUILD/apps/envpis/envpis"
[ -x "$ENVPIS" ] || { echo "interiors-bench: error: no $ENVPIS (build envpis_cmd first)" >&2; exit 1; }
[ -f "$ASSETS/interiors/window-room.gltf" ] || python3 scripts/make-interiors.py "$ASSETS/interiors"
mkdir -p "$OUT"
for integrator in $INTEGRATORS; do
  # env-portal has no BSDF hits; the portals cover every opening here, so it is unbiased, but along
  # paths (glossy bounces) it is not a contender: direct only.
  strategies=product,mis-portal,mis-comp-portal,product-portal
  [ "$integrator" = direct ] && strategies=$strategies,env-portal
  strategies=${STRATEGIES:-$strategies}
  for scene in $SCENES; do
    file=scenes/interior-$scene.json
    for map in $MAPS; do
      name=$scene-$(basename "$map" .exr)-$integrator
      [ -f "$OUT/$name/metrics.json" ] && continue
      echo "interiors-bench: $name ($(date -u +%H:%M:%S), load $(cut -d' ' -f1 /proc/loadavg))"
      nice -n 19 "$ENVPIS" compare --scene "$file" --env "$map" --integrator "$integrator" \
        --strategies "$strategies" --spp "$SPP" --seeds "$SEEDS" --ref-strategy mis-portal --ref-spp "$REF_SPP" \
        --width "${SIZE%x*}" --height "${SIZE#*x}" --threads 2 --no-convergence --no-analysis --no-plots \
        --quiet ${EXTRA:-} --out "$OUT/$name" > "$OUT/$name.log"
    done
  done
done
python3 scripts/interiors_table.py "$OUT"
