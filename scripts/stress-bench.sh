#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The firefly tail table (issue 9): fig1, direct lighting, 64 spp, strategies mis and product, over the
# generated sun stress family and the four quadrant-boundary suns of issue 23 (tests/stress_maps.h, written
# by bench/envpis_stress_maps) and the eight blender maps, with --seeds 3 (medians over seeds) against a
# 2048-spp reference of another seed.
# Prints one line per map and strategy: median relMSE, worst-seed max per-pixel relative squared error,
# worst-seed count of pixels more than 10x off, and the per-sphere worst ratio product/mis of the
# median relMSE. Override SPP, REF_SPP, SEEDS, PEAK_RATIO, MAPS, OUT, BUILD.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${OUT:-out/stress-bench}
SPP=${SPP:-64}
REF_SPP=${REF_SPP:-2048}
SEEDS=${SEEDS:-3}
PEAK=${PEAK_RATIO:+--peak-ratio $PEAK_RATIO}
if [ ! -x "$BUILD/apps/envpis/envpis" ] || [ ! -x "$BUILD/bench/envpis_stress_maps" ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd envpis_stress_maps
fi
mkdir -p "$OUT/maps"
"$BUILD/bench/envpis_stress_maps" "$OUT/maps" >/dev/null
MAPS=${MAPS:-"$OUT/maps/*.exr /usr/share/blender/datafiles/studiolights/world/*.exr"}
for map in $MAPS; do
  name=$(basename "$map" .exr)
  # shellcheck disable=SC2086
  "$BUILD/apps/envpis/envpis" compare --scene fig1 --env "$map" --integrator direct --strategies mis,product \
    --spp "$SPP" --ref-spp "$REF_SPP" --seeds "$SEEDS" --no-convergence --no-plots --quiet $PEAK \
    --out "$OUT/$name" >/dev/null
done
python3 - "$OUT" <<'PY'
import glob, json, os, sys
out = sys.argv[1]
print("| map | strategy | median relMSE | max rel. sq. error (worst seed) | pixels > 10x off (worst seed) | worst sphere product/mis |")
print("|---|---|---|---|---|---|")
for path in sorted(glob.glob(os.path.join(out, "*", "metrics.json"))):
    j = json.load(open(path))
    s = {x["strategy"]: x for x in j["equal_spp"]["strategies"]}
    ratio = max(p["relmse"] / m["relmse"] for p, m in zip(s["product"]["regions"], s["mis"]["regions"]) if m["relmse"] > 0)
    for name in ("mis", "product"):
        x = s[name]
        print(f"| {os.path.basename(os.path.dirname(path))} | {name} | {x['relmse']:.3g} | {x['max_rel_sq_error_worst']:.3g} | "
              f"{x['pixels_over_10x_worst']} | {ratio:.2f} |")
PY
