// SPDX-License-Identifier: Apache-2.0
// The renderer's scene: materials, objects (analytic spheres and triangle meshes) in an Embree 3
// scene, a camera and the environment map that lights everything.
//
// Lifetime (Embree's): add materials and objects, set the camera and environment, then commit()
// once; afterwards the scene is immutable and intersect()/occluded() are thread-safe.
//
// Orientation: a sphere's geometric normal points outwards. A mesh's geometric normal follows the
// triangle winding (counter-clockwise seen from the front), unless the mesh has vertex normals: then
// it is flipped where needed to agree with them. A dielectric's "outside" is where the normal points.
//
// Closed surfaces: a sphere is closed; a mesh is closed when, after welding vertices at equal
// positions, each edge is shared by exactly two triangles whose geometric normals (as above) are
// consistently oriented, pointing out of the volume (positive signed volume). commit() marks a
// transmissive material whose objects are all closed with Material::set_closed_surface(true), so the
// product strategy's BSDF proxy leaves out the lobes that point inside, where no light sample can
// reach the environment (docs/proxy.md, "Closed surfaces"). set_proxy_closed_surfaces(false) turns
// that off (commit() then clears the flag on every material).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "envpis/envpis.h"
#include "render/camera.h"
#include "render/material.h"
#include "render/math.h"
#include "render/pbr_material.h"

namespace envpis::render {

/// A material of the scene: the BSDF plus what the integrator must know about it.
struct SceneMaterial {
  std::string name;
  Material bsdf;
  /// True when the BSDF transmits light (dielectric, translucent): it is then one-sided (its frame
  /// keeps the outward normal and wo may be below it). Opaque materials are two-sided: their frame
  /// is flipped towards the viewer.
  bool transmissive = false;
  /// A glTF metallic-roughness material (render/pbr_material.h). When it is textured, the integrator
  /// assembles the BSDF per shading point from it, and `bsdf` holds its untextured factors (used
  /// for the name and the closed-surface flag only); otherwise `bsdf` is the material.
  std::shared_ptr<const PbrMaterial> pbr;
  Rgb emission{0, 0, 0};  ///< emitted radiance when there is no textured pbr material
  bool textured() const { return pbr && pbr->textured(); }
};

struct TriangleMesh {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;           ///< per vertex (same count as positions) or empty (flat shading)
  std::vector<std::uint32_t> indices;  ///< three per triangle
  std::vector<Point2> uvs;             ///< per vertex (glTF convention, render/texture.h) or empty
};

enum class ObjectType { Sphere, Mesh };

struct ObjectInfo {
  std::string name;
  ObjectType type = ObjectType::Sphere;
  int material = 0;
  Vec3 center;       ///< sphere centre (spheres only)
  float radius = 0;  ///< sphere radius (spheres only)
  std::size_t triangles = 0;
  bool closed = false;  ///< a closed surface with outward normals (see above)
};

struct SurfaceHit {
  float t = 0;
  Vec3 p;       ///< hit point
  Vec3 ng;      ///< unit geometric normal (outward / as authored, not flipped towards the ray)
  Vec3 ns;      ///< unit shading normal, on the same side as ng
  int object = -1;
  int material = -1;
  Point2 uv{0, 0};            ///< texture coordinates (meshes with UVs; else 0)
  Vec3 dpdu{0, 0, 0};         ///< the triangle's tangent along +u (meshes with UVs; else 0)
  float bitangent_sign = 1;   ///< +1: bitangent = cross(ns, tangent) (glTF's right-handed frame)
};

class Scene {
 public:
  Scene();
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// Returns the material id. Names must be unique and the material non-empty (throws Error).
  int add_material(std::string name, Material bsdf, bool transmissive);
  /// The same for a full SceneMaterial (pbr, emission); its name must be set.
  int add_material(SceneMaterial material);
  /// Material id by name, or -1.
  int find_material(const std::string& name) const;
  const SceneMaterial& material(int id) const { return materials_[static_cast<std::size_t>(id)]; }
  int material_count() const { return static_cast<int>(materials_.size()); }

