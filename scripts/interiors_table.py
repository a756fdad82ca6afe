#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The table of scripts/interiors-bench.sh: for every `envpis compare` run under OUT (one directory per
scene, map and integrator, each with its metrics.json), the efficiency 1 / (relMSE x seconds) of
product-portal over product and over mis-portal (relMSE: the median over seeds, as compare reports it;
seconds: the first seed's sampling wall time), the same with the reference's noise floor subtracted from
every relMSE (compare's relmse_floor: a noisy reference adds it to every strategy's relMSE, which pulls
ratios towards 1), the seconds, the robust relMSE ratio (without each image's top 0.1%
of pixels), the tail (largest per-pixel error and pixels 10x off, worst seed) and the bias check (the
largest per-object |z| against the reference); then per integrator the median and the geometric mean
of the ratios over the runs ("pooled").

  python3 scripts/interiors_table.py OUT      (writes OUT/results.md and prints it)
"""
import json
import math
import os
import statistics
import sys


def load(path):
    with open(path) as f:
        j = json.load(f)
    rows = {s["strategy"]: s for s in j["equal_spp"]["strategies"]}
    return j, rows


def eff(s, floor=0.0):
    return 1.0 / ((s["relmse"] - floor) * s["seconds"])


def ratio(rows, a, b, key=None, floor=0.0):
    """efficiency a / b; with `key` the ratio b / a of that metric; `floor`: the reference's own noise
    (relmse_floor, which every measured relMSE carries on top of its own), subtracted."""
    if a not in rows or b not in rows:
        return None
    if key:
        return rows[b][key] / rows[a][key]
    return eff(rows[a], floor) / eff(rows[b], floor)


def fmt(x, f=".2f"):
    return "-" if x is None else format(x, f)


def main(argv):
    if len(argv) != 1:
        print("usage: interiors_table.py OUT", file=sys.stderr)
        return 2
    out = argv[0]
    runs = sorted(d for d in os.listdir(out) if os.path.isfile(os.path.join(out, d, "metrics.json")))
    if not runs:
        print("interiors_table: error: no */metrics.json under %s" % out, file=sys.stderr)
        return 1
    lines = ["| run | spp | ref floor / pp relMSE | relMSE product | mis-portal | mis-comp-portal | product-portal "
             "| env-portal | seconds product, mis-portal, pp | eff pp / product | eff pp / mis-portal "
             "| eff pp / mis-comp-portal | floor-corrected eff pp / product, / mis-portal | robust relMSE "
             "mis-portal / pp | tail pp: max e, px > 10x (worst seed) | tail mis-portal | max abs z |",
             "|---" * 17 + "|"]
    pooled = {}
    for run in runs:
        j, rows = load(os.path.join(out, run, "metrics.json"))
        pp = rows.get("product-portal")
        r1, r2 = ratio(rows, "product-portal", "product"), ratio(rows, "product-portal", "mis-portal")
        r3 = ratio(rows, "product-portal", "mis-comp-portal")
        rob = ratio(rows, "product-portal", "mis-portal", "relmse_trimmed")
        floor = j["reference"].get("relmse_floor")
        c1 = ratio(rows, "product-portal", "product", floor=floor or 0.0)
        c2 = ratio(rows, "product-portal", "mis-portal", floor=floor or 0.0)
        secs = ", ".join(fmt(rows[k]["seconds"]) if k in rows else "-" for k in ("product", "mis-portal", "product-portal"))
        zmax = max(abs(r.get("z", 0.0)) for s in rows.values() for r in s.get("regions", []) if r.get("z") is not None)
        rel = lambda k: fmt(rows[k]["relmse"], ".3g") if k in rows else "-"  # noqa: E731
        tail = lambda k: ("%.3g, %d" % (rows[k]["max_rel_sq_error_worst"], rows[k]["pixels_over_10x_worst"])  # noqa: E731
                          if k in rows else "-")
        lines.append("| %s | %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s, %s | %s | %s | %s | %.1f |" % (
            run, pp["spp"] if pp else 0, fmt(floor / pp["relmse"] if pp and floor else None),
            rel("product"), rel("mis-portal"), rel("mis-comp-portal"), rel("product-portal"), rel("env-portal"),
            secs, fmt(r1), fmt(r2), fmt(r3), fmt(c1), fmt(c2), fmt(rob), tail("product-portal"), tail("mis-portal"),
            zmax))
        integrator = j.get("integrator", "?")
        for key, r in (("pp/product", r1), ("pp/mis-portal", r2), ("pp/mis-comp-portal", r3),
                       ("pp/product, floor-corrected", c1), ("pp/mis-portal, floor-corrected", c2)):
            if r is not None:
                pooled.setdefault((integrator, key), []).append(r)
    lines += ["", "| integrator | ratio | runs | median | geometric mean | min | max |", "|---|---|---|---|---|---|---|"]
    for (integrator, key), rs in sorted(pooled.items()):
        g = math.exp(sum(math.log(r) for r in rs) / len(rs))
        lines.append("| %s | efficiency %s | %d | %.2f | %.2f | %.2f | %.2f |" % (
            integrator, key, len(rs), statistics.median(rs), g, min(rs), max(rs)))
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out, "results.md"), "w") as f:
        f.write(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
