// SPDX-License-Identifier: Apache-2.0
#include "render/scene.h"

#include "render/sphere.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <string>

namespace envpis::render {

struct Scene::Embree {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  bool empty = true;         // no geometry in `scene`: every object is a direct sphere
  std::vector<int> spheres;  // object ids of the spheres tested directly, outside Embree

  ~Embree() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

namespace {

const char* embree_error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "error";
}

void check_embree(RTCDevice device, const char* what) {
  const RTCError err = rtcGetDeviceError(device);
  if (err != RTC_ERROR_NONE) throw Error(std::string("embree: ") + what + " failed: " + embree_error_name(err));
}

/// Whether the mesh is a closed surface whose face normals fn point out of the volume it bounds:
/// after welding vertices at bit-identical positions (seams of UV-split or normal-split vertices),
/// every directed edge (a, b) of the triangles, taken counter-clockwise about their face normal,
/// occurs exactly once and its reverse (b, a) exactly once, and the signed volume is positive.
/// Triangles whose welded corners coincide are ignored (they have no area). Anything else (an
/// open border, a non-manifold edge, inconsistent or inward normals) is not closed.
bool mesh_is_closed_outward(const TriangleMesh& m, const std::vector<Vec3>& fn) {
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> weld;
  std::vector<std::uint32_t> id(m.positions.size());
  for (std::size_t i = 0; i < m.positions.size(); ++i) {
    std::array<std::uint32_t, 3> key;
    const float xyz[3] = {m.positions[i].x + 0.0f, m.positions[i].y + 0.0f, m.positions[i].z + 0.0f};  // -0 -> +0
    std::memcpy(key.data(), xyz, sizeof xyz);
    id[i] = weld.emplace(key, static_cast<std::uint32_t>(weld.size())).first->second;
  }
  std::vector<std::uint64_t> edges;
  edges.reserve(m.indices.size());
  double volume6 = 0;
  for (std::size_t t = 0; t < fn.size(); ++t) {
    std::uint32_t v[3] = {m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
    const Vec3 p0 = m.positions[v[0]], p1 = m.positions[v[1]], p2 = m.positions[v[2]];
    if (dot(cross(p1 - p0, p2 - p0), fn[t]) < 0) std::swap(v[1], v[2]);  // orient by the face normal
    const std::uint32_t a = id[v[0]], b = id[v[1]], c = id[v[2]];
    if (a == b || b == c || c == a) continue;
    for (auto [x, y] : {std::pair{a, b}, std::pair{b, c}, std::pair{c, a}})
      edges.push_back(std::uint64_t(x) << 32 | y);
    const Vec3 q0 = m.positions[v[0]], q1 = m.positions[v[1]], q2 = m.positions[v[2]];
    volume6 += double(dot(q0, cross(q1, q2)));
  }
  if (edges.empty()) return false;
  std::sort(edges.begin(), edges.end());
  if (std::adjacent_find(edges.begin(), edges.end()) != edges.end()) return false;  // an edge used twice one way
  for (std::uint64_t e : edges) {
    const std::uint64_t reverse = (e << 32) | (e >> 32);
    if (!std::binary_search(edges.begin(), edges.end(), reverse)) return false;  // a border edge
  }
  return volume6 > 0;
}

}  // namespace

/// Per triangle: dp/du from the UV parametrization (the tangent of a normal map's frame) and the
/// bitangent's handedness. glTF's v grows downwards in the image, so for an unmirrored mapping
/// cross(dp/du, dp/dv) points against the normal and the +Y (up) of a normal map is -dp/dv, which
/// is cross(n, dp/du): sign +1. Degenerate UVs give a tangent perpendicular to the normal.
std::vector<Scene::FaceTangent> Scene::face_tangents(const TriangleMesh& m, const std::vector<Vec3>& fn) {
  std::vector<FaceTangent> out(fn.size());
  for (std::size_t t = 0; t < fn.size(); ++t) {
    const std::uint32_t* id = &m.indices[3 * t];
    const Vec3 e1 = m.positions[id[1]] - m.positions[id[0]], e2 = m.positions[id[2]] - m.positions[id[0]];
    const float du1 = m.uvs[id[1]].x - m.uvs[id[0]].x, dv1 = m.uvs[id[1]].y - m.uvs[id[0]].y;
    const float du2 = m.uvs[id[2]].x - m.uvs[id[0]].x, dv2 = m.uvs[id[2]].y - m.uvs[id[0]].y;
    const float det = du1 * dv2 - du2 * dv1;
    FaceTangent ft{Frame(fn[t]).s, 1.0f};
    if (std::fabs(det) > 1e-20f && std::isfinite(det)) {
      const Vec3 dpdu = (e1 * dv2 - e2 * dv1) * (1.0f / det), dpdv = (e2 * du1 - e1 * du2) * (1.0f / det);
      if (is_valid_direction(dpdu)) {
        ft.dpdu = dpdu;
        ft.sign = dot(cross(dpdu, dpdv), fn[t]) <= 0 ? 1.0f : -1.0f;
      }
    }
    out[t] = ft;
  }
  return out;
}

Scene::Scene() = default;
Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

int Scene::add_material(std::string name, Material bsdf, bool transmissive) {
  SceneMaterial m;
  m.name = std::move(name);
  m.bsdf = std::move(bsdf);
  m.transmissive = transmissive;
  return add_material(std::move(m));
}

int Scene::add_material(SceneMaterial m) {
  if (committed_) throw Error("scene: cannot add a material after commit()");
  if (m.name.empty()) throw Error("scene: a material needs a name");
  if (find_material(m.name) >= 0) throw Error("scene: duplicate material name '" + m.name + "'");
  if (m.bsdf.empty() && !m.textured()) throw Error("scene: material '" + m.name + "' has no lobe");
  m.bsdf.set_name(m.name);
  materials_.push_back(std::move(m));
  return static_cast<int>(materials_.size()) - 1;
}

int Scene::find_material(const std::string& name) const {
  for (std::size_t i = 0; i < materials_.size(); ++i)
    if (materials_[i].name == name) return static_cast<int>(i);
  return -1;
}

int Scene::add_sphere(std::string name, Vec3 center, float radius, int material) {
  if (committed_) throw Error("scene: cannot add an object after commit()");
  if (!(radius > 0) || !std::isfinite(radius)) throw Error("scene: sphere '" + name + "' needs a positive radius");
  if (!std::isfinite(center.x) || !std::isfinite(center.y) || !std::isfinite(center.z))
    throw Error("scene: sphere '" + name + "' has a non-finite centre");
  if (material < 0 || material >= material_count())
    throw Error("scene: sphere '" + name + "' has an invalid material id");
  ObjectInfo o;
  o.name = std::move(name);
  o.type = ObjectType::Sphere;
  o.material = material;
  o.center = center;
  o.radius = radius;
  o.closed = true;
  objects_.push_back(std::move(o));
  meshes_.emplace_back();
  face_normals_.emplace_back();
  face_tangents_.emplace_back();
  return static_cast<int>(objects_.size()) - 1;
}

int Scene::add_mesh(std::string name, TriangleMesh mesh, int material) {
  if (committed_) throw Error("scene: cannot add an object after commit()");
  if (material < 0 || material >= material_count())
    throw Error("scene: mesh '" + name + "' has an invalid material id");
  if (mesh.indices.empty() || mesh.indices.size() % 3 != 0)
    throw Error("scene: mesh '" + name + "' has no triangle (or an index count that is not a multiple of 3)");
  if (!mesh.normals.empty() && mesh.normals.size() != mesh.positions.size())
    throw Error("scene: mesh '" + name + "' has " + std::to_string(mesh.normals.size()) + " normals for " +
                std::to_string(mesh.positions.size()) + " vertices");
  for (const Vec3& p : mesh.positions)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw Error("scene: mesh '" + name + "' has a non-finite vertex");
  if (!mesh.uvs.empty() && mesh.uvs.size() != mesh.positions.size())
    throw Error("scene: mesh '" + name + "' has " + std::to_string(mesh.uvs.size()) + " UVs for " +
                std::to_string(mesh.positions.size()) + " vertices");
  for (const Point2& uv : mesh.uvs)
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) throw Error("scene: mesh '" + name + "' has a non-finite UV");
  for (std::uint32_t i : mesh.indices)
    if (i >= mesh.positions.size()) throw Error("scene: mesh '" + name + "' has an out-of-range vertex index");
  for (Vec3& n : mesh.normals) n = is_valid_direction(n) ? normalize(n) : Vec3{0, 0, 0};

