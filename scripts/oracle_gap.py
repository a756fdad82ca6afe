#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The oracle's gap by the analyzer (BENCHMARKS.md, "The oracle as a limit").

Usage: oracle_gap.py ON_DIR [OFF_DIR]
  ON_DIR:  `envpis analyze --strategies product,oracle --exact 48 --json ON_DIR/MAP.json` per map
  OFF_DIR: the same with `--strategies oracle --oracle-compensation off` (the share alone)
Prints, per object (sphere), pooled over maps x points by the geometric mean: V(product) / V(oracle)
of the renderer's estimator, the points where the oracle is worse than the product (and the worst
ratio), and, from OFF_DIR, the share's light sample alone against the exact 48 x 48 top level.
"""
import glob
import json
import math
import os
import sys


def points(directory):
    out = {}
    for path in sorted(glob.glob(os.path.join(directory, "*.json"))):
        j = json.load(open(path))
        name = os.path.basename(path)[:-5]
        for o in j["objects"]:
            for k, p in enumerate(o["per_point"]):
                out[(o["name"], name, k)] = p
    return out


def gmean(values):
    values = [v for v in values if v > 0 and math.isfinite(v)]
    return math.exp(sum(math.log(v) for v in values) / len(values)) if values else float("nan")


def main():
    on = points(sys.argv[1])
    off = points(sys.argv[2]) if len(sys.argv) > 2 else {}
    objects = []
    for key in on:
        if key[0] not in objects:
            objects.append(key[0])
    print("| object | points | V(product) / V(oracle), estimator | oracle worse (> 1.02x) | worst V(oracle)/V(product) |"
          + (" V(share) / V(exact-48), light alone |" if off else ""))
    print("|---|---|---|---|---|" + ("---|" if off else ""))
    for obj in objects:
        keys = [k for k in on if k[0] == obj]
        ratios = [on[k]["v"]["product"] / on[k]["v"]["oracle"] for k in keys]
        worse = sum(1 for r in ratios if r < 1 / 1.02)
        row = f"| {obj} | {len(keys)} | {gmean(ratios):.3g} | {worse} | {max(1 / r for r in ratios):.3g} |"
        if off:
            share = [off[k]["v_light"]["oracle"] / off[k]["v_exact"]["48"] for k in keys if k in off]
            row += f" {gmean(share):.3g} |"
        print(row)
    per_map = {}
    for k in on:
        per_map.setdefault(k[1], []).append(on[k]["v"]["product"] / on[k]["v"]["oracle"])
    print()
    print("| map | " + " | ".join(per_map) + " |")
    print("|---|" + "---|" * len(per_map))
    print("| V(product) / V(oracle), geometric mean over its points | "
          + " | ".join(f"{gmean(v):.3g}" for v in per_map.values()) + " |")


if __name__ == "__main__":
    main()
