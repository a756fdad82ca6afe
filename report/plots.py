#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Plots of an `envpis compare` run, for its report (index.html).

    python3 report/plots.py DIR/metrics.json

Writes SVG files to DIR/plots/ and DIR/plots/manifest.json (the list of figures with their titles and
captions, which `envpis compare` embeds in the report). Uses matplotlib (Debian: python3-matplotlib).
Exit status 3 when matplotlib is missing (the compare command then tries another interpreter or writes
the report without plots), 2 for a bad metrics.json.
"""
import json
import math
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import LogLocator, NullFormatter
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"plots.py: matplotlib is not available ({e})", file=sys.stderr)
    sys.exit(3)

COLORS = {
    "mis": "#1f77b4",
    "mis-comp": "#ff7f0e",
    "product": "#2ca02c",
    "oracle": "#9467bd",
    "bsdf": "#7f7f7f",
    "env": "#8c564b",
}
MARKERS = {"mis": "o", "mis-comp": "s", "product": "D", "oracle": "^", "bsdf": "v", "env": "x"}


def color(s):
    return COLORS.get(s, "#333333")


def region_label(name):
    """fig1's spheres are named conductor-<alpha>, diffuse, glass: label them by roughness."""
    if name.startswith("conductor-"):
        return "GGX " + name[len("conductor-"):]
    return name


def finite(x):
    return x is not None and isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def style_log_axis(ax, which="y"):
    axis = ax.yaxis if which == "y" else ax.xaxis
    axis.set_major_locator(LogLocator(base=10))
    axis.set_minor_locator(LogLocator(base=10, subs=range(2, 10)))
    axis.set_minor_formatter(NullFormatter())


def convergence_overall(m, out):
    conv = m.get("convergence") or {}
    if not conv:
        return None
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    lo, hi = math.inf, 0
    for s, series in conv.items():
        pts = [(p["spp"], p["relmse"]) for p in series if finite(p.get("relmse"))]
        if not pts:
            continue
        x, y = zip(*pts)
        ax.plot(x, y, marker=MARKERS.get(s, "o"), color=color(s), label=s, lw=1.8, ms=5)
        lo, hi = min(lo, min(x)), max(hi, max(x))
    if hi == 0:
        plt.close(fig)
        return None
    # 1/spp slope through the first point of the first series, for reading the rate
    first = next(iter(conv.values()))
    if first and finite(first[0].get("relmse")):
        x0, y0 = first[0]["spp"], first[0]["relmse"]
        ax.plot([lo, hi], [y0 * x0 / lo, y0 * x0 / hi], ls=":", color="#999", lw=1, label="1/spp")
    floor = (m.get("reference") or {}).get("relmse_floor")
    if finite(floor):
        ax.axhline(floor, color="#bbb", lw=1, ls="--", label="reference noise")
    ax.set_xscale("log", base=2)
    ax.set_yscale("log")
    style_log_axis(ax)
    ax.set_xlabel("samples per pixel")
    ax.set_ylabel("relMSE (whole image)")
    ax.set_title("Convergence")
    ax.grid(True, which="major", alpha=0.3)
    ax.legend(frameon=False, fontsize=9)
    fig.tight_layout()
    path = os.path.join(out, "convergence.svg")
    fig.savefig(path)
    plt.close(fig)
    return {
        "file": "plots/convergence.svg",
        "title": "Convergence: relMSE against spp (log-log)",
        "caption": "Each strategy rendered at 1, 2, 4, ... spp with the same seed (prefixes of the equal-spp "
        "render). The dotted line has slope -1 (an unbiased estimator's rate); the dashed one is the "
        "reference's own noise.",
    }