  const std::size_t tris = mesh.indices.size() / 3;
  std::vector<Vec3> fn(tris);
  for (std::size_t t = 0; t < tris; ++t) {
    const std::uint32_t* id = &mesh.indices[3 * t];
    const Vec3 p0 = mesh.positions[id[0]], p1 = mesh.positions[id[1]], p2 = mesh.positions[id[2]];
    Vec3 n = cross(p1 - p0, p2 - p0);
    n = is_valid_direction(n) ? normalize(n) : Vec3{0, 0, 1};
    if (!mesh.normals.empty()) {
      const Vec3 avg = mesh.normals[id[0]] + mesh.normals[id[1]] + mesh.normals[id[2]];
      if (dot(avg, n) < 0) n = -n;
    }
    fn[t] = n;
  }
  std::vector<FaceTangent> tangents;
  if (!mesh.uvs.empty()) tangents = face_tangents(mesh, fn);
  ObjectInfo o;
  o.name = std::move(name);
  o.type = ObjectType::Mesh;
  o.material = material;
  o.triangles = tris;
  o.closed = mesh_is_closed_outward(mesh, fn);
  objects_.push_back(std::move(o));
  meshes_.push_back(std::move(mesh));
  face_normals_.push_back(std::move(fn));
  face_tangents_.push_back(std::move(tangents));
  return static_cast<int>(objects_.size()) - 1;
}

void Scene::set_direct_sphere_limit(int n) {
  if (committed_) throw Error("scene: the direct sphere limit is set before commit()");
  direct_sphere_limit_ = std::max(0, n);
}

void Scene::set_proxy_closed_surfaces(bool enable) {
  proxy_closed_surfaces_ = enable;
  if (committed_) update_closed_surface_flags();
}

// Closed-surface flags: transmissive materials used (only) by closed objects.
void Scene::update_closed_surface_flags() {
  std::vector<char> closed(materials_.size(), 0), open(materials_.size(), 0);
  for (const ObjectInfo& o : objects_) (o.closed ? closed : open)[static_cast<std::size_t>(o.material)] = 1;
  for (std::size_t i = 0; i < materials_.size(); ++i)
    materials_[i].bsdf.set_closed_surface(proxy_closed_surfaces_ && materials_[i].transmissive && closed[i] &&
                                          !open[i]);
}

void Scene::commit() {
  if (committed_) return;
  if (!env_) throw Error("scene: no environment map");
  if (objects_.empty()) throw Error("scene: no object");
  update_closed_surface_flags();
  embree_ = std::make_unique<Embree>();
  embree_->device = rtcNewDevice(nullptr);
  if (!embree_->device) throw Error(std::string("embree: cannot create a device: ") + embree_error_name(rtcGetDeviceError(nullptr)));
  RTCDevice dev = embree_->device;
  embree_->scene = rtcNewScene(dev);
  check_embree(dev, "rtcNewScene");
  rtcSetSceneFlags(embree_->scene, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(embree_->scene, RTC_BUILD_QUALITY_HIGH);
  const auto sphere_count = std::count_if(objects_.begin(), objects_.end(),
                                         [](const ObjectInfo& o) { return o.type == ObjectType::Sphere; });
  const bool direct = sphere_count <= direct_sphere_limit_;
  for (std::size_t i = 0; i < objects_.size(); ++i) {
    const ObjectInfo& o = objects_[i];
    if (direct && o.type == ObjectType::Sphere) {
      embree_->spheres.push_back(static_cast<int>(i));
      continue;
    }
    embree_->empty = false;
    RTCGeometry g;
    if (o.type == ObjectType::Sphere) {
      g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
      check_embree(dev, "rtcNewGeometry(sphere)");
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), 1));
      check_embree(dev, "sphere buffer");
      v[0] = o.center.x;
      v[1] = o.center.y;
      v[2] = o.center.z;
      v[3] = o.radius;
    } else {
      const TriangleMesh& m = meshes_[i];
      g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
      check_embree(dev, "rtcNewGeometry(triangle)");
      auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                            3 * sizeof(float), m.positions.size()));
      check_embree(dev, "vertex buffer");
      for (std::size_t k = 0; k < m.positions.size(); ++k) {
        v[3 * k] = m.positions[k].x;
        v[3 * k + 1] = m.positions[k].y;
        v[3 * k + 2] = m.positions[k].z;
      }
      auto* idx = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                 3 * sizeof(unsigned), m.indices.size() / 3));
      check_embree(dev, "index buffer");
      for (std::size_t k = 0; k < m.indices.size(); ++k) idx[k] = m.indices[k];
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(embree_->scene, g, static_cast<unsigned>(i));
    rtcReleaseGeometry(g);
    check_embree(dev, "geometry commit");
  }
  rtcCommitScene(embree_->scene);
  check_embree(dev, "rtcCommitScene");
  committed_ = true;
}

