// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: the renderer's glTF loader (render/gltf.h, load_gltf) on arbitrary file contents.
//
// Input layout: the bytes of one glTF file, written to a temporary file named input.glb when they
// start with the GLB magic "glTF" and input.gltf otherwise (assimp's glTF reader picks the binary or
// the JSON form by the name). The file is alone in its directory, so a URI of a buffer or an image
// that is not a data: URI names a missing file; fuzz/make_corpus.py --gltf inlines the resources of
// the seed models as data: URIs.
//
// Contract checked: load_gltf() either throws envpis::Error whose message is one non-empty line
// naming the file, or returns a model the renderer can use as it is:
//   - at least one part; every part's mesh is what Scene::add_mesh accepts (a non-empty multiple of
//     3 indices, each in range; normals and UVs empty or one per vertex) and its positions, normals
//     and UVs are finite; its material index is in range;
//   - material names are unique and non-empty; every material has its glTF (pbr) form, and at a few
//     UVs its assembled BSDF has eval, pdf, albedo and sample weights that are finite and >= 0, its
//     emission is finite and >= 0 and its normal-mapped shading normal is a finite unit vector;
//   - a camera, when present, has a positive image size, and either Camera rejects it with
//     envpis::Error or its primary rays are finite.
// Any other exception, a crash, a sanitizer report, a leak or a hang is a finding.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <set>
#include <string>

#include "render/camera.h"
#include "render/gltf.h"

namespace {

using namespace envpis;
using namespace envpis::render;

std::string g_dir;     // private scratch directory of this process
bool g_verbose = false;  // ENVPIS_FUZZ_VERBOSE=1: print each input's outcome

void remove_scratch() {
  if (g_dir.empty()) return;
  std::remove((g_dir + "/input.glb").c_str());
  std::remove((g_dir + "/input.gltf").c_str());
  rmdir(g_dir.c_str());
}

[[noreturn]] void violated(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_gltf: contract violated: %s (%s)\n", what, detail.c_str());
  std::abort();
}

bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool finite_nonnegative(Rgb c) {
  for (float v : {c.r, c.g, c.b})
    if (!(v >= 0) || !std::isfinite(v)) return false;
  return true;
}
std::string str(Vec3 v) { return std::to_string(v.x) + " " + std::to_string(v.y) + " " + std::to_string(v.z); }

void check_mesh(const GltfModel::Part& p, std::size_t materials) {
  const TriangleMesh& m = p.mesh;
  const std::size_t n = m.positions.size();
  if (p.material < 0 || std::size_t(p.material) >= materials) violated("part with an invalid material", p.name);
  if (m.indices.empty() || m.indices.size() % 3 != 0)
    violated("part without triangles", p.name + ": " + std::to_string(m.indices.size()) + " indices");
  if (!m.normals.empty() && m.normals.size() != n) violated("normal count differs from the vertex count", p.name);
  if (!m.uvs.empty() && m.uvs.size() != n) violated("UV count differs from the vertex count", p.name);
  for (std::uint32_t i : m.indices)
    if (i >= n) violated("vertex index out of range", p.name + ": " + std::to_string(i));
  for (Vec3 v : m.positions)
    if (!finite(v)) violated("non-finite position", str(v));
  for (Vec3 v : m.normals)
    if (!finite(v)) violated("non-finite normal", str(v));
  for (Point2 uv : m.uvs)
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) violated("non-finite UV", p.name);
}