  /// Returns the object id (also its index in objects(), and the value of the object-id AOV).
  int add_sphere(std::string name, Vec3 center, float radius, int material);
  int add_mesh(std::string name, TriangleMesh mesh, int material);
  const std::vector<ObjectInfo>& objects() const { return objects_; }

  void set_camera(const CameraSpec& spec) { camera_ = spec; }
  const CameraSpec& camera() const { return camera_; }
  void set_environment(std::shared_ptr<const EnvironmentMap> env) { env_ = std::move(env); }
  const EnvironmentMap& environment() const { return *env_; }
  std::shared_ptr<const EnvironmentMap> environment_ptr() const { return env_; }
  bool has_environment() const { return env_ != nullptr; }
  /// A human-readable description of where the environment came from (file path or "procedural sky").
  void set_environment_description(std::string d) { env_description_ = std::move(d); }
  const std::string& environment_description() const { return env_description_; }

  /// Whether transmissive materials used only by closed objects are marked as closed surfaces
  /// (default true; see above). Before commit(), commit() applies it; after, the flags are updated
  /// at once (they do not touch the acceleration structure). Not while rendering.
  void set_proxy_closed_surfaces(bool enable);
  /// Whether the product strategy widens its proxy's roughness where a normal map bends the shading
  /// normal away from the geometric one (envpis::widen_roughness; default true; docs/assets.md
  /// measures it).
  void set_widen_bent_normals(bool enable) { widen_bent_normals_ = enable; }
  bool widen_bent_normals() const { return widen_bent_normals_; }
  bool proxy_closed_surfaces() const { return proxy_closed_surfaces_; }

  /// The scene's portals (envpis/portals.h: quads in the window openings, counter-clockwise seen from
  /// outside), used by the portal-aware strategies (render/strategy.h). Empty by default; they are not
  /// geometry (rays pass through them) and other strategies ignore them.
  void set_portals(Portals portals) { portals_ = std::move(portals); }
  const Portals& portals() const { return portals_; }

  /// Scenes with at most `n` spheres (default kDirectSphereLimit) test them directly, outside Embree:
  /// for a handful of spheres that is cheaper than Embree's dispatch (BENCHMARKS.md, "Spheres
  /// outside Embree, the sampler's seeds per pixel"); more go into Embree's BVH. Hits are the same up
  /// to round-off. Before commit() only; 0 puts every sphere into Embree.
  static constexpr int kDirectSphereLimit = 8;
  void set_direct_sphere_limit(int n);

  /// Builds the Embree acceleration structure and sets each material's closed-surface flag. Throws
  /// Error when there is no environment, no object or Embree fails.
  void commit();
  bool committed() const { return committed_; }

  /// Closest hit along the ray in (0, ray.tmax). Returns false on a miss.
  bool intersect(const Ray& ray, SurfaceHit* hit) const;
  /// True if anything blocks the segment (origin, origin + dir * tmax).
  bool occluded(Vec3 origin, Vec3 dir, float tmax = kInfinity) const;

 private:
  struct Embree;
  std::unique_ptr<Embree> embree_;
  std::vector<SceneMaterial> materials_;
  std::vector<ObjectInfo> objects_;
  std::vector<TriangleMesh> meshes_;  // indexed like objects_ (empty for spheres)
  std::vector<std::vector<Vec3>> face_normals_;
  struct FaceTangent {
    Vec3 dpdu;
    float sign;
  };
  std::vector<std::vector<FaceTangent>> face_tangents_;  // meshes with UVs only
  CameraSpec camera_;
  std::shared_ptr<const EnvironmentMap> env_;
  std::string env_description_;
  bool proxy_closed_surfaces_ = true;
  bool widen_bent_normals_ = true;
  Portals portals_;
  void update_closed_surface_flags();
  static std::vector<FaceTangent> face_tangents(const TriangleMesh& m, const std::vector<Vec3>& fn);
  bool committed_ = false;
  int direct_sphere_limit_ = kDirectSphereLimit;
  /// A hit's fields every object type sets alike (no texture coordinates or tangent yet).
  void begin_hit(int id, float t, SurfaceHit* hit) const;
  void sphere_hit(const Ray& ray, int id, float t, SurfaceHit* hit) const;
};

}  // namespace envpis::render
