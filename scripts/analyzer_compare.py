#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Compares product sampler configurations with `envpis analyze` runs over the 8 blender maps.

    for m in sunrise sunset studio interior city courtyard forest night; do
      for cfg in "paper:--subcells 1" "s4k0:--subcells 4 --refine-cells 0" "s4k8:--subcells 4 --refine-cells 8"; do
        envpis analyze --env /usr/share/blender/datafiles/studiolights/world/$m.exr --strategies mis,product \\
            --points 4 --exact 12 ${cfg#*:} --json DIR/$m-${cfg%%:*}.json
      done
    done
    scripts/analyzer_compare.py DIR paper s4k0 s4k8

Per object: the renderer's estimator V of product under each configuration (geometric mean over every
point of every map) and V(mis) / V(product), then the same for the light sample alone against the
exact-12 limit. Prints Markdown.
"""
import math
import os
import sys
import json

MAPS = ["sunrise", "sunset", "studio", "interior", "city", "courtyard", "forest", "night"]


def geo(values):
    values = [v for v in values if v is not None and v > 0]
    return math.exp(sum(map(math.log, values)) / len(values)) if values else float("nan")


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: analyzer_compare.py DIR CONFIG...")
    directory, configs = sys.argv[1], sys.argv[2:]
    # Only the maps every configuration has, so that each column pools the same points.
    present = [m for m in MAPS if all(os.path.exists(os.path.join(directory, f"{m}-{c}.json")) for c in configs)]
    if not present:
        sys.exit("analyzer_compare.py: no map has a run of every configuration")
    runs = {c: [json.load(open(os.path.join(directory, f"{m}-{c}.json"))) for m in present] for c in configs}
    maps = len(present)
    objects = [o["name"] for o in runs[configs[0]][0]["objects"]]
    print(f"{maps} maps; V = Var / I^2 of one sample, geometric mean over the points\n")
    head = "| object | " + " | ".join(f"mis / product {c}" for c in configs) + " | " + \
        " | ".join(f"light: product {c} / exact-12" for c in configs) + " |"
    print(head)
    print("|" + "---|" * (1 + 2 * len(configs)))
    for i, name in enumerate(objects):
        cells = []
        for key in ("v", "v_light"):
            for c in configs:
                pts = [p for run in runs[c][:maps] for p in run["objects"][i]["per_point"]]
                prod = geo([p[key]["product"] for p in pts])
                ref = geo([p["v"]["mis"] for p in pts]) if key == "v" else geo([p["v_exact"]["12"] for p in pts])
                cells.append(f"{ref / prod:.2f}" if key == "v" else f"{prod / ref:.2f}")
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
