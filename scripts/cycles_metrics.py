# SPDX-License-Identifier: Apache-2.0
"""The metrics and the markdown tables of scripts/cycles_compare.py (docs/cycles.md), pure functions only:
no files, no renders, so tests/test_cycles_metrics.py checks them without Blender.

Per-pixel error, as `envpis compare` (apps/envpis/metrics.h): e = mean over R, G, B of
(I - R)^2 / (R^2 + 0.01), R the renderer's own reference. Over the sphere's pixels:
  relMSE        the mean of e;
  quartiles     the mean of e over each quarter of the sphere's pixels ranked by reference brightness
                (quartile 4 = the brightest: the highlight, where the gap to Cycles was);
  worst         the largest e;
  over_10x      how many pixels have e > 100 ("more than 10x off").
Each is a median over the seeds. The slope is the least-squares slope of log relMSE against log spp
over the measured spp in [16, 256]; efficiency = 1 / (relMSE x spp x seconds per spp).
"""
import math

import numpy as np

REL_EPSILON = 0.01           # apps/envpis/metrics.h kRelEpsilon
TAIL_THRESHOLD = 100.0       # apps/envpis/metrics.h kTailThreshold: e > 100 is "more than 10x off"
SLOPE_RANGE = (16, 256)      # issue 21: the slope from 16 to 256 spp
ORTHO_HEIGHT = 2.2           # film height in world units: the unit sphere fills 1/1.1 of it
CYCLES = "cycles"


# ---- per image ----

def sphere_mask(size, ortho_height=ORTHO_HEIGHT):
    """Pixels whose centre sees the unit sphere through the orthographic camera (envpis's object-id)."""
    c = (np.arange(size) + 0.5) / size * ortho_height - ortho_height / 2
    x, y = np.meshgrid(c, c)
    return x * x + y * y < 1.0


def rel_sq_error(image, ref):
    """e per pixel: [h, w, 3] images -> [h, w]."""
    return np.mean((image - ref) ** 2 / (ref * ref + REL_EPSILON), axis=2)


def brightness_quartiles(brightness):
    """Quartile index 0 (darkest) .. 3 (brightest) of each value of a 1-D array: the values ranked, then
    cut into four parts of equal count (sizes differ by at most one; ties split by position)."""
    order = np.argsort(brightness, kind="stable")
    index = np.empty(len(brightness), dtype=np.int64)
    for q, part in enumerate(np.array_split(order, 4)):
        index[part] = q
    return index


def image_metrics(image, ref, mask, quartile):
    """The metrics of one render. mask: the sphere's pixels; quartile: brightness_quartiles() of the
    sphere's pixels in mask order (the same partition for every renderer of a scene)."""
    e = rel_sq_error(image, ref)
    es = e[mask]
    return {"relmse_sphere": float(es.mean()), "relmse_all": float(e.mean()),
            "quartiles": [float(es[quartile == q].mean()) if np.any(quartile == q) else math.nan for q in range(4)],
            "worst": float(es.max()), "over_10x": int(np.count_nonzero(es > TAIL_THRESHOLD))}


def agreement(cycles_ref, envpis_ref, mask):
    """How far apart the two converged references are on the sphere."""
    c, e = cycles_ref[mask], envpis_ref[mask]
    return {
        "mean_relative_difference": float(np.mean(np.abs(c - e) / (np.abs(e) + REL_EPSILON))),
        "ratio_of_means": float(c.mean() / e.mean()),
        "relmse_cycles_vs_envpis": float(np.mean(np.mean((c - e) ** 2 / (e * e + REL_EPSILON), axis=1))),
        "p95_relative_difference": float(np.percentile(np.mean(np.abs(c - e), axis=1) /
                                                       (np.mean(np.abs(e), axis=1) + REL_EPSILON), 95)),
    }


# ---- over seeds and spp ----

def median(values):
    return float(np.median(values))


