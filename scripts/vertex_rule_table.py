#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""The table of docs/assets.md, "Product where it pays: by the vertex's material": `envpis compare`
runs of one scene under several maps, one directory per --product-max-roughness value A:

    OUT/A<A>/<scene>--<map>/metrics.json      (strategies mis, mis-comp, product; --seeds 3)

Prints, per A and map, the CPU-time overhead time(product) / time(mis) of the equal-spp renders, and
per object the relMSE (median over seeds) / relMSE without the object's worst 0.1% of pixels for
mis, mis-comp and product; then per A the efficiency product / mis-comp, 1 / (relMSE x CPU seconds),
per object and pooled (geometric mean) over the objects and maps, with relMSE and trimmed relMSE.

    python3 scripts/vertex_rule_table.py OUT
"""
import glob
import json
import math
import os
import sys


def geomean(xs):
    xs = [x for x in xs if x > 0 and math.isfinite(x)]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def f(x):
    return "nan" if not math.isfinite(x) else f"{x:.3g}"


def runs(out):
    by_a = {}
    for path in sorted(glob.glob(os.path.join(out, "A*", "*--*", "metrics.json"))):
        a = os.path.basename(os.path.dirname(os.path.dirname(path)))[1:]
        scene_map = os.path.basename(os.path.dirname(path))
        by_a.setdefault(a, {})[scene_map] = json.load(open(path))
    return dict(sorted(by_a.items(), key=lambda kv: float(kv[0])))  # "inf" sorts last


def table(by_a):
    """The two tables for the runs of one scene: by_a maps A to {scene--map: metrics}."""
    regions = [r["name"] for r in next(iter(next(iter(by_a.values())).values()))["regions"]]
    print("| A | scene--map | CPU overhead product/mis | strategy | " + " | ".join(regions) + " |")
    print("|---|---|---|---|" + "---|" * len(regions))
    pooled, overheads = {}, {}
    for a, maps in by_a.items():
        for scene_map, m in maps.items():
            s = {x["strategy"]: x for x in m["equal_spp"]["strategies"]}
            ov = s["product"]["cpu_seconds"] / s["mis"]["cpu_seconds"]
            overheads.setdefault(a, []).append(ov)
            for name in ("mis", "mis-comp", "product"):
                cells = [f"{f(r['relmse'])} / {f(r['relmse_trimmed'])}" for r in s[name]["regions"]]
                print(f"| {a} | {scene_map} | {f(ov)} | {name} | " + " | ".join(cells) + " |")
            tc, tp = s["mis-comp"]["cpu_seconds"], s["product"]["cpu_seconds"]
            for rc, rp in zip(s["mis-comp"]["regions"], s["product"]["regions"]):
                d = pooled.setdefault(a, {}).setdefault(rc["name"], {"eff": [], "trim": []})
                d["eff"].append(rc["relmse"] * tc / (rp["relmse"] * tp))
                d["trim"].append(rc["relmse_trimmed"] * tc / (rp["relmse_trimmed"] * tp))
    print()
    print("| A | " + " | ".join(regions) + " | pooled | overheads (CPU) |")
    print("|---|" + "---|" * (len(regions) + 2))
    for a, objs in pooled.items():
        cells = [f"{f(geomean(o['eff']))} / {f(geomean(o['trim']))}" for o in objs.values()]
        all_eff = [e for o in objs.values() for e in o["eff"]]
        all_trim = [e for o in objs.values() for e in o["trim"]]
        print(f"| {a} | " + " | ".join(cells) + f" | {f(geomean(all_eff))} / {f(geomean(all_trim))} | " +
              ", ".join(f(x) for x in overheads[a]) + " |")
    print()


def main(out):
    scenes = {}
    for a, maps in runs(out).items():
        for scene_map, m in maps.items():
            scenes.setdefault(scene_map.partition("--")[0], {}).setdefault(a, {})[scene_map] = m
    for scene, by_a in sorted(scenes.items()):
        print(f"### {scene}\n")
        table(by_a)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "out/vr")
