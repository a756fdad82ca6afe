#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Pools `envpis analyze --json` files of several maps into the tables of docs/analyzer.md.

    for m in sunrise sunset studio interior city courtyard forest night; do
      envpis analyze --env /usr/share/blender/datafiles/studiolights/world/$m.exr --json DIR/$m.json
      envpis analyze --env .../$m.exr --strategies product --exact 12 --proxy-min-alpha 0 \\
          --json FLOOR_DIR/$m.json          # optional: the roughness floor off
    done
    scripts/analyzer_pool.py DIR [FLOOR_DIR]

Every value is pooled per object by the geometric mean over all points of all maps (each map has the
same points), as issue 10's table; "arithmetic" rows use the arithmetic mean over the points instead
(closer to what relMSE averages over pixels). Ratios are ratios of pooled values. Prints Markdown.
"""
import json
import math
import os
import sys

MAPS = ["sunrise", "sunset", "studio", "interior", "city", "courtyard", "forest", "night"]


def load(directory):
    return {m: json.load(open(os.path.join(directory, m + ".json"))) for m in MAPS
            if os.path.exists(os.path.join(directory, m + ".json"))}


def points(runs, index):
    return [p for run in runs.values() for p in run["objects"][index]["per_point"]]


def geo(values):
    values = [v for v in values if v is not None and v > 0]
    return math.exp(sum(map(math.log, values)) / len(values)) if values else float("nan")


def arith(values):
    values = [v for v in values if v is not None]
    return sum(values) / len(values) if values else float("nan")


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    runs = load(sys.argv[1])
    floor = load(sys.argv[2]) if len(sys.argv) > 2 else {}
    if not runs:
        sys.exit("no MAP.json in " + sys.argv[1])
    first = next(iter(runs.values()))
    names = [o["name"] for o in first["objects"]]

    def pooled(get, source=runs, mean=geo):
        return [mean([get(p) for p in points(source, i)]) for i in range(len(names))]

    v = lambda s, mean=geo: pooled(lambda p: p["v"].get(s), mean=mean)
    light = lambda s: pooled(lambda p: p["v_light"].get(s))
    exact = lambda t: pooled(lambda p: p["v_exact"].get(t))
    limit = pooled(lambda p: p["v_product_limit"])
    div = lambda a, b: [x / y for x, y in zip(a, b)]
    rows = [
        ("V(env) / V(product), light alone", div(light("env"), light("product"))),
        ("V(product) / V(exact-12), light alone", div(light("product"), exact("12"))),
    ]
    if len(floor) == len(runs):
        rows.append(("V(product, roughness floor off) / V(exact-12), light alone",
                     div(pooled(lambda p: p["v_light"]["product"], floor), exact("12"))))
    rows += [
        ("V(exact-12) / V(exact-48)", div(exact("12"), exact("48"))),
        ("V(mis) / V(product), estimator", div(v("mis"), v("product"))),
        ("V(mis) / V(product), estimator, arithmetic mean over points",
         div(v("mis", arith), v("product", arith))),
        ("V(mis-comp) / V(product), estimator", div(v("mis-comp"), v("product"))),
    ]
    if len(floor) == len(runs):
        rows.append(("V(product) / V(product, floor off), estimator",
                     div(v("product"), pooled(lambda p: p["v"]["product"], floor))))
    rows.append(("V(product) / V(oracle), estimator", div(v("product"), v("oracle"))))

    def table(title, rows_):
        print("| " + title + " | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(names))
        for label, values in rows_:
            print("| " + label + " | " + " | ".join(f"{x:.3g}" for x in values) + " |")
        print()

    table(f"pooled ({len(runs)} maps)", rows)
    strategies = first["strategies"]
    table("V", [(s + ", estimator", v(s)) for s in strategies] +
          [(s + ", light alone", light(s)) for s in strategies if s not in ("bsdf", "env", "mis")] +
          [("product* (exact product)", limit)] + [("exact-" + str(t), exact(str(t))) for t in first["exact_levels"]])
    per_map = []
    for m, run in runs.items():
        one = {m: run}
        per_map.append((m, div(pooled(lambda p: p["v"]["mis"], one), pooled(lambda p: p["v"]["product"], one))))
    table("V(mis) / V(product), estimator, per map", per_map)


if __name__ == "__main__":
    main()
