# SPDX-License-Identifier: Apache-2.0
"""Bad input raises a Python exception (ValueError for shapes and dtypes, envpis.Error with the
library's message for what the library refuses); nothing crashes."""
import os

import numpy as np
import pytest

import envpis


def test_library_errors_are_runtime_errors():
    assert issubclass(envpis.Error, RuntimeError)


def test_missing_file(tmp_path):
    path = str(tmp_path / "no-such-map.exr")
    with pytest.raises(envpis.Error, match="no-such-map.exr"):
        envpis.EnvironmentMap.load(path)


def test_bad_map_arrays():
    for bad in (np.zeros((4, 8)), np.zeros((4, 8, 4)), np.zeros((0, 8, 3)), np.zeros((2, 4, 3), dtype=str),
                np.zeros((2, 4, 3), dtype=bool), "pixels", [[1, 2], [3]]):
        with pytest.raises(ValueError):
            envpis.EnvironmentMap.from_array(bad)


def test_bad_map_options():
    px = np.ones((8, 16, 3), np.float32)
    with pytest.raises(envpis.Error, match="square"):
        envpis.EnvironmentMap.from_array(px, layout="equal-area")
    with pytest.raises(envpis.Error):
        envpis.EnvironmentMap.from_array(px, layout="cube")
    with pytest.raises(envpis.Error):
        envpis.EnvironmentMap.from_array(px, scale=-1)
    with pytest.raises(ValueError):
        envpis.EnvironmentMap.from_array(px, rotation=np.eye(2))


def test_bad_table_options(latlong_map):
    for kwargs in ({"top_resolution": 0}, {"peak_ratio": 0.5}, {"floor": 2.0}):
        with pytest.raises(envpis.Error):
            envpis.ImportanceTable(latlong_map, **kwargs)
    options = envpis.ProductSamplerOptions()
    options.env_mix = 2
    table = envpis.ImportanceTable(latlong_map)
    with pytest.raises(envpis.Error, match="env_mix"):
        envpis.ProductSampler(table, options)
    with pytest.raises(envpis.Error, match="env_mix"):
        envpis.product_sample(table, [0, 0, 1], [0, 0, 1], [1, 0, 0, 0, 0, 0, 1], np.zeros((3, 2)), options=options)
    with pytest.raises(envpis.Error):
        envpis.ProxyOptions().transform = "sideways"
    with pytest.raises(envpis.Error, match="reflection lobe"):
        envpis.ProxyOptions().reflection_lobe = "half"


def test_bad_shapes_and_dtypes(table):
    n = np.tile([0, 0, 1.0], (4, 1))
    p = np.tile([1, 0, 0, 0, 0, 0, 1.0], (4, 1))
    u = np.full((4, 2), 0.5)
    bad_calls = [
        lambda: envpis.product_sample(table, n, n, p, u[:, :1]),            # u N x 1
        lambda: envpis.product_sample(table, n[:3], n, p, u),               # 3 normals for 4 points
        lambda: envpis.product_sample(table, n, n, p[:, :6], u),            # 6-float proxies
        lambda: envpis.product_sample(table, n, n, p, u.astype(str)),       # strings
        lambda: envpis.product_sample(table, n, n, p, u.astype(complex)),   # complex
        lambda: envpis.product_sample(table, n, n, p, u, threads=-1),
        lambda: envpis.product_sample(table, n, n, np.zeros(4, dtype=[("diffuse", "f4")]), u),  # missing fields
        lambda: envpis.product_sample(table, n, n, [envpis.BsdfProxy(), 3], u),
        lambda: envpis.product_pdf(table, n, n, p, u),                      # dirs N x 2
        lambda: envpis.product_pdf(table, n, n, p, None),
        lambda: table.sample(np.zeros((4, 3))),
        lambda: table.pdf(np.zeros((2, 2, 3))),
        lambda: envpis.equal_area_square_to_sphere(np.zeros(3)),
        lambda: envpis.equal_area_sphere_to_square([["x", "y", "z"]]),
        lambda: envpis.ProductSampler(table).prepare([0, 1], [0, 0, 1], envpis.BsdfProxy()),
        lambda: envpis.ProductSampler(table).prepare([0, 0, 1], [0, 0, 1], np.zeros((2, 7))),
        lambda: envpis.BsdfProxy.from_array([1, 2, 3]),
    ]
    for i, call in enumerate(bad_calls):
        with pytest.raises(ValueError):
            call()
            pytest.fail(f"bad call {i} did not raise")


def test_empty_arrays(table):
    d, p = envpis.product_sample(table, np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 7)), np.zeros((0, 2)))
    assert d.shape == (0, 3) and p.shape == (0,)
    assert envpis.product_pdf(table, [0, 0, 1], [0, 0, 1], envpis.BsdfProxy(), np.zeros((0, 3))).shape == (0,)
    d, p = table.sample(np.zeros((0, 2)))
    assert d.shape == (0, 3) and p.shape == (0,)
    assert envpis.equal_area_square_to_sphere(np.zeros((0, 2))).shape == (0, 3)


def test_nan_and_degenerate_input_follows_the_library_policy(table):
    """Zero or NaN normals and wo, NaN u: no sample (pdf 0, the library's "ignore it"); u outside
    [0, 1) is clamped; a NaN proxy falls back to the environment."""
    s = envpis.ProductSampler(table)
    assert not s.prepare([np.nan, 0, 1], [0, 0, 1], envpis.BsdfProxy())
    d, p = s.sample([0.5, 0.5])
    assert p == 0 and s.pdf([0, 0, 1]) == 0
    n = np.array([[0, 0, 1], [np.nan] * 3, [0, 0, 0], [0, 0, 1], [0, 0, 1]], np.float32)
    proxies = np.tile([1, 0, 1, 0, 0.2, 0, 1.5], (5, 1)).astype(np.float32)
    proxies[3] = np.nan
    u = np.array([[0.5, 0.5], [0.5, 0.5], [0.5, 0.5], [0.2, 0.7], [-1.0, 2.0]], np.float32)
    d, p = envpis.product_sample(table, n, [0, 0.5, 1], proxies, u)
    assert list(p[1:3]) == [0, 0]
    assert np.all(np.isfinite(d)) and np.all(np.isfinite(p)) and p[3] > 0 and p[4] > 0
    _, p = envpis.product_sample(table, [0, 0, 1], [0, 0, 1], proxies[0], [[np.nan, 0.5], [0.5, np.nan]])
    assert list(p) == [0, 0]
    assert np.all(table.pdf([[np.nan, 0, 0], [0, 0, 0]]) == 0)
    env = envpis.EnvironmentMap.from_array(np.full((8, 16, 3), np.nan, np.float32))
    assert env.is_black
    black = envpis.ImportanceTable(env)
    assert black.empty
    d, p = envpis.product_sample(black, [0, 0, 1], [0, 0, 1], envpis.BsdfProxy(), np.full((2, 2), 0.5))
    assert np.all(p == 0)


def test_not_a_file(tmp_path):
    with pytest.raises(envpis.Error):
        envpis.EnvironmentMap.load(str(tmp_path))
    junk = tmp_path / "junk.exr"
    junk.write_bytes(os.urandom(64))
    with pytest.raises(envpis.Error, match="junk.exr"):
        envpis.EnvironmentMap.load(str(junk))
