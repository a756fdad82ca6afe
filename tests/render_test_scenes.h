// SPDX-License-Identifier: Apache-2.0
// Scenes shared by the renderer's tests: one sphere under a given sky, and a one-lobe material.
#pragma once

#include <memory>
#include <utility>

#include "render/material.h"
#include "render/scene.h"

namespace envpis::test {

using render::CameraSpec;
using render::Lobe;
using render::Material;
using render::Scene;

/// One unit sphere of material `m` seen from -Y (nothing else in the scene: visibility is the horizon).
inline Scene sphere_scene(Material m, bool transmissive, std::shared_ptr<const EnvironmentMap> env) {
  Scene s;
  s.add_material("m", std::move(m), transmissive);
  s.add_sphere("sphere", {0, 0, 0}, 1.0f, 0);
  s.set_camera(render::look_at({0, -10, 0}, {0, 0, 0}, 14.0f, 48, 48));
  s.set_environment(std::move(env));
  s.commit();
  return s;
}

/// A material of one lobe with weight 1; `closed`: Material::set_closed_surface.
inline Material single(std::shared_ptr<const Lobe> lobe, bool closed = false) {
  Material m;
  m.add(std::move(lobe), 1.0f);
  m.set_closed_surface(closed);
  return m;
}

}  // namespace envpis::test
