// SPDX-License-Identifier: Apache-2.0
// glTF 2.0 files (.gltf, .glb) for the renderer: geometry and cameras through assimp (Debian
// libassimp-dev), materials and textures read from the file's JSON (render/pbr_material.h says how
// they map to lobes). Coordinates: glTF is +Y up, the renderer +Z up; the loader turns the model
// by +90 degrees about X (glTF (x, y, z) -> (x, -z, y)).
//
// Meshes are grouped by material: a model becomes one triangle mesh per glTF material it uses, each
// with positions, normals and TEXCOORD_0 in world space (node transforms applied). Only TEXCOORD_0 is
// read; a texture that asks for another set is an error, as is any file assimp rejects, an index or
// accessor out of range, or a texture that cannot be decoded: load_gltf throws Error with one line
// that names the file.
//
// Portals (docs/scene-format.md, "Portals in glTF"): a node whose name starts with "portal" is not
// geometry but a portal quad in a window opening, its front face (counter-clockwise winding, as glTF
// defines it) looking out of the room. Its triangles become one quad (render/scene_portals.h), node
// transforms applied; a node that is not a planar convex quad is an Error naming the file and the node.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "render/camera.h"
#include "render/scene.h"
#include "envpis/portals.h"

namespace envpis::render {

struct GltfModel {
  struct Part {
    std::string name;  ///< the glTF material's name (or "material-<index>")
    TriangleMesh mesh;
    int material = 0;  ///< index into materials
  };
  std::vector<Part> parts;
  std::vector<SceneMaterial> materials;  ///< named like the parts; pbr set, bsdf its untextured look
  std::optional<CameraSpec> camera;      ///< the first camera of the node tree, if any
  struct Portal {
    std::string node;  ///< the glTF node's name (for messages)
    Quad quad;         ///< in the renderer's frame, counter-clockwise seen from outside
  };
  std::vector<Portal> portals;  ///< validated together by Portals (at most Portals::kMaxPortals)
};

/// Whether a glTF node with this name is a portal rather than geometry.
bool is_portal_node(const std::string& name);

GltfModel load_gltf(const std::string& path);

/// SceneMaterial for a PbrMaterial: bsdf is the material (untextured) or its look at uv (0.5, 0.5).
SceneMaterial make_pbr_scene_material(std::string name, std::shared_ptr<const PbrMaterial> pbr);

}  // namespace envpis::render
