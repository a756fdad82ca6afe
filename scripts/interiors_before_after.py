#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""product-portal before and after a change, on the runs of scripts/interiors-bench.sh: AFTER holds the
whole runs (product, mis-portal, product-portal, ...), BEFORE the same runs of product-portal alone (e.g.
`STRATEGIES=product-portal EXTRA="--product-cache 0" bash scripts/interiors-bench.sh BEFORE`). Per run:
product-portal's relMSE (median over seeds), sampling seconds (first seed, wall and CPU) and worst pixel,
before and after, and the efficiency 1 / (relMSE x seconds) of each over product and over mis-portal
(both from AFTER); then per integrator the medians and geometric means over the runs, with wall and
with CPU seconds.

  python3 scripts/interiors_before_after.py AFTER BEFORE
"""
import json
import math
import os
import statistics
import sys


def rows(path):
    with open(path) as f:
        j = json.load(f)
    return j, {s["strategy"]: s for s in j["equal_spp"]["strategies"]}


def eff(s, cpu):
    return 1.0 / (s["relmse"] * (s["cpu_seconds"] if cpu else s["seconds"]))


def main(argv):
    if len(argv) != 2:
        print("usage: interiors_before_after.py AFTER BEFORE", file=sys.stderr)
        return 2
    after, before = argv
    runs = sorted(d for d in os.listdir(after)
                  if os.path.isfile(os.path.join(after, d, "metrics.json"))
                  and os.path.isfile(os.path.join(before, d, "metrics.json")))
    lines = ["| run | pp relMSE before, after | pp seconds before, after (CPU) | pp worst pixel e before, after "
             "| eff pp / product before, after | eff pp / mis-portal before, after | the same with CPU seconds |",
             "|---" * 7 + "|"]
    pooled = {}
    for run in runs:
        j, a = rows(os.path.join(after, run, "metrics.json"))
        _, b = rows(os.path.join(before, run, "metrics.json"))
        pa, pb = a["product-portal"], b["product-portal"]
        r = {}
        for cpu in (False, True):
            for base in ("product", "mis-portal"):
                for tag, pp in (("before", pb), ("after", pa)):
                    r[(cpu, base, tag)] = eff(pp, cpu) / eff(a[base], cpu)
        lines.append("| %s | %.3g, %.3g | %.2f, %.2f (%.2f, %.2f) | %.3g, %.3g | %.2f, %.2f | %.2f, %.2f | %.2f, %.2f; %.2f, %.2f |" % (
            run, pb["relmse"], pa["relmse"], pb["seconds"], pa["seconds"], pb["cpu_seconds"], pa["cpu_seconds"],
            pb["max_rel_sq_error_worst"], pa["max_rel_sq_error_worst"],
            r[(False, "product", "before")], r[(False, "product", "after")],
            r[(False, "mis-portal", "before")], r[(False, "mis-portal", "after")],
            r[(True, "product", "before")], r[(True, "product", "after")],
            r[(True, "mis-portal", "before")], r[(True, "mis-portal", "after")]))
        for k, v in r.items():
            pooled.setdefault((j.get("integrator", "?"),) + k, []).append(v)
    lines += ["", "| integrator | seconds | ratio | runs | median before | median after | geometric mean before | after |",
              "|---|---|---|---|---|---|---|---|"]
    for integrator in sorted({k[0] for k in pooled}):
        for cpu in (False, True):
            for base in ("product", "mis-portal"):
                b = pooled.get((integrator, cpu, base, "before"), [])
                a = pooled.get((integrator, cpu, base, "after"), [])
                if not a:
                    continue
                g = lambda xs: math.exp(sum(map(math.log, xs)) / len(xs))  # noqa: E731
                lines.append("| %s | %s | efficiency pp / %s | %d | %.2f | %.2f | %.2f | %.2f |" % (
                    integrator, "CPU" if cpu else "wall", base, len(a), statistics.median(b), statistics.median(a),
                    g(b), g(a)))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
