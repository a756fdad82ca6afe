#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""envpis from Python: load a Blender environment map, plot its importance table and one shading
point's product distribution, draw a million product samples and check them against pdf() with a
chi-square test.

    PYTHONPATH=build/python python3 examples/python/product_distribution.py [--out DIR] [--samples N]

Writes importance.png (the table's fine importance and top-cell probabilities), product.png (the
product's cell probabilities, its density and the samples' histogram on the equal-area square) and
prints the chi-square p-value; exits 1 if it is below 1e-3.
"""
import argparse
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import envpis  # noqa: E402
from envpis_chi2 import chi2_test, expected_counts, observed_counts  # noqa: E402

BLENDER_WORLDS = "/usr/share/blender/datafiles/studiolights/world"


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--map", default=os.path.join(BLENDER_WORLDS, "sunset.exr"), help="environment map (EXR/HDR)")
    p.add_argument("--out", default="out/python-example", help="directory for the PNGs")
    p.add_argument("--samples", type=int, default=1_000_000, help="product samples for the chi-square test")
    p.add_argument("--seed", type=int, default=1)
    return p.parse_args()


def shading_point():
    """A glossy plastic facing the sunset's horizon: the normal tilted off +Z, seen at 60 degrees."""
    normal = np.array([0.6, 0.0, 0.8])
    wo = np.array([0.0, 0.87, 0.5])
    proxy = envpis.BsdfProxy()
    proxy.add_diffuse(0.3)
    proxy.add_reflection(0.7, 0.15)
    return normal, wo, proxy


def plot_table(table, path):
    fig, ax = plt.subplots(1, 2, figsize=(10, 4.6))
    im = ax[0].imshow(np.log10(table.importance()), cmap="magma")
    ax[0].set_title(f"log10 importance, {table.fine_resolution}$^2$ texels")
    fig.colorbar(im, ax=ax[0], shrink=0.8)
    im = ax[1].imshow(table.cell_probabilities(), cmap="viridis")
    ax[1].set_title(f"top cells E[c], {table.top_resolution}$^2$")
    fig.colorbar(im, ax=ax[1], shrink=0.8)
    for a in ax:
        a.set_xlabel("equal-area x")
        a.set_ylabel("equal-area y")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_product(sampler, dirs, path, res=256):
    k = (np.arange(res) + 0.5) / res
    grid = np.stack(np.meshgrid(k, k), -1).reshape(-1, 2)
    density = sampler.pdf(envpis.equal_area_square_to_sphere(grid)).reshape(res, res)
    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    im = ax[0].imshow(sampler.cell_probabilities(), cmap="viridis")
    ax[0].set_title("product cell probabilities P[c]")
    fig.colorbar(im, ax=ax[0], shrink=0.8)
    im = ax[1].imshow(np.log10(np.maximum(density, 1e-6)), cmap="magma")
    ax[1].set_title("log10 product pdf (solid angle)")
    fig.colorbar(im, ax=ax[1], shrink=0.8)
    hist = observed_counts(dirs, resolution=128)
    im = ax[2].imshow(np.log10(np.maximum(hist, 0.5)), cmap="magma")
    ax[2].set_title(f"log10 samples per bin ({len(dirs):,} samples)")
    fig.colorbar(im, ax=ax[2], shrink=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    args = parse_args()
    os.makedirs(args.out, exist_ok=True)
    env = envpis.EnvironmentMap.load(args.map)
    table = envpis.ImportanceTable(env)
    print(f"{env}: table T={table.top_resolution} N={table.fine_resolution}, integral {table.integral:.4g}")
    plot_table(table, os.path.join(args.out, "importance.png"))

    sampler = envpis.ProductSampler(table)
    normal, wo, proxy = shading_point()
    if not sampler.prepare(normal, wo, proxy):
        sys.exit("example: the shading point is invalid")
    u = np.random.default_rng(args.seed).random((args.samples, 2), dtype=np.float32)
    start = time.perf_counter()
    dirs, pdfs = sampler.sample(u)
    elapsed = time.perf_counter() - start
    print(f"{args.samples:,} samples in {elapsed * 1e3:.1f} ms ({elapsed / args.samples * 1e9:.0f} ns each)")
    plot_product(sampler, dirs, os.path.join(args.out, "product.png"))

    # The pdf is constant over each of the table's N x N fine texels: bins of whole texels with one
    # sub-sample per texel integrate it exactly (resolution * sub = N): the finest such bins up to
    # 128 per side (122 for the sunset's N = 732).
    res = max(r for r in range(1, 129) if table.fine_resolution % r == 0)
    expected = expected_counts(sampler.pdf, args.samples, resolution=res, sub=table.fine_resolution // res)
    p, stat, dof = chi2_test(observed_counts(dirs, resolution=res), expected)
    print(f"chi-square {stat:.1f} with {dof} degrees of freedom: p = {p:.3g}")
    print(f"wrote {args.out}/importance.png and {args.out}/product.png")
    if p < 1e-3:
        sys.exit("example: the samples do not follow pdf() (p < 1e-3)")


if __name__ == "__main__":
    main()