def convergence_regions(m, out):
    conv = m.get("convergence") or {}
    regions = m.get("regions") or []
    if not conv or not regions:
        return None
    n = len(regions)
    cols = min(4, n)
    rows = (n + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(2.5 * cols, 2.2 * rows), squeeze=False, sharex=True)
    for i, reg in enumerate(regions):
        ax = axes[i // cols][i % cols]
        for s, series in conv.items():
            pts = []
            for p in series:
                for r in p.get("regions", []):
                    if r["id"] == reg["id"] and finite(r.get("relmse")):
                        pts.append((p["spp"], r["relmse"]))
            if pts:
                x, y = zip(*pts)
                ax.plot(x, y, marker=MARKERS.get(s, "o"), color=color(s), label=s, lw=1.4, ms=3.5)
        ax.set_xscale("log", base=2)
        ax.set_yscale("log")
        ax.set_title(region_label(reg["name"]), fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
        ax.tick_params(labelsize=8)
    for j in range(n, rows * cols):
        axes[j // cols][j % cols].axis("off")
    handles, labels = axes[0][0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", ncol=len(labels), frameon=False, fontsize=9)
    fig.supxlabel("samples per pixel", fontsize=10)
    fig.supylabel("relMSE", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.93))
    fig.savefig(os.path.join(out, "convergence-regions.svg"))
    plt.close(fig)
    return {
        "file": "plots/convergence-regions.svg",
        "title": "Convergence per object",
        "caption": "relMSE over each object's pixels (by the object-id AOV) against spp.",
    }


def region_bars(m, out, key, title):
    block = m.get(key)
    regions = m.get("regions") or []
    if not block or not regions:
        return None
    strategies = block["strategies"]
    k = len(strategies)
    width = 0.8 / max(k, 1)
    fig, ax = plt.subplots(figsize=(max(6.4, 0.8 * len(regions) + 1.2), 4.2))
    xs = range(len(regions))
    seeds = len(m.get("seeds") or [0])
    for i, st in enumerate(strategies):
        vals, lo, hi = [], [], []
        for reg in regions:
            r = next((r for r in st["regions"] if r["id"] == reg["id"]), {})
            v = r.get("relmse")
            vals.append(v if finite(v) else float("nan"))
            # with --seeds K > 1: the bar is the median over the seeds, the error bar their [min, max]
            lo.append(v - r["relmse_min"] if finite(v) and finite(r.get("relmse_min")) else 0)
            hi.append(r["relmse_max"] - v if finite(v) and finite(r.get("relmse_max")) else 0)
        pos = [x - 0.4 + width * (i + 0.5) for x in xs]
        ax.bar(pos, vals, width=width * 0.95, color=color(st["strategy"]),
               label=f'{st["strategy"]} ({st["spp"]} spp)', yerr=[lo, hi] if seeds > 1 else None,
               error_kw={"elinewidth": 0.8, "capsize": 1.5, "ecolor": "#333"})
    ax.set_yscale("log")
    style_log_axis(ax)
    ax.set_xticks(list(xs))
    ax.set_xticklabels([region_label(r["name"]) for r in regions], rotation=0, fontsize=9)
    ax.set_ylabel("relMSE")
    ax.set_title(title)
    ax.grid(True, axis="y", which="major", alpha=0.3)
    ax.legend(frameon=False, fontsize=9, ncol=min(k, 4))
    fig.tight_layout()
    name = f"regions-{key.replace('_', '-')}.svg"
    fig.savefig(os.path.join(out, name))
    plt.close(fig)
    return {
        "file": "plots/" + name,
        "title": title,
        "caption": "relMSE over each object's pixels, lower is better (log scale)."
        + (f" Bars: the median over {seeds} seeds; error bars: their minimum and maximum." if seeds > 1 else ""),
    }


def ratio_bars(m, out, key, title):
    """relMSE(strategy) / relMSE(product) per object: above 1, product wins."""
    block = m.get(key)
    regions = m.get("regions") or []
    if not block or not regions:
        return None
    strategies = block["strategies"]
    prod = next((s for s in strategies if s["strategy"] == "product"), None)
    others = [s for s in strategies if s["strategy"] != "product"]
    if key == "equal_time":  # the oracle is the limit, not a competitor at equal time (it gets ~1 spp)
        others = [s for s in others if s["strategy"] != "oracle"]
    if prod is None or not others:
        return None

    def rel(st, rid):
        return next((r.get("relmse") for r in st["regions"] if r["id"] == rid), None)

    k = len(others)
    width = 0.8 / k
    fig, ax = plt.subplots(figsize=(max(6.4, 0.8 * len(regions) + 1.2), 4.2))
    xs = range(len(regions))
    for i, st in enumerate(others):
        vals = []
        for reg in regions:
            a, b = rel(st, reg["id"]), rel(prod, reg["id"])
            vals.append(a / b if finite(a) and finite(b) else float("nan"))
        pos = [x - 0.4 + width * (i + 0.5) for x in xs]
        ax.bar(pos, vals, width=width * 0.95, color=color(st["strategy"]), label=f'{st["strategy"]} / product')
        for p, v in zip(pos, vals):
            if math.isfinite(v):
                ax.annotate(f"{v:.2g}", (p, v), ha="center", va="bottom" if v >= 1 else "top", fontsize=7,
                            xytext=(0, 2 if v >= 1 else -2), textcoords="offset points")
    ax.axhline(1.0, color="#333", lw=1)
    ax.set_yscale("log")
    style_log_axis(ax)
    ax.set_xticks(list(xs))
    ax.set_xticklabels([region_label(r["name"]) for r in regions], fontsize=9)
    ax.set_ylabel("relMSE ratio (> 1: product is better)")
    ax.set_title(title)
    ax.grid(True, axis="y", which="major", alpha=0.3)
    ax.legend(frameon=False, fontsize=9, ncol=min(k, 3))
    fig.tight_layout()
    name = f"ratios-{key.replace('_', '-')}.svg"
    fig.savefig(os.path.join(out, name))
    plt.close(fig)
    return {
        "file": "plots/" + name,
        "title": title,
        "caption": "relMSE of each strategy divided by product's, per object. Above 1 product has less error; "
        "oracle below 1 shows the room left for improvement.",
    }


def main(argv):
    if len(argv) != 2:
        print("usage: plots.py DIR/metrics.json", file=sys.stderr)
        return 2
    try:
        with open(argv[1], encoding="utf-8") as f:
            m = json.load(f)
    except (OSError, ValueError) as e:
        print(f"plots.py: cannot read {argv[1]}: {e}", file=sys.stderr)
        return 2
    out = os.path.join(os.path.dirname(os.path.abspath(argv[1])), "plots")
    os.makedirs(out, exist_ok=True)
    plt.rcParams.update({"svg.fonttype": "none", "font.size": 10, "axes.spines.top": False,
                         "axes.spines.right": False})
    figures = []
    for fig in (
        convergence_overall(m, out),
        convergence_regions(m, out),
        region_bars(m, out, "equal_spp", "relMSE per object at equal spp"),
        ratio_bars(m, out, "equal_spp", "relMSE relative to product at equal spp"),
        region_bars(m, out, "equal_time", "relMSE per object at equal time"),
        ratio_bars(m, out, "equal_time", "relMSE relative to product at equal time"),
    ):
        if fig:
            figures.append(fig)
    with open(os.path.join(out, "manifest.json"), "w", encoding="utf-8") as f:
        json.dump({"figures": figures}, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
