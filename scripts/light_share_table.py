#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""How much a light distribution could still gain on the asset benchmark's glossy objects: per object,
pooled over the maps of an scripts/assets-bench.sh run, the share of the variance that light samples
bring under mis-comp and under product (median over maps), product's gain (trimmed relMSE mis-comp /
product at equal spp, geometric mean) and 1 / (1 - mis-comp's share), the gain of a light distribution
without variance of its own if the BSDF-sampled part kept its variance (geometric mean; a bound only
under that assumption: the MIS weights change that part too). docs/assets.md has the reading.

    python3 scripts/light_share_table.py OUT
"""
import glob
import json
import math
import os
import sys

from assets_table import alpha_of
from paper_table import f, geomean, median


def rows(out):
    for path in sorted(glob.glob(os.path.join(out, "*", "metrics.json"))):
        with open(path) as fh:
            m = json.load(fh)
        scene = os.path.basename(os.path.dirname(path)).split("--")[0]
        by = {s["strategy"]: s for s in m["equal_spp"]["strategies"]}
        if "mis-comp" not in by or "product" not in by:
            continue
        for i, region in enumerate(m["regions"]):
            a = alpha_of(scene, region["name"])
            if a is None or not 0.05 <= a <= 0.5:
                continue
            mc, pr = by["mis-comp"]["regions"][i], by["product"]["regions"][i]
            if not (pr["relmse_trimmed"] > 0 and mc["relmse_trimmed"] > 0):
                continue
            share = mc["light_variance_share"]
            yield (scene, region["name"], a, share, pr["light_variance_share"],
                   mc["relmse_trimmed"] / pr["relmse_trimmed"], 1.0 / (1.0 - min(share, 0.99)))


def main(out):
    data = list(rows(out))
    if not data:
        sys.exit(f"light_share_table: no glossy objects with mis-comp and product in {out}")
    print("| scene | object | alpha | maps | light share, mis-comp | light share, product | relMSE mis-comp / product (trimmed) | 1 / (1 - share of mis-comp) |")
    print("|---|---|---|---|---|---|---|---|")
    for key in sorted(set((r[0], r[1]) for r in data)):
        sel = [r for r in data if (r[0], r[1]) == key]
        print(f"| {key[0]} | {key[1]} | {sel[0][2]:.3f} | {len(sel)} | {f(median([r[3] for r in sel]))} | "
              f"{f(median([r[4] for r in sel]))} | {f(geomean([r[5] for r in sel]))} | {f(geomean([r[6] for r in sel]))} |")
    above = sum(1 for r in data if r[5] > r[6])
    print(f"\nPooled over {len(data)} glossy object-maps: light share of mis-comp median {f(median([r[3] for r in data]))} "
          f"({f(min(r[3] for r in data))}-{f(max(r[3] for r in data))}), of product {f(median([r[4] for r in data]))}; "
          f"relMSE mis-comp / product {f(geomean([r[5] for r in data]))}; 1 / (1 - share) {f(geomean([r[6] for r in data]))}; "
          f"object-maps gaining more than it: {above}.")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: light_share_table.py OUT")
    main(sys.argv[1])