void check_material(const SceneMaterial& sm) {
  if (!sm.pbr) violated("glTF material without its pbr form", sm.name);
  if (!finite_nonnegative(sm.emission)) violated("emission not finite and >= 0", sm.name);
  const Vec3 wo = normalize(Vec3{0.3f, -0.2f, 0.9f});
  const Vec3 wis[] = {normalize(Vec3{-0.3f, 0.2f, 0.9f}), normalize(Vec3{0.5f, 0.5f, 0.1f}), Vec3{0, 0, -1},
                      Vec3{0, 0, 1}};
  const Point2 uvs[] = {{0.5f, 0.5f}, {0, 0}, {0.999f, 0.25f}, {-3.7f, 12.2f}};
  Material bsdf;
  for (Point2 uv : uvs) {
    sm.pbr->assemble(uv, &bsdf);
    if (!finite_nonnegative(sm.pbr->emission(uv))) violated("textured emission not finite and >= 0", sm.name);
    const float albedo = bsdf.albedo(wo);
    if (!(albedo >= 0) || !std::isfinite(albedo)) violated("albedo not finite and >= 0", sm.name);
    for (Vec3 wi : wis) {
      const float pdf = bsdf.pdf(wo, wi);
      if (!finite_nonnegative(bsdf.eval(wo, wi)) || !(pdf >= 0) || !std::isfinite(pdf))
        violated("eval or pdf not finite and >= 0", sm.name);
    }
    for (float u : {0.1f, 0.6f, 0.95f})
      if (const auto s = bsdf.sample(wo, {u, 1 - u}, u))
        if (!finite_nonnegative(s->weight) || !(s->pdf >= 0) || !finite(s->wi))
          violated("sample not finite", sm.name);
    const Vec3 n = sm.pbr->normal_mapped(uv, {0, 0, 1}, {1, 0, 0}, 1);
    if (!finite(n) || std::fabs(length(n) - 1) > 1e-3f) violated("normal-mapped normal not unit", str(n));
  }
}

void check_camera(const CameraSpec& spec) {
  if (spec.width < 1 || spec.height < 1)
    violated("camera image size", std::to_string(spec.width) + "x" + std::to_string(spec.height));
  try {
    const Camera cam(spec, spec.width, spec.height);
    for (float f : {0.0f, 0.5f, 1.0f}) {
      const Ray r = cam.generate_ray(f * spec.width, f * spec.height);
      if (!finite(r.origin) || !finite(r.direction)) violated("camera ray not finite", str(r.direction));
    }
  } catch (const Error&) {
    // Rejected where the scene is set up: a clean error too.
  }
}

void check_model(const GltfModel& model) {
  if (model.parts.empty()) violated("model without parts", "");
  std::set<std::string> names;
  for (const SceneMaterial& m : model.materials) {
    if (m.name.empty() || !names.insert(m.name).second) violated("material names not unique", m.name);
    check_material(m);
  }
  for (const GltfModel::Part& p : model.parts) check_mesh(p, model.materials.size());
  if (model.camera) check_camera(*model.camera);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* tmp = std::getenv("TMPDIR");
  std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/envpis-fuzz-gltf-XXXXXX";
  if (!mkdtemp(templ.data())) {
    std::perror("fuzz_gltf: mkdtemp");
    std::abort();
  }
  g_dir = templ;
  std::atexit(remove_scratch);
  const char* verbose = std::getenv("ENVPIS_FUZZ_VERBOSE");
  g_verbose = verbose && std::strcmp(verbose, "1") == 0;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
  const std::string path = g_dir + (glb ? "/input.glb" : "/input.gltf");
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) {
      std::perror("fuzz_gltf: fopen");
      std::abort();
    }
    if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
  }
  try {
    const GltfModel model = load_gltf(path);
    if (g_verbose) {
      std::size_t triangles = 0;
      for (const GltfModel::Part& p : model.parts) triangles += p.mesh.indices.size() / 3;
      std::fprintf(stderr, "fuzz_gltf: loaded %zu parts, %zu triangles, %zu materials%s\n", model.parts.size(),
                   triangles, model.materials.size(), model.camera ? ", a camera" : "");
    }
    check_model(model);
  } catch (const Error& e) {
    const std::string msg = e.what();
    if (g_verbose) std::fprintf(stderr, "fuzz_gltf: error: %s\n", msg.c_str());
    if (msg.rfind(path + ": ", 0) != 0 || msg.size() <= path.size() + 2) violated("error not naming the file", msg);
    if (msg.find('\n') != std::string::npos || msg.find('\r') != std::string::npos)
      violated("error message of more than one line", msg);
  }
  std::remove(path.c_str());
  return 0;
}
