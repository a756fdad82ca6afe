// SPDX-License-Identifier: Apache-2.0
// The integrators: environment lighting, plus the emission of emissive (glTF) materials, added where a
// path hits them (they are not light-sampled).
//
//   direct  one bounce: the camera ray's first hit gathers environment light with the strategy's
//           light sample and one BSDF sample (combined by MIS for mis, mis-comp, product, oracle),
//           with shadow rays. Camera rays that miss see the environment.
//   path    the same estimate at every vertex of a path continued by BSDF sampling, Russian roulette
//           from depth rr_depth on, at most max_depth surface interactions.
//
// Per vertex, for a strategy with light samples: one light sample (weight w_l / p_l) and one BSDF
// sample; the BSDF sample's direction, if it reaches the environment, adds its radiance with weight
// w_b (0 for `env`, 1 for `bsdf`), and otherwise continues the path. `direct` is `path` with
// max_depth 1 and no Russian roulette.
//
// Textured materials (SceneMaterial::textured) are assembled per shading point into a per-thread
// Material (render/pbr_material.h); a normal map replaces the shading normal (kept on the geometric
// normal's side) and, with Scene::widen_bent_normals, the product strategy's proxy is widened by the
// angle between the two (ShadingContext::cos_bent).
//
// Path regularization (render/regularization.h, off by default) clamps each contribution, and
// filters each vertex's lobes from what the path did before it (PathRegularizer).
//
// Light samples that arrive below the surface (of an opaque material), that have pdf 0, or whose
// geometric and shading sides disagree contribute nothing.
#pragma once

#include <string>

#include "render/firefly_log.h"
#include "render/regularization.h"
#include "render/sampler.h"
#include "render/scene.h"
#include "render/strategy.h"

namespace envpis::render {

enum class IntegratorKind { Direct, Path };
IntegratorKind parse_integrator(const std::string& s);  ///< "direct" | "path"
const char* to_string(IntegratorKind k);

struct IntegratorOptions {
  IntegratorKind kind = IntegratorKind::Path;
  Heuristic heuristic = Heuristic::Power;
  int max_depth = 8;  ///< path: maximum number of surface interactions (>= 1)
  int rr_depth = 3;   ///< path: Russian roulette from this many interactions on
  RegularizationOptions regularization;  ///< Cycles' clamp, caustics and filter glossy (default: off)
};

/// Random-number dimensions used by one pixel sample: 2 for the pixel position, then a fixed block
/// per path vertex (so a vertex's numbers do not depend on what earlier vertices consumed).
constexpr unsigned kPixelDimensions = 2;
constexpr unsigned kDimensionsPerVertex = 8;
/// Within a vertex's block: light sample 0-1, BSDF sample 2-3, lobe choice 4, Russian roulette 5.
constexpr unsigned kRouletteDimension = 5;

/// The normals a hit is shaded with, seen from wo (unit, pointing away from the surface): an opaque
/// material is two-sided, so both normals are flipped towards wo; a shading normal on the other side
/// of wo than the geometric one is replaced by the geometric one.
struct ShadingNormals {
  Vec3 ng, ns;
};
ShadingNormals shading_normals(const SurfaceHit& hit, bool transmissive, Vec3 wo);

/// The BSDF at a hit: the scene material itself, or a textured one's lobes assembled at the hit's UV
/// into `scratch` (no allocation once it has grown). A normal map bends hit->ns; cos_bent is then the
/// cosine between the bent and the geometric normal when the scene widens the proxy for bent normals,
/// else 1. emission is what the surface emits towards the viewer.
struct HitMaterial {
  const Material* bsdf = nullptr;
  float cos_bent = 1;
  Rgb emission;
};
HitMaterial resolve_material(const Scene& scene, SurfaceHit* hit, Material* scratch);

/// Whether direction wi (world; local_z its component along the shading normal) can bring light to a
/// hit with normals `sn`: above the geometric surface unless the material transmits, and on the same
/// side of the geometric and the shading normal (no light leaks through shading normals). Light and
/// BSDF samples outside this set contribute nothing to the direct estimate.
inline bool direction_counts(Vec3 wi, float local_z, const ShadingNormals& sn, bool transmissive) {
  const bool above = dot(wi, sn.ng) > 0;
  return (transmissive || above) && above == (local_z > 0);
}

class Integrator {
 public:
  Integrator(const Scene& scene, const IntegratorOptions& options);
  /// Radiance arriving along the camera ray. `log` (null: off) sees every light and BSDF sample
  /// contribution that exceeds its threshold (render/firefly_log.h); it changes nothing.
  /// `light_part` (null: off) receives the part of the result that light samples brought (every
  /// vertex's; the rest came from BSDF samples, emission and the camera's view of the environment).
  Rgb li(const Ray& camera_ray, PixelSampler& rng, LightSampler& light, FireflyRecorder* log = nullptr,
         Rgb* light_part = nullptr) const;
  const IntegratorOptions& options() const { return options_; }

 private:
  struct Vertex;
  float mis_weight(float pdf_f, float pdf_g) const;
  /// The light sample `ls`'s contribution at vertex v (0 when it counts for nothing).
  Rgb light_sample(const Vertex& v, const DirectionSample& ls, const LightSampler& light, const PathRegularizer& reg,
                   FireflyRecorder* log) const;
  const Scene& scene_;
  const EnvironmentMap& env_;
  IntegratorOptions options_;
};

}  // namespace envpis::render
