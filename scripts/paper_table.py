#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Aggregates `envpis compare` runs of fig1 (one per environment map) into the markdown tables of
BENCHMARKS.md: relMSE ratios per roughness at equal spp and at equal time, the overhead ratio, the gap
to the oracle, and the issue's targets with met / not met.

    python3 scripts/paper_table.py OUT/*/metrics.json > OUT/table.md
    python3 scripts/paper_table.py --summary [LABEL=]OUT [[LABEL=]OUT2]

The first form prints the full per-map tables. --summary prints the pooled table of BENCHMARKS.md's
"Current" fig1 section: one row per comparison and run (each OUT a scripts/paper-table.sh output
directory; LABEL defaults to the run's sampler), with two runs also the ratio first / second of the
pooled equal-spp mis / product, then each run's overhead and worst sphere-map.

Ratios > 1 mean product has less error (mis / product, mis-comp / product) or that the oracle has less
error than product (product / oracle). "Pooled" is the geometric mean over the maps.
"""
import glob
import json
import math
import os
import sys

TARGET_MIS_OVER_PRODUCT = 1 / 0.55  # product relMSE <= 0.55 x mis at roughness 0.2 and 0.3, pooled
TARGET_WORST_PRODUCT_OVER_MIS = 1.1  # no sphere of any map more than 1.1x worse than mis
TARGET_OVERHEAD = 1.10  # time(product) / time(mis), goal 1.05


def label(name):
    return name[len("conductor-"):] if name.startswith("conductor-") else name


def geomean(xs):
    xs = [x for x in xs if x is not None and math.isfinite(x) and x > 0]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def median(xs):
    xs = sorted(x for x in xs if x is not None and math.isfinite(x))
    if not xs:
        return float("nan")
    n = len(xs)
    return xs[n // 2] if n % 2 else 0.5 * (xs[n // 2 - 1] + xs[n // 2])


def f(x, digits=2):
    if x is None or not math.isfinite(x):
        return "-"
    return f"{x:.{digits}f}"


def region_relmse(block, strategy):
    for s in block["strategies"]:
        if s["strategy"] == strategy:
            return {r["name"]: r["relmse"] for r in s["regions"]}, s
    return None, None


def region_relerr(block, strategy):
    """Relative standard error of each region's relMSE (from the spread of its per-pixel terms)."""
    for s in block["strategies"]:
        if s["strategy"] == strategy:
            return {r["name"]: (r.get("relmse_stderr") or float("nan")) / r["relmse"] if r.get("relmse") else float("nan")
                    for r in s["regions"]}
    return None


def paired_regions(runs, block_key, num, den, per_region, combine):
    """{map: {region: combine(num's value, den's value)}}: `per_region(block, strategy)` gives a
    strategy's {region: value} (None when absent); maps lacking either strategy are left out."""
    out = {}
    for name, m in runs:
        block = m.get(block_key)
        if not block:
            continue
        a, b = per_region(block, num), per_region(block, den)
        if a is None or b is None:
            continue
        out[name] = {r: combine(a[r], b.get(r)) for r in a}
    return out


def ratio_relerr(runs, block_key, num, den):
    """{map: {region: relative standard error of relMSE(num) / relMSE(den)}} (errors taken independent)."""
    return paired_regions(runs, block_key, num, den, region_relerr, lambda x, y: math.sqrt(x ** 2 + y ** 2))


def ratio_table(runs, block_key, num, den):
    """{map: {region: relMSE(num) / relMSE(den)}} for the runs that have both strategies."""
    return paired_regions(runs, block_key, num, den, lambda block, s: region_relmse(block, s)[0],
                          lambda x, y: x / y if x and y else float("nan"))


def efficiency_ratio(runs, num, den):
    """Per-object efficiency ratio eff(den) / eff(num) at equal spp = relMSE(num) t(num) / (relMSE(den) t(den))."""
    out = {}
    for name, m in runs:
        a, sa = region_relmse(m["equal_spp"], num)
        b, sb = region_relmse(m["equal_spp"], den)
        if a is None or b is None:
            continue
        out[name] = {r: a[r] * sa["seconds"] / (b[r] * sb["seconds"]) for r in a}
    return out


def md_rows(table, regions, maps, relerr=None):
    lines = []
    for mp in maps:
        if mp in table:
            lines.append(f"| {mp} | " + " | ".join(f(table[mp].get(r)) for r in regions) + " |")
    pooled = [geomean([table[mp].get(r) for mp in maps if mp in table]) for r in regions]
    medians = [median([table[mp].get(r) for mp in maps if mp in table]) for r in regions]
    lines.append("| **pooled** (geometric mean) | " + " | ".join(f"**{f(p)}**" for p in pooled) + " |")
    lines.append("| median | " + " | ".join(f(p) for p in medians) + " |")
    if relerr:
        # 1 standard error of the pooled value: the log of a geometric mean of k ratios has
        # s.e. sqrt(sum of squared relative errors) / k.
        cells = []
        for r in regions:
            errs = [relerr[mp][r] for mp in maps if mp in relerr and math.isfinite(relerr[mp].get(r, float("nan")))]
            cells.append(f"{100 * math.sqrt(sum(e * e for e in errs)) / len(errs):.0f}% / {100 * median(errs):.0f}%"
                         if errs else "-")
        lines.append("| s.e. pooled / per map (median) | " + " | ".join(cells) + " |")
    return lines, dict(zip(regions, pooled))


def load_runs(paths):
    """[(map name, metrics)] sorted by map name."""
    runs = []
    for p in paths:
        with open(p, encoding="utf-8") as fh:
            m = json.load(fh)
        runs.append((os.path.splitext(os.path.basename(m["environment"]))[0], m))
    runs.sort(key=lambda x: x[0])
    return runs


def pooled_row(runs, block_key, num, den, regions):
    """Geometric mean over the maps of relMSE(num) / relMSE(den), per region (None without the strategies)."""
    t = ratio_table(runs, block_key, num, den)
    if not t:
        return None
    return [geomean([t[mp].get(r) for mp in t]) for r in regions]


SUMMARY_ROWS = [
    ("equal_spp", "mis", "product", "equal spp, mis / product"),
    ("equal_spp", "mis-comp", "product", "equal spp, mis-comp / product"),
    ("equal_time", "mis", "product", "equal time, mis / product"),
    ("equal_time", "mis-comp", "product", "equal time, mis-comp / product"),
]


def summary(args):
    """The pooled fig1 table over one or two paper-table runs (see the module's docstring)."""
    groups = []
    for a in args:
        name, _, d = a.partition("=") if "=" in a else ("", "", a)
        runs = load_runs(sorted(glob.glob(os.path.join(d, "*", "metrics.json"))))
        if not runs:
            print(f"paper_table.py: no */metrics.json under {d}", file=sys.stderr)
            return 2
        m0 = runs[0][1]
        groups.append((name or m0.get("sampler", "independent"), runs))
    regions = [r["name"] for r in groups[0][1][0][1]["regions"]]
    out = ["| comparison (pooled over the maps) | run | " + " | ".join(label(r) for r in regions) + " |",
           "|---|---|" + "---|" * len(regions)]
    rows = {}
    for key, num, den, title in SUMMARY_ROWS:
        for name, runs in groups:
            row = pooled_row(runs, key, num, den, regions)
            if row is None:
                continue
            rows[(key, num, den, name)] = row
            out.append(f"| {title} | {name} | " + " | ".join(f(x) for x in row) + " |")
        if len(groups) == 2 and (key, num) == ("equal_spp", "mis"):
            a, b = (rows.get((key, num, den, g[0])) for g in groups)
            if a and b:
                out.append(f"| {title} | {groups[0][0]} / {groups[1][0]} | "
                           + " | ".join(f(x / y) if x and y else "-" for x, y in zip(a, b)) + " |")
    out.append("")
    out.append("| run | maps | seeds | spp | reference | overhead wall / CPU (pooled) | worst sphere-map, product / mis at equal spp |")
    out.append("|---|---|---|---|---|---|---|")
    for name, runs in groups:
        m0 = runs[0][1]
        walls = [m["overhead"]["ratio"] for _, m in runs if m.get("overhead")]
        cpus = [m["overhead"].get("ratio_cpu") for _, m in runs if m.get("overhead")]
        t = ratio_table(runs, "equal_spp", "product", "mis")
        worst = max(((v, mp, r) for mp in t for r, v in t[mp].items() if math.isfinite(v)), default=None)
        w = f"{f(worst[0])}x ({worst[1]}, {label(worst[2])})" if worst else "-"
        out.append(f"| {name} | {len(runs)} | {len(m0.get('seeds', [0]))} | {m0['equal_spp']['spp']} | "
                   f"{m0['reference']['strategy']} at {m0['reference']['spp']} spp | {f(geomean(walls), 3)} / "
                   f"{f(geomean(cpus), 3)} | {w} |")
    print("\n".join(out))
    return 0


