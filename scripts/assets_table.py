#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Aggregates the `envpis compare` runs of scripts/assets-bench.sh (asset scenes x maps, path integrator,
medians over seeds) into the markdown tables of docs/assets.md, once for the unregularized runs (OUT)
and once for the regularized ones (OUT/regularized, with REGULARIZE=1), each under its own heading:

  1. per scene and map: overhead time(product) / time(mis) and whole-image relMSE ratios;
  2. per object (pooled over the maps): relMSE ratios mis / product and mis-comp / product at equal
     spp, and efficiency ratios (1 / (relMSE x time): product over mis and over mis-comp);
  3. per object, the figures one caustic pixel cannot decide (relMSE without each object's worst 0.1%
     of pixels, the median per-pixel error), the tail (worst pixel, pixels 10x off) and the share of
     the variance that light samples brought (metrics.h);
  4. the issue's targets, met or not, with relMSE and with the trimmed relMSE;
  5. (when OUT/widen-*/ exists) product with and without widen_roughness on normal-mapped objects.

    python3 scripts/assets_table.py OUT > OUT/table.md

Ratios > 1 favour product. "Pooled" is the geometric mean over maps (and objects where stated).
Glossy objects are those whose main lobe has GGX alpha in [0.05, 0.5] (GLOSSY below, from the scenes'
materials: alpha = roughness^2 for pbr materials).
"""
import glob
import json
import math
import os
import sys

from paper_table import f, geomean, median  # the fig1 tables' pooling and formatting

TARGET_EFFICIENCY_OVER_MIS_COMP = 1.5  # pooled over the glossy objects
TARGET_OVERHEAD = 1.10                 # time(product) / time(mis); goal 1.05

# Main-lobe GGX alpha of the objects of scenes/assets-*.json (None: diffuse-dominated or mixed).
ALPHA = {
    "bunny": 0.1, "suzanne": 0.05, "clay": None, "plastic": 0.15, "floor": None,
    "engine": 0.2025, "chrome": 0.0225, "glass": 0.0625, "lacquer": 0.04,
}


# Objects whose alpha differs from the table above in their scene (the close-up's copper Suzanne).
SCENE_ALPHA = {("suzanne-closeup", "suzanne"): 0.1, ("suzanne-closeup", "steel"): 0.2}


def alpha_of(scene, obj):
    if (scene, obj) in SCENE_ALPHA:
        return SCENE_ALPHA[(scene, obj)]
    if obj in ALPHA and not (scene == "clearcoat" and obj == "floor"):
        return ALPHA[obj]
    if obj.endswith("_Base"):
        return 0.19   # roughness 0.44
    if obj.endswith("_Coated") or obj.endswith("_Coating"):
        return 0.001  # roughness 0.03 (clear coats): near-mirror
    return None


def strategies(block):
    return {s["strategy"]: s for s in block["strategies"]}


def load(out, prefix):
    runs = {}
    for path in sorted(glob.glob(os.path.join(out, prefix + "*", "metrics.json"))):
        scene, _, env = os.path.basename(os.path.dirname(path))[len(prefix):].partition("--")
        runs[(scene, env)] = json.load(open(path))
    return runs


def regularization_label(runs):
    """The runs' path regularization in words (metrics.json "regularization")."""
    labels = set()
    for j in runs.values():
        r = j.get("regularization")
        if not j.get("regularized") or not r:
            labels.add("unregularized")
            continue
        parts = []
        if r["clamp_direct"] > 0:
            parts.append(f"clamp direct {r['clamp_direct']:g}")
        if r["clamp_indirect"] > 0:
            parts.append(f"clamp indirect {r['clamp_indirect']:g}")
        if r["caustics"] != "reflective,refractive":
            parts.append(f"caustics {r['caustics']}")
        if r["filter_glossy"] > 0:
            parts.append(f"filter glossy {r['filter_glossy']:g}")
        labels.add("regularized: " + ", ".join(parts))
    return "; ".join(sorted(labels)) or "no runs"


def ratio(a, b):
    return a / b if a is not None and b is not None and b > 0 and math.isfinite(a) and math.isfinite(b) else float("nan")