def seed_medians(per_seed):
    """Median over seeds of every metric of image_metrics() (quartiles each on its own) and of seconds."""
    out = {k: median([r[k] for r in per_seed])
           for k in ("relmse_sphere", "relmse_all", "worst", "over_10x", "seconds")}
    out["quartiles"] = [median([r["quartiles"][q] for r in per_seed]) for q in range(4)]
    return out


def loglog_slope(spps, values, lo=SLOPE_RANGE[0], hi=SLOPE_RANGE[1]):
    """Least-squares slope of log(value) against log(spp) over the points with lo <= spp <= hi; None with
    fewer than two such points or a value <= 0. -1 for independent samples, steeper when stratified."""
    pts = [(math.log(s), math.log(v)) for s, v in zip(spps, values) if lo <= s <= hi and v is not None and v > 0]
    if len(pts) < 2 or len(pts) != sum(1 for s in spps if lo <= s <= hi):
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx if sxx > 0 else None


def seconds_per_spp(rows):
    """Seconds per sample per pixel: the fastest seed of the largest spp (rows ascending in spp), over
    that spp. Shared by cycles_compare.py and cycles_assets.py."""
    return min(s["seconds"] for s in rows[-1]["seeds"]) / rows[-1]["spp"]


def summarise(rows):
    """rows: [{"spp", "seeds": [image_metrics + "seconds"]}] ascending spp -> adds the medians, the seconds
    per spp, the efficiencies and the slopes; returns {"seconds_per_spp", "slope_sphere", "slope_q4", "spp"}.

    Seconds per spp come from the largest spp (the least timer and start-up noise; Blender's render_time
    has 10 ms steps), its fastest seed (other processes only ever slow a render down)."""
    for r in rows:
        r.update(seed_medians(r["seeds"]))
    rate = seconds_per_spp(rows)
    for r in rows:  # None when the time rounds to 0 or relMSE is 0
        for key in ("sphere", "all"):
            v = r["relmse_" + key]
            r["efficiency_" + key] = 1.0 / (v * r["spp"] * rate) if v > 0 and rate > 0 else None
    spps = [r["spp"] for r in rows]
    return {"seconds_per_spp": rate,
            "slope_sphere": loglog_slope(spps, [r["relmse_sphere"] for r in rows]),
            "slope_q4": loglog_slope(spps, [r["quartiles"][3] for r in rows]),
            "spp": rows}


def ratio(a, b):
    return a / b if a is not None and b is not None and b != 0 else None


def at_spp(renderer, spp):
    for r in renderer["spp"]:
        if r["spp"] == spp:
            return r
    return None


def targets(scene, strategy="envpis product", spps=(64, 256)):
    """Issue 21's targets for one scene, product against Cycles: relMSE ratio <= 1 and brightest-quartile
    ratio <= 1 at each spp, slope at least as steep, efficiency ratio >= 2 at each spp. Each check is
    (value(s), met: bool or None when not measured)."""
    cyc, mine = scene["renderers"].get(CYCLES), scene["renderers"].get(strategy)
    if cyc is None or mine is None:
        return None
    out = {"relmse": [], "q4": [], "efficiency": []}
    for s in spps:
        a, b = at_spp(mine, s), at_spp(cyc, s)
        if a is None or b is None:
            for k in out:
                out[k].append(None)
            continue
        out["relmse"].append(ratio(a["relmse_sphere"], b["relmse_sphere"]))
        out["q4"].append(ratio(a["quartiles"][3], b["quartiles"][3]))
        out["efficiency"].append(ratio(a["efficiency_sphere"], b["efficiency_sphere"]))
    out["slope"] = (mine["slope_sphere"], cyc["slope_sphere"])

    def all_ok(values, good):
        return None if not values or any(v is None for v in values) else all(good(v) for v in values)
    out["met"] = {"relmse": all_ok(out["relmse"], lambda v: v <= 1.0),
                  "q4": all_ok(out["q4"], lambda v: v <= 1.0),
                  "slope": None if None in out["slope"] else out["slope"][0] <= out["slope"][1],
                  "efficiency": all_ok(out["efficiency"], lambda v: v >= 2.0)}
    return out