def main(paths):
    if paths and paths[0] == "--summary":
        return summary(paths[1:]) if 1 <= len(paths) - 1 <= 2 else usage()
    runs = load_runs(paths)
    if not runs:
        print("paper_table.py: no metrics.json given", file=sys.stderr)
        return 2
    maps = [n for n, _ in runs]
    regions = [r["name"] for r in runs[0][1]["regions"]]
    head = "| map | " + " | ".join(label(r) for r in regions) + " |"
    sep = "|---|" + "---|" * len(regions)
    m0 = runs[0][1]
    out = []
    et = m0.get("equal_time") or {}
    out.append(f"Scene fig1 at {m0['width']}x{m0['height']}, {m0['integrator']} lighting, {m0['heuristic']} heuristic, "
               f"{m0.get('sampler', 'independent')} sampler, relMSE the median over {len(m0.get('seeds', [0]))} seed(s), "
               f"{m0['threads']} threads; equal spp = {m0['equal_spp']['spp']} spp; equal time = each strategy gets "
               f"the seconds mis took at {m0['equal_spp']['spp']} spp; reference: {m0['reference']['strategy']} at "
               f"{m0['reference']['spp']} spp with another seed (its own noise adds ~{f(100 * geomean([m['reference']['relmse_floor'] / r['relmse'] for _, m in runs for r in m['equal_spp']['strategies'] if r['strategy'] == 'mis']), 1)}% "
               f"of mis's relMSE); oracle: {m0['oracle_options']['resolution']}^2 cells x "
               f"{m0['oracle_options']['directions']} first-pass point(s) per cell. Columns: the GGX conductor spheres by roughness "
               f"(alpha), then the diffuse and the glass (alpha 0.2) sphere. relMSE over each sphere's pixels.")
    out.append("")
    pooled = {}
    sections = [
        ("equal_spp", "mis", "product", "Equal spp: relMSE(mis) / relMSE(product) (> 1: product better)"),
        ("equal_spp", "mis-comp", "product", "Equal spp: relMSE(mis-comp) / relMSE(product)"),
        ("equal_time", "mis", "product", "Equal time: relMSE(mis) / relMSE(product)"),
        ("equal_time", "mis-comp", "product", "Equal time: relMSE(mis-comp) / relMSE(product)"),
        ("equal_spp", "product", "oracle", "Gap to the oracle at equal spp: relMSE(product) / relMSE(oracle) (> 1: room left)"),
    ]
    for key, num, den, title in sections:
        t = ratio_table(runs, key, num, den)
        if not t:
            continue
        out.append(f"**{title}**")
        out.append("")
        out.append(head)
        out.append(sep)
        lines, pooled[(key, num, den)] = md_rows(t, regions, maps, ratio_relerr(runs, key, num, den))
        out.extend(lines)
        out.append("")

    # Overhead
    out.append("**Overhead: time(product) / time(mis) at equal spp** (sampling loop; wall = minimum of the timing "
               "repeats; CPU = process CPU seconds, less sensitive to other load on the machine)")
    out.append("")
    out.append("| map | wall | CPU | mis s | product s |")
    out.append("|---|---|---|---|---|")
    walls, cpus = [], []
    for name, m in runs:
        o = m.get("overhead")
        if not o:
            continue
        walls.append(o["ratio"])
        cpus.append(o.get("ratio_cpu"))
        out.append(f"| {name} | {f(o['ratio'], 3)} | {f(o.get('ratio_cpu'), 3)} | {f(o['mis_seconds'], 3)} | {f(o['product_seconds'], 3)} |")
    ow, oc = geomean(walls), geomean(cpus)
    out.append(f"| **pooled** (geometric mean) | **{f(ow, 3)}** | **{f(oc, 3)}** | | |")
    out.append("")

    # Targets
    eff_mis = efficiency_ratio(runs, "mis", "product")
    eff_comp = efficiency_ratio(runs, "mis-comp", "product")
    out.append("**Targets** (issue 4)")
    out.append("")
    out.append("| target | measured | verdict |")
    out.append("|---|---|---|")
    spp_mis = pooled.get(("equal_spp", "mis", "product"), {})
    for r in ("conductor-0.2", "conductor-0.3"):
        v = spp_mis.get(r, float("nan"))
        ok = v >= TARGET_MIS_OVER_PRODUCT
        out.append(f"| product relMSE <= 0.55x mis at alpha {label(r)}, pooled, equal spp | {f(1 / v if v else float('nan'))}x "
                   f"(mis/product {f(v)}) | {'met' if ok else 'not met'}"
                   f"{'' if ok else f' (by {f(100 * (1 / v / 0.55 - 1), 0)}%)'} |")
    t = ratio_table(runs, "equal_spp", "product", "mis")
    te = ratio_relerr(runs, "equal_spp", "product", "mis")
    worst = max(((v, mp, r) for mp in t for r, v in t[mp].items() if math.isfinite(v)), default=(float("nan"), "", ""))
    bad = sorted(((v, mp, r) for mp in t for r, v in t[mp].items() if math.isfinite(v) and v > TARGET_WORST_PRODUCT_OVER_MIS),
                 reverse=True)
    ok = not bad
    # above 1.1 by more than two standard errors of the ratio (for the noise of one seed)
    sig = [(v, mp, r) for v, mp, r in bad if te.get(mp) and v / (1 + 2 * te[mp][r]) > TARGET_WORST_PRODUCT_OVER_MIS]
    detail = ", ".join(f"{mp} {label(r)} {f(v)}x" for v, mp, r in bad[:10]) + (" ..." if len(bad) > 10 else "")
    detail += f"; {len(sig)} of them by more than 2 s.e." if te else ""
    out.append(f"| no sphere of any map more than 1.1x worse than mis (equal spp) | worst {f(worst[0])}x "
               f"({worst[1]}, {label(worst[2])}); {len(bad)} of {sum(len(v) for v in t.values())} sphere-maps above 1.1x"
               f"{': ' + detail if bad else ''} | {'met' if ok else 'not met'} |")
    for rname in ("conductor-0.1", "conductor-0.2", "conductor-0.3", "conductor-0.5"):
        a = geomean([eff_mis[mp][rname] for mp in eff_mis])
        b = geomean([eff_comp[mp][rname] for mp in eff_comp])
        wins_a = sum(1 for mp in eff_mis if eff_mis[mp][rname] > 1)
        wins_b = sum(1 for mp in eff_comp if eff_comp[mp][rname] > 1)
        ok = a > 1 and b > 1
        out.append(f"| efficiency of product above mis and mis-comp at alpha {label(rname)} (pooled) | "
                   f"eff(product)/eff(mis) {f(a)} ({wins_a}/{len(eff_mis)} maps), eff(product)/eff(mis-comp) {f(b)} "
                   f"({wins_b}/{len(eff_comp)} maps) | {'met' if ok else 'not met'} |")
    ok10, ok5 = ow <= TARGET_OVERHEAD, ow <= 1.05
    out.append(f"| overhead <= 10% on fig1, direct (goal 5%) | {f(100 * (ow - 1), 1)}% wall, {f(100 * (oc - 1), 1)}% CPU "
               f"(pooled) | {'met' if ok10 else 'not met'}{'' if ok10 else f' (by {f(100 * (ow - TARGET_OVERHEAD), 1)} points)'}"
               f"; goal 5% {'met' if ok5 else 'not met'} |")
    out.append("")
    print("\n".join(out))
    return 0


def usage():
    print("usage: paper_table.py METRICS.json ... | --summary [LABEL=]DIR [[LABEL=]DIR]", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
