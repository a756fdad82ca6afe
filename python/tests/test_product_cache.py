# SPDX-License-Identifier: Apache-2.0
"""ProductCache from Python: the sampler it hands out at a point is bitwise the sampler prepared afresh
at the rounded point, whatever the cache's size, and it counts its reuse."""
import numpy as np
import pytest

import envpis
from conftest import random_points


def fresh(table, n, wo, proxy):
    s = envpis.ProductSampler(table)
    s.prepare(n, wo, proxy)
    return s


@pytest.mark.parametrize("entries", [1, 16])
def test_cached_sampler_is_the_sampler_of_the_rounded_point(table, entries):
    normals, wo, proxies = random_points(200, 3)
    # Neighbours: every point twice more, nudged by far less than the rounding step.
    rng = np.random.default_rng(4)
    idx = np.repeat(np.arange(200), 3)
    n = normals[idx] + 1e-4 * rng.normal(size=(600, 3))
    w = wo[idx] + 1e-4 * rng.normal(size=(600, 3))
    options = envpis.ProductCacheOptions()
    options.entries = entries
    cache = envpis.ProductCache(table, envpis.ProductSamplerOptions(), options)
    u = rng.random((8, 2)).astype(np.float32)
    for i in range(600):
        got = cache.prepare(n[i], w[i], proxies[idx[i]])
        rn, rw, rp = cache.round(n[i], w[i], proxies[idx[i]])
        want = fresh(table, rn, rw, rp)
        assert got.valid == want.valid
        gd, gp = got.sample(u)
        wd, wp = want.sample(u)
        np.testing.assert_array_equal(gd, wd)
        np.testing.assert_array_equal(gp, wp)
        np.testing.assert_array_equal(got.pdf(gd), want.pdf(gd))
    assert cache.hits + cache.misses == 600
    assert cache.hits >= 300  # the neighbours round to their point's key (most of them)


def test_round_moves_little(table):
    normals, wo, proxies = random_points(100, 5)
    cache = envpis.ProductCache(table)
    k = cache.options.resolution
    for i in range(100):  # the documented bound: a direction moves by at most 0.87 / K radians
        for before, after in zip((normals[i], wo[i]), cache.round(normals[i], wo[i], proxies[i])[:2]):
            assert abs(np.linalg.norm(after) - 1) < 1e-5
            assert np.arccos(min(1.0, float(np.dot(before, after)))) <= 0.87 / k + 1e-4


def test_invalid_points_and_options(table):
    cache = envpis.ProductCache(table)
    s = cache.prepare([np.nan, 0, 1], [0, 0, 1], envpis.BsdfProxy())
    assert not s.valid
    _, pdf = s.sample([0.5, 0.5])
    assert pdf == 0
    with pytest.raises(ValueError):
        cache.prepare([0, 0], [0, 0, 1], envpis.BsdfProxy())
    bad = envpis.ProductCacheOptions()
    bad.entries = 0
    with pytest.raises(envpis.Error, match="entries"):
        envpis.ProductCache(table, envpis.ProductSamplerOptions(), bad)
    bad = envpis.ProductCacheOptions()
    bad.resolution = 5000
    with pytest.raises(envpis.Error, match="resolution"):
        envpis.ProductCache(table, envpis.ProductSamplerOptions(), bad)
