# SPDX-License-Identifier: Apache-2.0
"""The batched calls return exactly what the per-point API returns for each shading point, whatever
the thread count and however the inputs are given."""
import numpy as np
import pytest

import envpis
from conftest import random_points

N = 3000


def per_point(table, normals, wo, proxies, u, dirs):
    """The reference: one ProductSampler, prepare + sample + pdf per point, from Python."""
    s = envpis.ProductSampler(table)
    out_dirs, out_pdf, out_pdf_at = np.zeros((len(u), 3), np.float32), np.zeros(len(u), np.float32), np.zeros(len(u), np.float32)
    for i in range(len(u)):
        s.prepare(normals[i], wo[i], proxies[i])
        out_dirs[i], out_pdf[i] = s.sample(u[i])
        out_pdf_at[i] = s.pdf(dirs[i])
    return out_dirs, out_pdf, out_pdf_at


def inputs(seed):
    normals, wo, proxies = random_points(N, seed)
    normals[::97] = np.nan  # invalid points: no sample, pdf 0
    wo[5::101] = 0
    rng = np.random.default_rng(seed + 1)
    return normals, wo, proxies, rng.random((N, 2)).astype(np.float32), rng.normal(size=(N, 3)).astype(np.float32)


def test_batch_equals_per_point(table):
    normals, wo, proxies, u, dirs = inputs(1)
    ref_dirs, ref_pdf, ref_pdf_at = per_point(table, normals, wo, proxies, u, dirs)
    got_dirs, got_pdf = envpis.product_sample(table, normals, wo, proxies, u)
    np.testing.assert_array_equal(got_dirs, ref_dirs)
    np.testing.assert_array_equal(got_pdf, ref_pdf)
    np.testing.assert_array_equal(envpis.product_pdf(table, normals, wo, proxies, dirs), ref_pdf_at)
    invalid = np.isnan(normals[:, 0]) | ~np.any(wo != 0, axis=1)
    assert np.all(got_pdf[invalid] == 0) and np.all(got_dirs[invalid] == 0)
    assert np.all(got_pdf[~invalid] > 0)


def test_batch_is_independent_of_threads(table):
    normals, wo, proxies, u, _ = inputs(2)
    one = envpis.product_sample(table, normals, wo, proxies, u, threads=1)
    two = envpis.ProductSampler.sample_batch(table, normals, wo, proxies, u, threads=2)
    default = envpis.product_sample(table, normals, wo, proxies, u)
    for got in (two, default):
        np.testing.assert_array_equal(got[0], one[0])
        np.testing.assert_array_equal(got[1], one[1])


def test_proxy_forms_agree(table):
    """N x 7 float32, float64, a structured array, a list of BsdfProxy and one shared row."""
    normals, wo, proxies, u, _ = inputs(3)
    proxies = proxies[:200]
    normals, wo, u = normals[:200], wo[:200], u[:200]
    ref = envpis.product_sample(table, normals, wo, proxies, u)
    structured = np.zeros(len(proxies), dtype=[(f, np.float64) for f in reversed(envpis.PROXY_FIELDS)] + [("extra", np.int32)])
    for k, f in enumerate(envpis.PROXY_FIELDS):
        structured[f] = proxies[:, k]
    as_list = [envpis.BsdfProxy.from_array(p) for p in proxies]
    for form in (proxies.astype(np.float64), structured, as_list):
        got = envpis.product_sample(table, normals, wo, form, u)
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[1], ref[1])
    shared = envpis.product_sample(table, normals, wo, as_list[0], u)
    tiled = envpis.product_sample(table, normals, wo, np.tile(proxies[0], (len(u), 1)), u)
    np.testing.assert_array_equal(shared[0], tiled[0])


def test_options_reach_the_batch(table):
    normals, wo, proxies, u, _ = inputs(4)
    options = envpis.ProductSamplerOptions()
    options.env_mix = 0.5
    options.proxy.transform = "slides"
    options.proxy.reflection_lobe = "half-vector"
    assert options.proxy.reflection_lobe == "half-vector"
    s = envpis.ProductSampler(table, options)
    got = envpis.product_sample(table, normals[:50], wo[:50], proxies[:50], u[:50], options=options)
    for i in range(50):
        s.prepare(normals[i], wo[i], proxies[i])
        d, p = s.sample(u[i])
        np.testing.assert_array_equal(got[0][i], d)
        assert got[1][i] == p
    default = envpis.product_sample(table, normals[:50], wo[:50], proxies[:50], u[:50])
    assert not np.array_equal(default[1], got[1])


def test_cell_probabilities(table):
    s = envpis.ProductSampler(table)
    assert s.prepare([0, 0, 1], [0, 0, 1], [1, 0, 0, 0, 0, 0, 1])
    probs = s.cell_probabilities()
    assert probs.shape == (12, 12)
    assert abs(probs.sum() - 1) < 1e-5


def test_concurrent_calls_from_python_threads(table):
    """The batch releases the GIL and shares the table read-only: calls from several Python threads
    at once give the serial results."""
    import threading

    normals, wo, proxies, u, _ = inputs(5)
    ref = envpis.product_sample(table, normals, wo, proxies, u, threads=1)
    results = [None] * 4

    def work(k):
        results[k] = envpis.product_sample(table, normals, wo, proxies, u, threads=1)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got in results:
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[1], ref[1])


def test_simd_option_picks_the_kernels(table):
    """The scalar reference and the default kernels give the same distribution within the SIMD
    estimates' error; an unknown instruction set is an envpis.Error."""
    options = envpis.ProductSamplerOptions()
    assert options.simd == "best"
    options.simd = "scalar"
    scalar = envpis.ProductSampler(table, options)
    best = envpis.ProductSampler(table)
    for s in (scalar, best):
        assert s.prepare([0, 0, 1], [1, 0, 1], [0, 0, 1, 0, 0.2, 0, 1.5])
    np.testing.assert_allclose(scalar.cell_probabilities(), best.cell_probabilities(), rtol=2e-3, atol=1e-7)
    with pytest.raises(envpis.Error, match="unknown SIMD"):
        options.simd = "mmx"