# ---- markdown ----

def fmt(v, spec=".3g"):
    return "-" if v is None else format(v, spec)


def shown_spp(spps):
    """The spp the tables show: those from 16 up (issue 21's range), or all when none reaches 16."""
    s = [x for x in spps if x >= SLOPE_RANGE[0]]
    return s or list(spps)


def scene_label(scene):
    return "%s, %g" % (scene["map_name"], scene["alpha"])


def results_table(scenes, spps):
    """One table for every scene and renderer (pasted into BENCHMARKS.md)."""
    show = shown_spp(spps)
    lo, hi = show[0], show[-1]
    sl = "/".join(str(s) for s in show)
    cells = ["map, alpha", "renderer", "relMSE %s spp" % sl, "slope %d-%d (brightest q.)" % (lo, hi),
             "brightest quartile %s spp" % sl, "quartiles 1 / 2 / 3 at %d spp" % hi, "ms/spp",
             "efficiency vs Cycles %s spp" % sl, "worst pixel e %d / %d spp" % (lo, hi),
             "pixels 10x off %d / %d spp" % (lo, hi)]
    lines = ["| " + " | ".join(cells) + " |", "|" + "---|" * len(cells)]
    for scene in scenes:
        first = True
        cyc = scene["renderers"].get(CYCLES)
        for key, r in scene["renderers"].items():
            rows = [at_spp(r, s) for s in show]
            crow = [at_spp(cyc, s) if cyc else None for s in show]
            eff = [fmt(ratio(m["efficiency_sphere"], c["efficiency_sphere"]) if m and c else None, ".2f")
                   for m, c in zip(rows, crow)]
            top = rows[-1]
            lines.append("| %s | %s | %s | %s (%s) | %s | %s | %.2f | %s | %s / %s | %s / %s |" % (
                scene_label(scene) if first else "", "Cycles" if key == CYCLES else key.replace("envpis ", ""),
                " / ".join(fmt(x["relmse_sphere"]) for x in rows), fmt(r["slope_sphere"], ".2f"),
                fmt(r["slope_q4"], ".2f"), " / ".join(fmt(x["quartiles"][3]) for x in rows),
                " / ".join(fmt(v) for v in top["quartiles"][:3]), 1000 * r["seconds_per_spp"], " / ".join(eff),
                fmt(rows[0]["worst"]), fmt(top["worst"]), fmt(rows[0]["over_10x"], "g"), fmt(top["over_10x"], "g")))
            first = False
    return "\n".join(lines) + "\n"


