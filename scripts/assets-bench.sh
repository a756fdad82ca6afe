#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The asset-scene evidence of docs/assets.md (issue 12): `envpis compare` of every scenes/assets-*.json
# under each map (the 8 blender-data maps and the @pmndrs/assets HDRIs of scripts/fetch-assets.sh), the
# path integrator, the default (Sobol) sampler, strategies mis, mis-comp and product, equal spp and
# equal time, medians over SEEDS seeds; with REGULARIZE=1 the same runs again with Cycles-style path
# regularization (REGULARIZATION, default: Cycles' Filter Glossy 1 and Clamp Indirect 10 with both
# caustics switches off) into OUT/regularized/; then the widen_roughness on/off runs on the
# normal-mapped scenes (product only); scripts/assets_table.py writes OUT/table.md (both variants,
# labelled). Each run's report (a page a person can open, with the images) is
# OUT/[regularized/]<scene>--<map>/index.html.
#
# Override WIDTH, HEIGHT (default 128 x 72), SPP (64), REF_SPP (1024), SEEDS (3), MAX_DEPTH (8),
# SCENES, MAPS (default: the 8 blender maps + 8 @pmndrs HDRIs), OUT, BUILD (REBUILD=0: use BUILD as is),
# REGULARIZE (1: also the regularized runs), REGULARIZATION (the envpis options of those runs),
# WIDEN (1: also the widen_roughness runs), EXTRA (more `envpis compare` options for every run, e.g.
# EXTRA="--product-compensation on").
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${OUT:-out/assets-bench}
WIDTH=${WIDTH:-128}
HEIGHT=${HEIGHT:-72}
SPP=${SPP:-64}
REF_SPP=${REF_SPP:-1024}
SEEDS=${SEEDS:-3}
MAX_DEPTH=${MAX_DEPTH:-8}
WIDEN=${WIDEN:-1}
REGULARIZE=${REGULARIZE:-0}
REGULARIZATION=${REGULARIZATION:-"--filter-glossy 1 --clamp-indirect 10 --caustics none"}
read -r -a EXTRA_ARGS <<<"${EXTRA:-}"
ASSETS=${ENVPIS_ASSETS:-${XDG_CACHE_HOME:-$HOME/.cache}/envpis/assets}
SCENES=${SCENES:-scenes/assets-*.json}
PMNDRS="apartment city dawn forest lobby park studio sunset"
MAPS=${MAPS:-"/usr/share/blender/datafiles/studiolights/world/*.exr $(for m in $PMNDRS; do printf '%s ' "$ASSETS/hdri/$m.exr"; done)"}
if [ ! -x "$BUILD/apps/envpis/envpis" ] || [ "${REBUILD:-1}" = 1 ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release -DENVPIS_BUILD_BENCH=OFF >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd
fi
[ -d "$ASSETS/hdri" ] || { echo "assets-bench: no $ASSETS/hdri: run scripts/fetch-assets.sh" >&2; exit 1; }
start=$(date +%s)
mkdir -p "$OUT"
# A map's name in the output directories: the @pmndrs HDRIs share names with blender's (city, forest...).
map_name() { case $1 in "$ASSETS"/hdri/*) echo "pmndrs-$(basename "$1" .exr)" ;; *) basename "$1" .exr ;; esac; }
compare() {  # scene-file label map strategies [extra args]
  local scene=$1 label=$2 map=$3 strategies=$4
  shift 4
  "$BUILD/apps/envpis/envpis" compare --scene "$scene" --env "$map" --integrator path --max-depth "$MAX_DEPTH" \
    --strategies "$strategies" --seeds "$SEEDS" --spp "$SPP" --ref-spp "$REF_SPP" --width "$WIDTH" --height "$HEIGHT" \
    --no-convergence --quiet --out "$OUT/$label--$(map_name "$map")" "${EXTRA_ARGS[@]}" "$@" 2>/dev/null | { grep -E "^overhead" || true; } | sed "s|^|  $label $(map_name "$map"): |"
}
for scene in $SCENES; do
  name=$(basename "$scene" .json)
  name=${name#assets-}
  for map in $MAPS; do
    compare "$scene" "$name" "$map" mis,mis-comp,product --equal-time auto
    if [ "$REGULARIZE" = 1 ]; then
      # shellcheck disable=SC2086  # REGULARIZATION is a list of options
      compare "$scene" "regularized/$name" "$map" mis,mis-comp,product --equal-time auto $REGULARIZATION
    fi
  done
done
if [ "$WIDEN" = 1 ]; then
  # The same scenes with "widen_bent_normals": false, next to a second run with it on (same seeds).
  for scene in scenes/assets-bunny.json scenes/assets-clearcoat.json; do
    name=$(basename "$scene" .json)
    name=${name#assets-}
    off="$OUT/$name-widen-off.json"
    sed 's|^{|{"widen_bent_normals": false,|' "$scene" > "$off"
    sed -i "s|\"file\": \"\\([^$/][^\"]*\\)\"|\"file\": \"$PWD/scenes/\\1\"|g" "$off"
    for map in $MAPS; do
      compare "$scene" "widen-$name-on" "$map" product --no-plots
      compare "$off" "widen-$name-off" "$map" product --no-plots
    done
  done
fi
python3 scripts/assets_table.py "$OUT" > "$OUT/table.md"
echo "assets-bench: done in $(( $(date +%s) - start )) s; table in $OUT/table.md"