bool Scene::intersect(const Ray& ray, SurfaceHit* hit) const {
  float t_sphere = ray.tmax;
  int sphere = -1;
  for (int i : embree_->spheres) {
    const ObjectInfo& o = objects_[static_cast<std::size_t>(i)];
    if (intersect_sphere(ray.origin, ray.direction, o.center, o.radius, t_sphere, &t_sphere)) sphere = i;
  }
  const auto direct_hit = [&] {
    if (sphere < 0) return false;
    sphere_hit(ray, sphere, t_sphere, hit);
    return true;
  };
  if (embree_->empty) return direct_hit();
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  rh.ray.org_x = ray.origin.x;
  rh.ray.org_y = ray.origin.y;
  rh.ray.org_z = ray.origin.z;
  rh.ray.dir_x = ray.direction.x;
  rh.ray.dir_y = ray.direction.y;
  rh.ray.dir_z = ray.direction.z;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = t_sphere;  // only what lies before the nearest direct sphere
  rh.ray.time = 0.0f;
  rh.ray.mask = 0xffffffffu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(embree_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return direct_hit();

  const int id = static_cast<int>(rh.hit.geomID);
  const ObjectInfo& o = objects_[static_cast<std::size_t>(id)];
  if (o.type == ObjectType::Sphere) {
    sphere_hit(ray, id, rh.ray.tfar, hit);
  } else {
    begin_hit(id, rh.ray.tfar, hit);
    const TriangleMesh& m = meshes_[static_cast<std::size_t>(id)];
    const std::uint32_t* tri = &m.indices[3 * static_cast<std::size_t>(rh.hit.primID)];
    const float u = rh.hit.u, v = rh.hit.v, w = 1.0f - u - v;
    hit->p = m.positions[tri[0]] * w + m.positions[tri[1]] * u + m.positions[tri[2]] * v;
    const Vec3 ng = face_normals_[static_cast<std::size_t>(id)][rh.hit.primID];
    hit->ng = ng;
    hit->ns = ng;
    if (!m.uvs.empty()) {
      hit->uv = {m.uvs[tri[0]].x * w + m.uvs[tri[1]].x * u + m.uvs[tri[2]].x * v,
                 m.uvs[tri[0]].y * w + m.uvs[tri[1]].y * u + m.uvs[tri[2]].y * v};
      const FaceTangent& ft = face_tangents_[static_cast<std::size_t>(id)][rh.hit.primID];
      hit->dpdu = ft.dpdu;
      hit->bitangent_sign = ft.sign;
    }
    if (!m.normals.empty()) {
      const Vec3 ns = m.normals[tri[0]] * w + m.normals[tri[1]] * u + m.normals[tri[2]] * v;
      if (is_valid_direction(ns)) {
        const Vec3 nn = normalize(ns);
        if (dot(nn, ng) > 0) hit->ns = nn;
      }
    }
  }
  return true;
}

void Scene::begin_hit(int id, float t, SurfaceHit* hit) const {
  hit->t = t;
  hit->uv = {0, 0};
  hit->dpdu = {0, 0, 0};
  hit->bitangent_sign = 1;
  hit->object = id;
  hit->material = objects_[static_cast<std::size_t>(id)].material;
}

void Scene::sphere_hit(const Ray& ray, int id, float t, SurfaceHit* hit) const {
  const ObjectInfo& o = objects_[static_cast<std::size_t>(id)];
  begin_hit(id, t, hit);
  const Vec3 p = ray.origin + ray.direction * t;
  Vec3 n = p - o.center;
  n = is_valid_direction(n) ? normalize(n) : Vec3{0, 0, 1};
  hit->p = o.center + n * o.radius;  // reprojected onto the sphere: less round-off than o + t d
  hit->ng = n;
  hit->ns = n;
}

bool Scene::occluded(Vec3 origin, Vec3 dir, float tmax) const {
  for (int i : embree_->spheres) {
    const ObjectInfo& o = objects_[static_cast<std::size_t>(i)];
    float t;
    if (intersect_sphere(origin, dir, o.center, o.radius, tmax, &t)) return true;
  }
  if (embree_->empty) return false;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRay r;
  r.org_x = origin.x;
  r.org_y = origin.y;
  r.org_z = origin.z;
  r.dir_x = dir.x;
  r.dir_y = dir.y;
  r.dir_z = dir.z;
  r.tnear = 0.0f;
  r.tfar = tmax;
  r.time = 0.0f;
  r.mask = 0xffffffffu;
  r.id = 0;
  r.flags = 0;
  rtcOccluded1(embree_->scene, &ctx, &r);
  return r.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

}  // namespace envpis::render
