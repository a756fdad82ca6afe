# SPDX-License-Identifier: Apache-2.0
"""EnvironmentMap and ImportanceTable through the bindings: both layouts from arrays, a real map from
Blender's data, the equal-area mapping on arrays."""
import os

import numpy as np
import pytest

import envpis
from conftest import SUNSET, sky_pixels


def texel_centres_latlong(h, w):
    """World directions of lat-long texel centres under the Panorama orientation (u = 0.5 - phi/2pi)."""
    v, u = np.meshgrid((np.arange(h) + 0.5) / h, (np.arange(w) + 0.5) / w, indexing="ij")
    theta, phi = np.pi * v, 2 * np.pi * (0.5 - u)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)], -1).reshape(-1, 3)


def test_latlong_eval_reads_the_texels():
    px = sky_pixels(16, 32)
    env = envpis.EnvironmentMap.from_array(px, layout="latlong", filter="nearest")
    assert (env.width, env.height, env.layout, env.filter) == (32, 16, "latlong", "nearest")
    np.testing.assert_allclose(env.eval(texel_centres_latlong(16, 32)), px.reshape(-1, 3), rtol=1e-6)
    np.testing.assert_array_equal(env.to_array(), px)


def test_equal_area_eval_reads_the_texels():
    px = sky_pixels(24, 24).astype(np.float64)  # float64 is converted
    env = envpis.EnvironmentMap.from_array(px, filter="nearest")
    assert env.layout == "equal-area"
    k = (np.arange(24) + 0.5) / 24
    uv = np.stack(np.meshgrid(k, k), -1).reshape(-1, 2)
    np.testing.assert_allclose(env.eval(envpis.equal_area_square_to_sphere(uv)), px.reshape(-1, 3), rtol=1e-6)


def test_equal_area_round_trip():
    uv = np.random.default_rng(0).random((1000, 2))
    d = envpis.equal_area_square_to_sphere(uv)
    np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(envpis.equal_area_sphere_to_square(d), uv, atol=1e-5)
    assert envpis.equal_area_square_to_sphere([0.5, 0.5]).tolist() == [0, 0, 1]


def test_table_arrays(table):
    imp = table.importance()
    assert imp.shape == (table.fine_resolution,) * 2 and np.all(imp > 0)
    probs = table.cell_probabilities()
    assert probs.shape == (12, 12) and abs(probs.sum() - 1) < 1e-5
    assert table.integral > 0 and table.cell_resolution * 12 == table.fine_resolution


def test_map_texel_table():
    px = sky_pixels(16, 32)
    env = envpis.EnvironmentMap.from_array(px, layout="latlong")
    t = envpis.ImportanceTable(env, fine_texels="map", subdivision=2)
    assert t.fine_texels == "map" and t.fine_resolution == 0
    imp = t.importance()
    assert imp.shape == (16, 32) and np.all(imp > 0)
    d, p = t.sample(np.random.default_rng(2).random((500, 2)))
    np.testing.assert_allclose(t.pdf(d), p, rtol=1e-4)
    with pytest.raises(envpis.Error, match="fine texels"):
        envpis.ImportanceTable(env, fine_texels="latlong")


def test_scale_and_rotation():
    px = sky_pixels(16, 32)
    rot = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)  # 90 degrees about +Z
    env = envpis.EnvironmentMap.from_array(px, layout="latlong")
    turned = envpis.EnvironmentMap.from_array(px, layout="latlong", scale=2, rotation=rot)
    d = envpis.equal_area_square_to_sphere(np.random.default_rng(1).random((100, 2)))
    np.testing.assert_allclose(turned.eval(d @ rot.T), 2 * env.eval(d), rtol=1e-4, atol=1e-6)


@pytest.mark.skipif(not os.path.exists(SUNSET), reason=f"{SUNSET} not installed (Debian package blender-data)")
def test_blender_map():
    env = envpis.EnvironmentMap.load(SUNSET)
    assert env.layout == "latlong" and env.path == SUNSET and env.width == 2 * env.height
    table = envpis.ImportanceTable(env)
    sampler = envpis.ProductSampler(table)
    assert sampler.prepare([0, 0, 1], [0, 1, 1], [0.5, 0, 0.5, 0, 0.3, 0, 1])
    d, p = sampler.sample(np.random.default_rng(0).random((1000, 2)))
    assert np.all(p > 0)
    np.testing.assert_allclose(sampler.pdf(d), p, rtol=1e-5)
