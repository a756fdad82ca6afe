// SPDX-License-Identifier: Apache-2.0
// Scenes: the built-in test scenes after the paper's figures, the procedural sky, and scene files
// (JSON, documented in docs/scene-format.md).
//
//   fig1   a row of eight unit spheres, left to right (object ids 0..7): GGX conductor (neutral metal,
//          f0 = 0.9) at roughness 0.02, 0.05, 0.1, 0.2, 0.3, 0.5, a diffuse sphere (albedo 0.8) and a
//          rough glass sphere (GGX dielectric, alpha 0.2, eta 1.5). No ground; 768 x 128 by default.
//          Default environment: the general default (below).
//   fig5   a gold GGX conductor torus knot (alpha 0.25, complex IOR of gold; a (2,3) knot tube of
//          ~19k triangles with smooth normals, object 0) on a dark diffuse ground square (object 1).
//          640 x 360 by default. Default environment: blender-data's studio.exr (several hot spots),
//          else the general default.
//
// General default environment: /usr/share/blender/datafiles/studiolights/world/sunset.exr when it
// exists (Debian package blender-data), else the built-in procedural sky (SkyOptions defaults).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/scene.h"

namespace envpis::render {

/// The built-in procedural sky (a lat-long map, +Z up): a sky gradient from a blue zenith to a pale
/// horizon, a uniform dark ground below the horizon, and a sun disc with a soft edge.
struct SkyOptions {
  int width = 512, height = 256;  ///< lat-long resolution
  float sun_elevation = 35.0f;    ///< degrees above the horizon
  float sun_azimuth = 225.0f;     ///< degrees from +X towards +Y
  float sun_radius = 1.5f;        ///< angular radius, degrees
  float sun_radiance = 1500.0f;   ///< radiance inside the disc
  float sky_radiance = 1.0f;      ///< scales the sky gradient (zenith ~0.3, horizon ~1)
  float ground_radiance = 0.08f;  ///< below the horizon
};
EnvironmentMap make_procedural_sky(const SkyOptions& options = {});

/// A map of constant radiance (white furnace).
EnvironmentMap make_constant_environment(Rgb radiance, int width = 16, int height = 8);

constexpr const char* kBlenderWorldDir = "/usr/share/blender/datafiles/studiolights/world";

/// The general default environment (see above); *description says which one was chosen.
std::shared_ptr<const EnvironmentMap> default_environment(std::string* description = nullptr);

const std::vector<std::string>& builtin_scene_names();  ///< {"fig1", "fig5"}
bool is_builtin_scene(const std::string& name);

/// Builds a built-in scene; env null = the scene's default environment. The scene is committed.
Scene make_builtin_scene(const std::string& name, std::shared_ptr<const EnvironmentMap> env = nullptr);

/// Loads a JSON scene file (or a glTF file, by its extension .gltf / .glb: load_gltf_scene); env
/// non-null overrides the file's environment. The scene is committed.
/// Throws Error naming the file and the offending field for every problem.
Scene load_scene_file(const std::string& path, std::shared_ptr<const EnvironmentMap> env = nullptr);

/// A glTF file (.gltf, .glb; render/gltf.h) as a whole scene: its materials, its first camera (or
/// one that frames the model from the front, slightly above), the default environment unless env.
Scene load_gltf_scene(const std::string& path, std::shared_ptr<const EnvironmentMap> env = nullptr);

/// The directories scene files name as ${NAME} (docs/assets.md):
///   ASSIMP_MODELS   $ENVPIS_ASSIMP_MODELS, else /usr/share/assimp/models (Debian assimp-testmodels)
///   ENVPIS_ASSETS   $ENVPIS_ASSETS, else ${XDG_CACHE_HOME:-$HOME/.cache}/envpis/assets (what
///                   scripts/fetch-assets.sh decodes from npm's @pmndrs/assets)
///   BLENDER_WORLDS  kBlenderWorldDir
/// Throws Error for another name.
std::string asset_directory(const std::string& name);

/// A built-in name, a scene file (.json) or a glTF file (.gltf, .glb) path; env_path non-empty
/// loads that map (overriding the scene's).
Scene load_scene(const std::string& name_or_file, const std::string& env_path = "");

/// Procedural meshes (also usable from scene files as "type": "torus-knot").
TriangleMesh make_torus_knot(int p = 2, int q = 3, float major = 2.0f, float minor = 0.8f, float tube = 0.45f,
                             int segments = 600, int sides = 32);
/// Horizontal, normal +Z, UVs spanning [0, 1]^2 (u along +X, v along -Y).
TriangleMesh make_quad(Vec3 center, float half_x, float half_y);

/// fig1's object ids, left to right, and their names.
const std::vector<std::string>& fig1_sphere_names();

}  // namespace envpis::render