def targets_table(scenes):
    """Issue 21's targets, product against Cycles, one row per scene."""
    def verdict(ok):
        return "-" if ok is None else ("met" if ok else "**not met**")

    head = ["map, alpha", "relMSE product / Cycles 64 / 256 spp (<= 1)", "brightest quartile 64 / 256 (<= 1)",
            "slope product / Cycles (as steep)", "efficiency product / Cycles 64 / 256 (>= 2)"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for scene in scenes:
        t = targets(scene)
        if t is None:
            continue
        m = t["met"]
        lines.append("| %s | %s: %s | %s: %s | %s / %s: %s | %s: %s |" % (
            scene_label(scene), " / ".join(fmt(v, ".2f") for v in t["relmse"]), verdict(m["relmse"]),
            " / ".join(fmt(v, ".2f") for v in t["q4"]), verdict(m["q4"]),
            fmt(t["slope"][0], ".2f"), fmt(t["slope"][1], ".2f"), verdict(m["slope"]),
            " / ".join(fmt(v, ".2f") for v in t["efficiency"]), verdict(m["efficiency"])))
    return "\n".join(lines) + "\n"


def markdown(settings, scenes, note):
    """The whole report: settings, the results table, the targets table, the references' agreement."""
    s = settings
    lines = ["# Cycles vs envpis, matched sphere scenes", "",
             "%dx%d, orthographic, direct light, %d threads; envpis `--sampler %s --env-filter nearest`, "
             "Cycles %s; references: Cycles and envpis %s at %d spp; each renderer against its own reference; "
             "medians over %d seed(s). relMSE over the sphere's pixels; quartiles of the sphere's pixels by "
             "reference brightness (the mean of the two references; 4 = brightest); slope: least squares of "
             "log relMSE on log spp over %d-%d spp; efficiency = 1 / (relMSE x spp x ms per spp), relative to "
             "Cycles'; worst pixel e and pixels 10x off (e > 100) over the sphere. %s"
             % (s["size"], s["size"], s["threads"], s["sampler"], s["pattern"], s["ref_strategy"], s["ref_spp"],
                s["seeds"], SLOPE_RANGE[0], SLOPE_RANGE[1], note), "",
             results_table(scenes, s["spp"]),
             "Issue 21's targets, product against Cycles:", "", targets_table(scenes),
             "Converged references, Cycles vs envpis on the sphere (a check that the scenes match):", ""]
    for scene in scenes:
        ag = scene["agreement"]
        lines.append("- %s: mean relative difference %.4f, ratio of means %.4f, 95th percentile %.4f." % (
            scene_label(scene), ag["mean_relative_difference"], ag["ratio_of_means"],
            ag["p95_relative_difference"]))
    return "\n".join(lines) + "\n"


# ---- regions (objects) of a whole scene: scripts/cycles_assets.py ----

TRIM_FRACTION = 0.001        # the robust relMSE leaves out each region's top 0.1% of pixels


def trimmed_count(n):
    """How many of a region's n pixels the robust relMSE leaves out: ceil(n / 1000), so a region of up
    to 1000 pixels loses its worst one (a lone caustic pixel), and none when n < 2."""
    return 0 if n < 2 else int(math.ceil(n * TRIM_FRACTION))


def region_metrics(e):
    """Metrics of one region from its per-pixel errors e (1-D): relMSE, the robust figures (relMSE
    without the top 0.1% of pixels; the median per-pixel error) and the tail (worst pixel, pixels 10x
    off). None for an empty region."""
    n = e.size
    if n == 0:
        return None
    k = trimmed_count(n)
    kept = np.sort(e)[:n - k]
    return {"pixels": int(n), "relmse": float(e.mean()), "relmse_trimmed": float(kept.mean()),
            "median": float(np.median(e)), "worst": float(e.max()),
            "over_10x": int(np.count_nonzero(e > TAIL_THRESHOLD))}


def regions_metrics(image, ref, regions):
    """{region name: region_metrics} of one render against its reference; regions: {name: [h, w] bool}."""
    e = rel_sq_error(image, ref)
    return {name: region_metrics(e[mask]) for name, mask in regions.items()}


def region_masks(ids, groups):
    """{"all": everything, name: pixels whose centre sees one of the object's ids}; ids: [h, w] of the
    object-id AOV (-1 = environment); groups: [(name, [ids])]. Objects without a pixel are left out."""
    masks = {"all": np.ones(ids.shape, dtype=bool)}
    for name, members in groups:
        m = np.isin(ids, members)
        if m.any():
            masks[name] = m
    return masks


METRICS = ("relmse", "relmse_trimmed", "median", "worst", "over_10x")


def summarise_regions(rows):
    """rows: [{"spp", "seeds": [{"seconds", "regions": {name: region_metrics}}]}], ascending spp ->
    per row "regions": medians over seeds of every metric, and the efficiencies 1 / (relMSE x seconds)
    on the plain and the trimmed relMSE; returns {"seconds_per_spp", "spp": rows}."""
    rate = seconds_per_spp(rows)
    for r in rows:
        names = r["seeds"][0]["regions"].keys()
        r["regions"] = {}
        for name in names:
            m = {k: median([s["regions"][name][k] for s in r["seeds"]]) for k in METRICS}
            for k in ("relmse", "relmse_trimmed"):
                m["efficiency" + k[6:]] = 1.0 / (m[k] * r["spp"] * rate) if m[k] > 0 and rate > 0 else None
            r["regions"][name] = m
    return {"seconds_per_spp": rate, "spp": rows}


def region_agreement(cycles_ref, envpis_ref, regions):
    """{region: agreement()} of the two converged references (how far apart the renderers' images are)."""
    return {name: agreement(cycles_ref, envpis_ref, mask) for name, mask in regions.items()}


def scene_table(scene, spps):
    """One scene-map: per renderer, the whole image's figures and efficiency relative to Cycles."""
    sl = "/".join(str(s) for s in spps)
    head = ["renderer", "relMSE %s spp" % sl, "relMSE w/o top 0.1%% %s" % sl, "median e %s" % sl, "ms/spp",
            "efficiency vs Cycles %s" % sl, "same, robust relMSE %s" % sl, "worst pixel e %d" % spps[-1],
            "pixels 10x off %d" % spps[-1]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    cyc = scene["renderers"].get(CYCLES)
    for key, r in scene["renderers"].items():
        rows = [at_spp(r, s)["regions"]["all"] for s in spps]
        crow = [at_spp(cyc, s)["regions"]["all"] if cyc else None for s in spps]
        eff = [fmt(ratio(m["efficiency"], c["efficiency"]) if c else None, ".2f") for m, c in zip(rows, crow)]
        effr = [fmt(ratio(m["efficiency_trimmed"], c["efficiency_trimmed"]) if c else None, ".2f")
                for m, c in zip(rows, crow)]
        lines.append("| %s | %s | %s | %s | %.2f | %s | %s | %s | %s |" % (
            "Cycles" if key == CYCLES else key.replace("envpis ", ""),
            " / ".join(fmt(x["relmse"]) for x in rows), " / ".join(fmt(x["relmse_trimmed"]) for x in rows),
            " / ".join(fmt(x["median"]) for x in rows), 1000 * r["seconds_per_spp"], " / ".join(eff),
            " / ".join(effr), fmt(rows[-1]["worst"]), fmt(rows[-1]["over_10x"], "g")))
    return "\n".join(lines) + "\n"


def object_table(scene, spp):
    """One scene-map at one spp: per object, relMSE (robust in brackets) of every renderer, efficiency
    of each envpis strategy relative to Cycles, how far apart the two references are, and (noise floor)
    how far apart two images of envpis at about the references' noise are."""
    keys = list(scene["renderers"])
    names = [n for n in at_spp(scene["renderers"][keys[0]], spp)["regions"] if n != "all"]
    head = ["object", "pixels"] + ["relMSE (robust) %s" % ("Cycles" if k == CYCLES else k.replace("envpis ", ""))
                                   for k in keys]
    head += ["eff. %s / Cycles" % k.replace("envpis ", "") for k in keys if k != CYCLES]
    head += ["references: mean rel. difference", "same renderer (noise floor)", "ratio of means C / E"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for name in names + ["all"]:
        row = {k: at_spp(scene["renderers"][k], spp)["regions"].get(name) for k in keys}
        c = row.get(CYCLES)
        ag = scene["agreement"].get(name, {})
        cells = [name, fmt(scene["pixels"].get(name), "d")]
        cells += ["%s (%s)" % (fmt(row[k]["relmse"]), fmt(row[k]["relmse_trimmed"])) if row[k] else "-" for k in keys]
        cells += [fmt(ratio(row[k]["efficiency"], c["efficiency"]) if row[k] and c else None, ".2f")
                  for k in keys if k != CYCLES]
        floor = scene.get("noise_floor", {}).get(name, {})
        cells += [fmt(ag.get("mean_relative_difference"), ".3f"), fmt(floor.get("mean_relative_difference"), ".3f"),
                  fmt(ag.get("ratio_of_means"), ".3f")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
