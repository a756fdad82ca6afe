# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures: small synthetic maps built with numpy (a bright sun on a sky gradient), in both
layouts, and their tables. PYTHONPATH must hold the build's python/ directory (CTest sets it)."""
import numpy as np
import pytest

import envpis

SUNSET = "/usr/share/blender/datafiles/studiolights/world/sunset.exr"


def sky_pixels(height, width, seed=7):
    """Radiance with structure at every scale: a gradient, noise, and a sun 200x brighter."""
    rng = np.random.default_rng(seed)
    y = np.linspace(0, 1, height)[:, None, None]
    pixels = (0.2 + y * np.array([0.3, 0.5, 1.0]) + 0.3 * rng.random((height, width, 3))).astype(np.float32)
    pixels[height // 4, width // 3] = 200.0
    return pixels


@pytest.fixture(scope="session")
def latlong_map():
    return envpis.EnvironmentMap.from_array(sky_pixels(32, 64), layout="latlong")


@pytest.fixture(scope="session")
def equal_area_map():
    return envpis.EnvironmentMap.from_array(sky_pixels(48, 48), layout="equal-area")


@pytest.fixture(scope="session")
def table(latlong_map):
    return envpis.ImportanceTable(latlong_map, top_resolution=12)


def random_points(n, seed):
    """n shading points: unit normals, wo on the normal's side (mostly), and mixed proxies."""
    rng = np.random.default_rng(seed)
    normals = rng.normal(size=(n, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    wo = rng.normal(size=(n, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    flip = np.sum(wo * normals, axis=1) < 0
    wo[flip & (rng.random(n) < 0.9)] *= -1
    proxies = np.zeros((n, 7), dtype=np.float32)
    proxies[:, 0] = rng.random(n)                      # diffuse
    proxies[:, 1] = rng.random(n) * (rng.random(n) < 0.2)  # translucent
    proxies[:, 2] = rng.random(n)                      # reflection
    proxies[:, 3] = rng.random(n) * (rng.random(n) < 0.3)  # refraction
    proxies[:, 4] = rng.random(n)                      # alpha_reflection
    proxies[:, 5] = rng.random(n)                      # alpha_refraction
    proxies[:, 6] = 1.0 + rng.random(n)                # ior
    return normals.astype(np.float32), wo.astype(np.float32), proxies
