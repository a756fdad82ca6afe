// SPDX-License-Identifier: Apache-2.0
// The analyzer's integrand (render/analyzer.h): f = BSDF x |cos| x radiance (x visibility) and every
// density at one quadrature direction of one shading point. Internal to the analyzer.
//
// What does not depend on the shading point is computed once per map (TexelCentres): the direction
// of every fine texel's centre, the radiance there and the densities of the light distributions that
// need no prepare() (the environment table of env and mis, mis-comp's table). The first pass of every
// point evaluates exactly these directions, so each point then pays only for its BSDF and its own
// distributions (product, oracle); the values are the same bits as evaluating them per point.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "render/integrator.h"
#include "render/oracle.h"
#include "render/scene.h"
#include "render/strategy.h"

namespace envpis::render::analyzer_detail {

constexpr int kMaxDistributions = 4;  // environment table, compensated table, product, oracle

/// The integrand and every density at one quadrature direction.
struct DirectionValues {
  Rgb f;              // BSDF * |cos| * radiance * visibility
  float f_blind = 0;  // channel average of f without visibility: what the limits sample
  float p_bsdf = 0;
  std::array<float, kMaxDistributions> p_light{};
};

/// Whether a light distribution's density is the same at every shading point (no prepare()).
bool point_independent(Strategy s);

/// Per fine texel of the n x n equal-area grid (row-major): its centre's direction and radiance, and
/// the densities of the point-independent distributions among `tables` there (empty for the others).
struct TexelCentres {
  int n = 0;
  std::vector<Vec3> direction;
  std::vector<Rgb> radiance;
  std::array<std::vector<float>, kMaxDistributions> pdf;

  TexelCentres(const EnvironmentMap& env, int n, const std::vector<StrategyTables>& tables);
  /// The equal-area coordinate of the centre of texel x (or row y) of n.
  static float centre(int x, int n) { return texel_centre(x, 0, n).x; }
};

/// What one thread's first pass keeps from point to point: the grid of watched values and a band of
/// rows (render/analyzer.cpp).
struct PassScratch {
  std::vector<std::array<float, 3>> grid;
  std::vector<DirectionValues> values;
  std::vector<char> counts;  // per texel of the band: whether f is not 0 there
  std::vector<std::array<int, 2>> texel;  // the band's counted texels (x, y)
  std::vector<OracleSampler::TexelBsdf> bsdf, cell;
};

/// Everything about one shading point that the quadrature evaluates.
class PointEvaluator {
 public:
  /// `deferred` (-1: none): a distribution whose density eval_centre() leaves to the caller (pdf_square).
  PointEvaluator(const Scene& scene, const SurfaceHit& hit, Vec3 wo, bool visibility,
                 const std::vector<StrategyTables>& tables, const TexelCentres& centres, std::uint64_t jitter,
                 std::vector<LightSampler>& samplers, int deferred = -1);
  PointEvaluator(const PointEvaluator&) = delete;
  PointEvaluator& operator=(const PointEvaluator&) = delete;

  /// The values at (the direction of) equal-area point p; false when f is 0 there even without visibility.
  bool eval(Point2 p, DirectionValues* out) const;
  /// The same at the centre of fine texel (x, y), from the per-map values, but for the deferred
  /// distribution's density. `bsdf` (may be null) receives the material's value there when evaluated.
  bool eval_centre(int x, int y, DirectionValues* out, OracleSampler::TexelBsdf* bsdf = nullptr) const;
  /// Distribution k's density at equal-area point p.
  float pdf_square(std::size_t k, Point2 p) const { return samplers_[k].pdf_square(p); }

 private:
  template <class Radiance, class Density>
  bool eval(Vec3 d, Radiance radiance, Density density, DirectionValues* out,
            OracleSampler::TexelBsdf* bsdf = nullptr, int deferred = -1) const;

  const Scene& scene_;
  const EnvironmentMap& env_;
  const TexelCentres& centres_;
  SurfaceHit hit_;  // its shading normal bent by a normal map, if any
  const SceneMaterial& mat_;
  Material scratch_;  // a textured material's lobes at this hit
  HitMaterial hm_;    // points into scratch_: the evaluator is neither copied nor moved
  ShadingNormals sn_;
  Frame frame_;
  Vec3 wo_l_;
  Material::Choice choice_;  // the material's lobe choice at wo_l_
  bool visibility_;
  std::vector<LightSampler>& samplers_;  // the thread's, one per table (built at its first point)
  std::array<bool, kMaxDistributions> fixed_{};  // per distribution: its density is in centres_.pdf
  int deferred_;
};

}  // namespace envpis::render::analyzer_detail
