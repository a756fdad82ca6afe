// SPDX-License-Identifier: Apache-2.0
// The render tests' shared environment (test_render.cpp, test_scene_file.cpp).
#pragma once

#include <memory>

#include "render/scenes.h"

namespace envpis::render {

/// A small sky with a broad, moderately bright sun: hard enough that the strategies differ, soft
/// enough that per-pixel sample variances are trustworthy at tens of samples.
inline std::shared_ptr<const EnvironmentMap> test_sky() {
  static const auto env = [] {
    SkyOptions o;
    o.width = 128;
    o.height = 64;
    o.sun_elevation = 25.0f;
    o.sun_azimuth = 250.0f;  // behind and to the side of the fig1 camera (which looks along +Y)
    o.sun_radius = 6.0f;
    o.sun_radiance = 25.0f;
    return std::make_shared<const EnvironmentMap>(make_procedural_sky(o));
  }();
  return env;
}

}  // namespace envpis::render
