# SPDX-License-Identifier: Apache-2.0
"""Chi-square tests of the samplers through the bindings: samples binned on the equal-area square
against the bins' integrated pdf (envpis_chi2). Fixed seeds; a correct sampler fails one of these
with probability 1e-3 each."""
import numpy as np
import pytest

import envpis
from envpis_chi2 import chi2_test, expected_counts, observed_counts

COUNT = 200_000
RES = 24  # bins per side: the synthetic tables have N = 96 fine texels, so each bin is 4x4 texels


def check(sample, pdf, seed):
    u = np.random.default_rng(seed).random((COUNT, 2))
    dirs, pdfs = sample(u)
    assert np.all(pdfs > 0), "a valid sampler must always return a sample"
    assert np.all(np.isfinite(dirs))
    np.testing.assert_allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-5)
    np.testing.assert_allclose(pdfs, pdf(dirs), rtol=1e-5)  # sample's pdf is pdf() of its direction
    expected = expected_counts(pdf, COUNT, resolution=RES, sub=4)
    assert expected.sum() == pytest.approx(COUNT, rel=1e-3), "pdf must integrate to 1"
    p, stat, dof = chi2_test(observed_counts(dirs, resolution=RES), expected)
    assert p > 1e-3, f"chi-square {stat:.1f} with {dof} dof: p = {p:.2e}"


def proxy(diffuse=0.0, translucent=0.0, reflection=0.0, alpha_r=0.0, refraction=0.0, alpha_t=0.0, ior=1.5):
    b = envpis.BsdfProxy()
    b.add_diffuse(diffuse)
    b.add_translucent(translucent)
    b.add_reflection(reflection, alpha_r)
    b.add_refraction(refraction, alpha_t, ior)
    return b


SHADING_POINTS = {
    "diffuse": ([0, 0, 1], [0.3, 0.1, 1], proxy(diffuse=1)),
    "glossy": ([0.2, -0.5, 0.8], [0.7, 0.2, 0.3], proxy(diffuse=0.2, reflection=0.8, alpha_r=0.1)),
    "glass": ([-0.3, 0.6, 0.7], [0.1, 0.3, 1], proxy(reflection=0.1, alpha_r=0.05, refraction=0.9, alpha_t=0.2)),
    "translucent": ([0.5, 0.5, -0.6], [0.1, 0.2, -1], proxy(diffuse=0.5, translucent=0.5)),
    "zero proxy (environment fallback)": ([0, 0, 1], [0, 0, 1], envpis.BsdfProxy()),
}


@pytest.mark.parametrize("name", list(SHADING_POINTS))
@pytest.mark.parametrize("layout", ["latlong", "equal-area"])
def test_product_sampler_chi2(name, layout, latlong_map, equal_area_map):
    env = latlong_map if layout == "latlong" else equal_area_map
    table = envpis.ImportanceTable(env)
    assert table.fine_resolution % RES == 0  # bins are whole table texels
    sampler = envpis.ProductSampler(table)
    n, wo, b = SHADING_POINTS[name]
    assert sampler.prepare(n, wo, b)
    check(sampler.sample, sampler.pdf, seed=list(SHADING_POINTS).index(name) * 2 + (layout == "latlong"))


def test_batched_product_sample_chi2(table):
    """The batched call with one shared shading point follows the same distribution."""
    n, wo, b = SHADING_POINTS["glossy"]
    check(lambda u: envpis.product_sample(table, n, wo, b, u),
          lambda d: envpis.product_pdf(table, n, wo, b, d), seed=11)


def test_environment_only_chi2(table):
    check(table.sample, table.pdf, seed=5)


def test_chi2_detects_a_wrong_pdf(table):
    """The harness has teeth: a pdf that ignores the proxy fails against product samples."""
    sampler = envpis.ProductSampler(table)
    n, wo, b = SHADING_POINTS["glossy"]
    sampler.prepare(n, wo, b)
    u = np.random.default_rng(3).random((COUNT, 2))
    dirs, _ = sampler.sample(u)
    p, _, _ = chi2_test(observed_counts(dirs, RES), expected_counts(table.pdf, COUNT, RES, 4))
    assert p < 1e-6


@pytest.mark.parametrize("name,estimate", [("glossy", "cone"), ("glass", "cone"), ("glossy", "moments"),
                                           ("glass", "moments")])
def test_refined_product_sampler_chi2(name, estimate, latlong_map):
    """The refined sampler (sub-cells chosen by the product too) through the bindings, with either
    cell estimate."""
    table = envpis.ImportanceTable(latlong_map, subdivision=4)
    assert table.subdivision == 4 and table.fine_resolution % RES == 0
    options = envpis.ProductSamplerOptions()
    options.refine = True
    options.cell_estimate = estimate
    assert options.cell_estimate == estimate
    sampler = envpis.ProductSampler(table, options)
    assert sampler.refines
    n, wo, b = SHADING_POINTS[name]
    assert sampler.prepare(n, wo, b)
    check(sampler.sample, sampler.pdf, seed=20 + len(name) + len(estimate))


def test_cell_estimate_rejects_unknown_names():
    options = envpis.ProductSamplerOptions()
    with pytest.raises(RuntimeError, match="cone"):
        options.cell_estimate = "nearest"


def test_refined_product_sampler_needs_subcells(table):
    options = envpis.ProductSamplerOptions()
    options.refine = True
    with pytest.raises(RuntimeError, match="sub-cells"):
        envpis.ProductSampler(table, options)
