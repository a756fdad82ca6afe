# SPDX-License-Identifier: Apache-2.0
"""Portals from Python (envpis/portals.h): both samplers through a window are chi-square tested from
points inside a room, their density is 0 only where no direction can leave through a portal, the
product without a view is the product of before, and bad input raises ValueError (shapes) or
envpis.Error (the library's checks)."""
import numpy as np
import pytest

import envpis
from test_chi2 import check, proxy

# An east window (x = 2) and a skylight (z = 3) of a room [-2, 2]^2 x [0, 3], counter-clockwise seen
# from outside, so that the normals point out.
EAST = [[2, -1, 0.8], [2, 1, 0.8], [2, 1, 2.2], [2, -1, 2.2]]
SKYLIGHT = [[-0.5, -0.5, 3], [0.5, -0.5, 3], [0.5, 0.5, 3], [-0.5, 0.5, 3]]
POINTS = {"centre": [0, 0, 1], "near the window": [1.5, 0.3, 1.2], "corner": [-1.8, 1.8, 0.1]}


@pytest.fixture(scope="module")
def portals():
    return envpis.Portals(np.array([EAST, SKYLIGHT], dtype=np.float32))


def test_portals_hold_valid_quads_with_outward_normals(portals):
    assert len(portals) == 2
    np.testing.assert_allclose(portals.normal(0), [1, 0, 0], atol=1e-6)
    np.testing.assert_allclose(portals.normal(1), [0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(portals.quad(0), EAST)
    hit = portals.passes([0, 0, 1], np.array([[1, 0, 0.2], [-1, 0, 0], [0, 0, 1]], dtype=np.float32))
    np.testing.assert_array_equal(hit, [1, 0, 1])


@pytest.mark.parametrize("where", sorted(POINTS))
def test_environment_sampler_through_portals_chi_square(table, portals, where):
    view = envpis.PortalView(table, portals)
    assert view.prepare(POINTS[where])
    s = envpis.PortalEnvironmentSampler(table)
    assert s.prepare(view)
    check(s.sample, s.pdf, seed=11)


@pytest.mark.parametrize("where", sorted(POINTS))
def test_product_through_portals_chi_square(table, portals, where):
    view = envpis.PortalView(table, portals)
    assert view.prepare(POINTS[where])
    s = envpis.ProductSampler(table)
    assert s.prepare([0.2, 0.1, 0.97], [0.6, -0.2, 0.8], proxy(diffuse=0.3, reflection=0.7, alpha_r=0.2), view)
    check(s.sample, s.pdf, seed=12)


def test_density_is_zero_only_where_no_portal_is_seen(table, portals):
    view = envpis.PortalView(table, portals)
    assert view.prepare(POINTS["centre"])
    s = envpis.PortalEnvironmentSampler(table)
    assert s.prepare(view)
    d = np.random.default_rng(3).normal(size=(20000, 3)).astype(np.float32)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    through = view.passes(d) > 0
    assert through.any() and (~through).any()
    assert np.all(s.pdf(d)[through] > 0), "a direction through a portal must have light-sample density"
    assert view.cell_fractions().max() <= 1 and view.cell_fractions().min() >= 0


def test_product_without_a_view_is_unchanged(table):
    u = np.random.default_rng(5).random((256, 2)).astype(np.float32)
    p = proxy(diffuse=0.5, reflection=0.5, alpha_r=0.1)
    a, b = envpis.ProductSampler(table), envpis.ProductSampler(table)
    assert a.prepare([0, 0, 1], [0.3, 0.2, 0.9], p)
    assert b.prepare([0, 0, 1], [0.3, 0.2, 0.9], p, None)
    for x, y in zip(a.sample(u), b.sample(u)):
        np.testing.assert_array_equal(x, y)


def test_a_point_that_sees_no_portal_has_no_sample(table, portals):
    view = envpis.PortalView(table, portals)
    assert not view.prepare([5, 0, 4])  # outside: on the outer side of both one-sided portals
    assert not view.prepare([np.nan, 0, 1])
    s = envpis.PortalEnvironmentSampler(table)
    assert not s.prepare(view)
    dirs, pdfs = s.sample(np.full((4, 2), 0.5, dtype=np.float32))
    assert np.all(pdfs == 0) and np.all(np.isfinite(dirs))
    assert np.all(s.pdf(np.array([[1, 0, 0]], dtype=np.float32)) == 0)


@pytest.mark.parametrize("bad", [
    [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]],          # collinear
    [[0, 0, 0], [1, 0, 0], [1, 1, 0.5], [0, 1, 0]],        # not planar
    [[0, 0, 0], [1, 0, 0], [0.2, 0.2, 0], [0, 1, 0]],      # not convex
    [[0, 0, 0], [1, 0, 0], [1, np.nan, 0], [0, 1, 0]],     # not finite
])
def test_bad_quads_raise_the_library_error(bad):
    with pytest.raises(envpis.Error):
        envpis.Portals(np.array(bad, dtype=np.float32))


def test_bad_shapes_and_options_raise_clean_errors(table, portals):
    with pytest.raises(ValueError):
        envpis.Portals([[0, 0, 0], [1, 0, 0], [1, 1, 0]])
    with pytest.raises(ValueError):
        envpis.Portals("window")
    with pytest.raises(ValueError):
        envpis.PortalView(table, portals).prepare([0, 0])
    o = envpis.PortalViewOptions()
    with pytest.raises(envpis.Error):
        o.estimate = "exact"
    with pytest.raises(IndexError):
        portals.normal(2)
    many = envpis.Portals()
    for i in range(8):
        many.add(np.array(EAST, dtype=np.float32) + np.array([0, 0, 3 * i], dtype=np.float32))
    with pytest.raises(envpis.Error):
        many.add(EAST)
