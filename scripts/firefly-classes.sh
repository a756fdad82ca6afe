#!/usr/bin/env bash
# SPDX-License-Identifier: Apache-2.0
# The firefly diagnosis of docs/fireflies.md (issue 9): fig1, direct lighting, 64 spp, strategies mis and
# product, with the table's peak bound off (--peak-ratio 0) and on (8), over a few generated stress maps
# (tests/stress_maps.h) and sunrise.exr, seeds 0 .. SEEDS-1 against one cached 1024-spp reference per map
# (seed 1000003). Every run logs the samples whose contribution / spp exceeds FACTOR sqrt(R^2 + 0.01)
# (envpis compare --firefly-log); the script then sorts them into classes and prints a table of counts:
# F >= 10 (one sample alone takes its pixel about 10x off) and, in brackets, F >= FACTOR.
# Override MAPS (stress-map names or .exr paths), SEEDS, SPP, REF_SPP, FACTOR, OUT, BUILD; CLASSIFY_ONLY=1
# re-reads the logs of an earlier run without rendering.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build}
OUT=${OUT:-out/firefly-classes}
SPP=${SPP:-64}
REF_SPP=${REF_SPP:-1024}
SEEDS=${SEEDS:-4}
FACTOR=${FACTOR:-3}
MAPS=${MAPS:-"cell-edge subtexel two-suns quadrant /usr/share/blender/datafiles/studiolights/world/sunrise.exr"}
if [ ! -x "$BUILD/apps/envpis/envpis" ] || [ ! -x "$BUILD/bench/envpis_stress_maps" ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$BUILD" -j"$(nproc)" --target envpis_cmd envpis_stress_maps
fi
mkdir -p "$OUT/maps"
"$BUILD/bench/envpis_stress_maps" "$OUT/maps" >/dev/null
for map in $MAPS; do
  [ "${CLASSIFY_ONLY:-0}" = 1 ] && break
  case "$map" in *.exr) path=$map ;; *) path=$OUT/maps/$map.exr ;; esac
  name=$(basename "$path" .exr)
  for k in 0 8; do
    for ((seed = 0; seed < SEEDS; seed++)); do
      run=$OUT/runs/$name-k$k-s$seed
      "$BUILD/apps/envpis/envpis" compare --scene fig1 --env "$path" --integrator direct --strategies mis,product \
        --spp "$SPP" --ref-spp "$REF_SPP" --ref-seed 1000003 --seed "$seed" --peak-ratio "$k" --repeats 1 \
        --no-convergence --no-plots --quiet --out "$run" --firefly-log "$run/fireflies" --firefly-factor "$FACTOR" \
        >/dev/null
    done
  done
done
python3 - "$OUT/runs" "$FACTOR" <<'PY'
import collections, csv, glob, os, re, sys

runs, factor = sys.argv[1], float(sys.argv[2])
K = 8.0  # the peak bound's ratio: a texel whose radiance exceeds K times its importance is under-rated

CAUSES = ("under-rated texel", "proxy under-rates the cell", "other")
CLASSES = [t + ": " + c for t in ("light", "bsdf") for c in CAUSES]

def classify(r, strategy):
    under = float(r["radiance"]) > K * float(r["texel_importance"])
    # How much less often this strategy picks the direction's top cell than the table (mis) does.
    cp = float(r["cell_probability"])
    proxy_low = strategy == "product" and (cp <= 0 or float(r["cell_env_probability"]) / cp > 2)
    return r["technique"] + ": " + CAUSES[0 if under else 1 if proxy_low else 2]

# (strategy, K) -> class -> [F >= 10, all]; the same per map and per object, F >= 10 only.
counts = collections.defaultdict(lambda: collections.defaultdict(lambda: [0, 0]))
where = collections.defaultdict(collections.Counter)
amplification = collections.defaultdict(list)  # product light samples: E[c] / P[c]
for path in sorted(glob.glob(os.path.join(runs, "*", "fireflies", "fireflies-*.csv"))):
    m = re.search(r"([^/]+)-k(\d+)-s\d+/fireflies/fireflies-(.+)\.csv$", path)
    name, k, strategy = m.group(1), int(m.group(2)), m.group(3)
    for r in csv.DictReader(open(path)):
        f = float(r["contribution"]) / float(r["threshold"]) * factor  # contribution / spp over sqrt(R^2 + 0.01)
        c = counts[(strategy, k)][classify(r, strategy)]
        c[1] += 1
        c[0] += f >= 10
        if f >= 10:
            where[(strategy, k)]["map " + name] += 1
            where[(strategy, k)]["object " + r["object"]] += 1
        if strategy == "product" and r["technique"] == "light" and float(r["cell_probability"]) > 0:
            amplification[k].append(float(r["cell_env_probability"]) / float(r["cell_probability"]))
print("| strategy | peak ratio | " + " | ".join(CLASSES) + " |")
print("|---|---|" + "---|" * len(CLASSES))
for strategy in ("mis", "product"):
    for k in (0, 8):
        row = counts[(strategy, k)]
        print(f"| {strategy} | {k} | " + " | ".join(f"{row[c][0]} ({row[c][1]})" for c in CLASSES) + " |")
for key, w in sorted(where.items()):
    print(f"{key[0]}, peak ratio {key[1]}, F >= 10 by map and object: " + ", ".join(f"{n} {v}" for n, v in sorted(w.items())))
for k, a in sorted(amplification.items()):
    a.sort()
    print(f"product light samples, peak ratio {k}: E[c] / P[c] from {a[0]:.2f} to {a[-1]:.2f}, median {a[len(a) // 2]:.2f}, "
          f"{sum(x > 2 for x in a)} of {len(a)} above 2")
PY
