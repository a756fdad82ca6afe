// SPDX-License-Identifier: Apache-2.0
#include "render/analyzer_integrand.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace envpis::render::analyzer_detail {

bool point_independent(Strategy s) { return s == Strategy::Env || s == Strategy::Mis || s == Strategy::MisComp; }

TexelCentres::TexelCentres(const EnvironmentMap& env, int n_, const std::vector<StrategyTables>& tables) : n(n_) {
  const std::size_t count = static_cast<std::size_t>(n) * n;
  direction.resize(count);
  radiance.resize(count);
  for (std::size_t k = 0; k < tables.size() && k < pdf.size(); ++k)
    if (point_independent(tables[k].strategy)) pdf[k].resize(count);
  tbb::parallel_for(tbb::blocked_range<int>(0, n), [&](const tbb::blocked_range<int>& rows) {
    std::vector<LightSampler> samplers;  // no prepare(): their densities do not depend on the point
    for (std::size_t k = 0; k < tables.size() && k < pdf.size(); ++k)
      if (!pdf[k].empty()) samplers.emplace_back(tables[k]);
    const std::size_t un = static_cast<std::size_t>(n);
    std::vector<float> u(un), v(un), dx(un), dy(un), dz(un);
    for (int x = 0; x < n; ++x) u[static_cast<std::size_t>(x)] = centre(x, n);
    for (int y = rows.begin(); y < rows.end(); ++y) {
      std::fill(v.begin(), v.end(), centre(y, n));
      equal_area_square_to_sphere(un, u.data(), v.data(), dx.data(), dy.data(), dz.data());
      for (std::size_t x = 0; x < un; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * un + x;
        const Vec3 d{dx[x], dy[x], dz[x]};
        direction[i] = d;
        radiance[i] = env.eval(d);
        std::size_t s = 0;
        for (auto& p : pdf)
          if (!p.empty()) p[i] = samplers[s++].pdf_texel(static_cast<int>(x), y, n);
      }
    }
  });
}

PointEvaluator::PointEvaluator(const Scene& scene, const SurfaceHit& hit, Vec3 wo, bool visibility,
                               const std::vector<StrategyTables>& tables, const TexelCentres& centres,
                               std::uint64_t jitter, std::vector<LightSampler>& samplers, int deferred)
    : scene_(scene),
      env_(scene.environment()),
      centres_(centres),
      hit_(hit),
      mat_(scene.material(hit.material)),
      hm_(resolve_material(scene, &hit_, &scratch_)),
      sn_(shading_normals(hit_, mat_.transmissive, wo)),
      frame_(sn_.ns),
      wo_l_(frame_.to_local(wo)),
      choice_(hm_.bsdf->choice(wo_l_)),
      visibility_(visibility),
      samplers_(samplers),
      deferred_(deferred) {
  ShadingContext sc;
  sc.n = sn_.ns;
  sc.wo = wo;
  sc.wo_local = wo_l_;
  sc.frame = &frame_;
  sc.bsdf = hm_.bsdf;
  sc.cos_bent = hm_.cos_bent;
  sc.jitter = jitter;
  sc.opaque = !mat_.transmissive;
  if (samplers_.size() != tables.size()) {  // the thread's first point: its samplers are reused after it
    samplers_.clear();
    for (const StrategyTables& t : tables) samplers_.emplace_back(t);
  }
  for (std::size_t k = 0; k < tables.size(); ++k) {
    if (k < fixed_.size() && !centres_.pdf[k].empty()) fixed_[k] = true;  // no prepare() needed
    else samplers_[k].prepare(sc);
  }
}

// The direction's values; the radiance and the densities come from the callables (the map and the
// samplers at an arbitrary point; the per-map arrays and the samplers' texel densities at a centre).
template <class Radiance, class Density>
bool PointEvaluator::eval(Vec3 d, Radiance radiance, Density density, DirectionValues* out,
                          OracleSampler::TexelBsdf* bsdf, int deferred) const {
  const Vec3 wl = frame_.to_local(d);
  if (bsdf) *bsdf = {Rgb{}, 0.0f, wl.z, false};
  if (!direction_counts(d, wl.z, sn_, mat_.transmissive)) return false;
  // The inside of a closed surface never sees the environment (Material::set_closed_surface).
  if (hm_.bsdf->closed_surface() && wl.z < 0) return false;
  float p_bsdf;
  const Rgb fr = hm_.bsdf->eval_pdf(wo_l_, wl, &p_bsdf, choice_);
  if (bsdf) *bsdf = {fr, p_bsdf, wl.z, true};
  const Rgb fb = fr * std::fabs(wl.z);
  if (is_black(fb)) return false;
  const Rgb f = fb * radiance();
  if (is_black(f) || !is_finite(f)) return false;
  out->f = f;
  out->f_blind = f.average();
  if (visibility_ && scene_.occluded(offset_ray_origin(hit_.p, hit_.ng, d), d)) out->f = Rgb{0, 0, 0};
  out->p_bsdf = p_bsdf;
  for (std::size_t k = 0; k < samplers_.size(); ++k)
    if (static_cast<int>(k) != deferred) out->p_light[k] = density(k);
  return true;
}

// Every density is looked up by the quadrature point's own equal-area point (LightSampler::pdf_square),
// not by mapping its direction back to the square: the point's texel is the one the quadrature means.
bool PointEvaluator::eval(Point2 p, DirectionValues* out) const {
  const Vec3 d = equal_area_square_to_sphere(p);
  return eval(d, [&] { return env_.eval(d); }, [&](std::size_t k) { return samplers_[k].pdf_square(p); }, out);
}

bool PointEvaluator::eval_centre(int x, int y, DirectionValues* out, OracleSampler::TexelBsdf* bsdf) const {
  const int n = centres_.n;
  const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(n) + static_cast<std::size_t>(x);
  return eval(
      centres_.direction[i], [&] { return centres_.radiance[i]; },
      [&](std::size_t k) { return fixed_[k] ? centres_.pdf[k][i] : samplers_[k].pdf_texel(x, y, n); }, out, bsdf,
      deferred_);
}

}  // namespace envpis::render::analyzer_detail