def robust_table(runs):
    """Per object, pooled over the maps: the figures one caustic pixel cannot decide, the tail and the
    light samples' share of the variance."""
    rows = {}
    for (scene, env), j in sorted(runs.items()):
        s = strategies(j["equal_spp"])
        c, p = s["mis-comp"], s["product"]
        for rc, rp in zip(c["regions"], p["regions"]):
            if not rp.get("relmse") or rp["relmse"] <= 0:
                continue
            d = rows.setdefault((scene, rp["name"]), {k: [] for k in ("rel", "trim", "med", "eff_trim", "share_c", "share_p")} | {"tail_c": 0, "tail_p": 0, "worst_c": 0.0, "worst_p": 0.0})
            d["rel"].append(ratio(rc["relmse"], rp["relmse"]))
            d["trim"].append(ratio(rc.get("relmse_trimmed"), rp.get("relmse_trimmed")))
            d["med"].append(ratio(rc.get("median_rel_sq_error"), rp.get("median_rel_sq_error")))
            d["eff_trim"].append(ratio(rc.get("relmse_trimmed", 0) * c["seconds"], rp.get("relmse_trimmed", 0) * p["seconds"]))
            d["share_c"].append(rc.get("light_variance_share"))
            d["share_p"].append(rp.get("light_variance_share"))
            d["tail_c"] += rc.get("pixels_over_10x") or 0
            d["tail_p"] += rp.get("pixels_over_10x") or 0
            d["worst_c"] = max(d["worst_c"], rc.get("max_rel_sq_error_worst") or 0)
            d["worst_p"] = max(d["worst_p"], rp.get("max_rel_sq_error_worst") or 0)
    print("\n### Per object: robust figures, tail and light share (equal spp, pooled over the maps)\n")
    print("Ratios mis-comp / product (> 1 favours product): relMSE, relMSE without the object's worst 0.1% of "
          "pixels (\"trimmed\"), median per-pixel error; efficiency product / mis-comp from the trimmed relMSE. "
          "Light share: the part of the object's variance that light samples brought (median over maps). Tail: "
          "pixels more than 10x off (median over seeds, summed over maps) and the worst pixel's relative squared "
          "error (worst seed and map).\n")
    print("| scene | object | relMSE | trimmed relMSE | median error | eff. (trimmed) | light share mis-comp | light share product | px > 10x mis-comp / product | worst pixel mis-comp / product |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    glossy = []
    for (scene, obj), d in sorted(rows.items()):
        a = alpha_of(scene, obj)
        if a is not None and 0.05 <= a <= 0.5:
            glossy += d["eff_trim"]
        print(f"| {scene} | {obj} | {f(geomean(d['rel']))} | {f(geomean(d['trim']))} | {f(geomean(d['med']))} | "
              f"{f(geomean(d['eff_trim']))} | {f(median(d['share_c']))} | {f(median(d['share_p']))} | "
              f"{d['tail_c']:g} / {d['tail_p']:g} | {d['worst_c']:.3g} / {d['worst_p']:.3g} |")
    return geomean(glossy)


def main(out):
    report(out)
    reg = os.path.join(out, "regularized")  # scripts/assets-bench.sh with REGULARIZE=1
    if os.path.isdir(reg):
        print("\n")
        report(reg)
    widen_table(out)


def report(out):
    runs = load(out, "")
    runs = {k: v for k, v in runs.items() if not k[0].startswith("widen-")}
    label = regularization_label(runs)
    print(f"## {label[0].upper() + label[1:]}\n")
    print("### Per scene and map (path integrator, equal spp; medians over seeds)\n")
    print("| scene | map | overhead product/mis | relMSE mis/product | relMSE mis-comp/product | eff. product/mis | eff. product/mis-comp | equal time: relMSE mis/product | equal time: relMSE mis-comp/product |")
    print("|---|---|---|---|---|---|---|---|---|")
    overheads = []
    per_object = {}  # (scene, object) -> lists
    for (scene, env), j in sorted(runs.items()):
        s = strategies(j["equal_spp"])
        m, c, p = s["mis"], s["mis-comp"], s["product"]
        eff = lambda a, b: (a["relmse"] * a["seconds"]) / (b["relmse"] * b["seconds"])
        overheads.append(j["overhead"]["ratio"])
        t = strategies(j["equal_time"]) if j.get("equal_time") else {}
        et = lambda a: f(t[a]["relmse"] / t["product"]["relmse"]) if a in t and "product" in t else "-"
        print(f"| {scene} | {env} | {f(j['overhead']['ratio'])} | {f(m['relmse'] / p['relmse'])} | "
              f"{f(c['relmse'] / p['relmse'])} | {f(eff(m, p))} | {f(eff(c, p))} | {et('mis')} | {et('mis-comp')} |")
        for rm, rc, rp in zip(m["regions"], c["regions"], p["regions"]):
            if rm["relmse"] <= 0 or rp["relmse"] <= 0:
                continue
            d = per_object.setdefault((scene, rm["name"]), {"mis": [], "comp": [], "eff_mis": [], "eff_comp": [], "worse": 0, "worse_noise": 0,
                                                                    "worse_comp": 0, "worse_comp_noise": 0, "n": 0})
            d["mis"].append(rm["relmse"] / rp["relmse"])
            d["comp"].append(rc["relmse"] / rp["relmse"])
            d["eff_mis"].append(rm["relmse"] * m["seconds"] / (rp["relmse"] * p["seconds"]))
            d["eff_comp"].append(rc["relmse"] * c["seconds"] / (rp["relmse"] * p["seconds"]))
            d["n"] += 1
            # Worse than mis: the median over seeds is higher; beyond noise: by more than twice the
            # combined standard error of the two medians.
            se = math.hypot(rm.get("relmse_stderr", 0), rp.get("relmse_stderr", 0))
            d["worse"] += rp["relmse"] > rm["relmse"]
            d["worse_noise"] += rp["relmse"] > rm["relmse"] + 2 * se
            se_c = math.hypot(rc.get("relmse_stderr", 0), rp.get("relmse_stderr", 0))
            d["worse_comp"] += rp["relmse"] > rc["relmse"]
            d["worse_comp_noise"] += rp["relmse"] > rc["relmse"] + 2 * se_c
    print("\n### Per object, pooled over the maps (geometric means; min over maps in brackets)\n")
    print("| scene | object | alpha | maps | relMSE mis/product | relMSE mis-comp/product | eff. product/mis | eff. product/mis-comp | maps where product is worse than mis (beyond 2 stderr) | than mis-comp (beyond 2 stderr) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    glossy_eff_comp, worse_total, worse_noise_total, object_maps = [], 0, 0, 0
    worse_comp_total, worse_comp_noise_total = 0, 0
    for (scene, obj), d in sorted(per_object.items()):
        a = alpha_of(scene, obj)
        if a is not None and 0.05 <= a <= 0.5:
            glossy_eff_comp += d["eff_comp"]
        worse_total += d["worse"]
        worse_noise_total += d["worse_noise"]
        worse_comp_total += d["worse_comp"]
        worse_comp_noise_total += d["worse_comp_noise"]
        object_maps += d["n"]
        print(f"| {scene} | {obj} | {f(a, 3) if a is not None else 'mixed or textured'} | {d['n']} | {f(geomean(d['mis']))} ({f(min(d['mis']))}) | "
              f"{f(geomean(d['comp']))} ({f(min(d['comp']))}) | {f(geomean(d['eff_mis']))} | {f(geomean(d['eff_comp']))} | {d['worse']} ({d['worse_noise']}) | "
              f"{d['worse_comp']} ({d['worse_comp_noise']}) |")
    pooled = geomean(glossy_eff_comp)
    pooled_trimmed = robust_table(runs)
    ov = median(overheads)
    print("\n### Targets\n")
    print("| target | measured | met |")
    print("|---|---|---|")
    print(f"| efficiency product / mis-comp >= {TARGET_EFFICIENCY_OVER_MIS_COMP}, pooled over glossy objects (alpha 0.05-0.5) | {f(pooled)} | {'yes' if pooled >= TARGET_EFFICIENCY_OVER_MIS_COMP else 'no'} |")
    print(f"| the same from the trimmed relMSE (worst 0.1% of each object's pixels left out) | {f(pooled_trimmed)} | {'yes' if pooled_trimmed >= TARGET_EFFICIENCY_OVER_MIS_COMP else 'no'} |")
    print(f"| no object worse than mis (median over seeds) | {worse_total} of {object_maps} object-maps worse ({worse_noise_total} beyond 2 stderr) | {'yes' if worse_total == 0 else 'no'} |")
    print(f"| no object worse than mis-comp beyond 2 standard errors (issue 22) | {worse_comp_total} of {object_maps} object-maps worse, "
          f"{worse_comp_noise_total} beyond 2 stderr | {'yes' if worse_comp_noise_total == 0 else 'no'} |")
    print(f"| overhead time(product) / time(mis) <= {TARGET_OVERHEAD} (median over scene-maps) | {f(ov)} (max {f(max(overheads) if overheads else float('nan'))}) | {'yes' if ov <= TARGET_OVERHEAD else 'no'} |")


def widen_table(out):
    widen = load(out, "widen-")
    if widen:
        print("\n### widen_roughness on normal-mapped objects (product, equal spp, medians over seeds)\n")
        print("| scene | map | object | relMSE without | relMSE with | without / with |")
        print("|---|---|---|---|---|---|")
        ratios = []
        for (scene, env), j in sorted(widen.items()):
            if not scene.endswith("-on"):
                continue
            off = widen.get((scene[:-3] + "-off", env))
            if not off:
                continue
            on_r = {r["name"]: r["relmse"] for r in strategies(j["equal_spp"])["product"]["regions"]}
            off_r = {r["name"]: r["relmse"] for r in strategies(off["equal_spp"])["product"]["regions"]}
            for name in sorted(on_r):
                if not (name == "floor" or "Norm" in name) or not on_r[name] > 0:
                    continue
                ratios.append(off_r[name] / on_r[name])
                print(f"| {scene[:-3]} | {env} | {name} | {off_r[name]:.4g} | {on_r[name]:.4g} | {f(off_r[name] / on_r[name])} |")
        print(f"\nPooled (geometric mean) without / with: {f(geomean(ratios))} over {len(ratios)} object-maps.")


if __name__ == "__main__":
    main(sys.argv[1])
