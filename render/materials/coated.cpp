// SPDX-License-Identifier: Apache-2.0
// Coated diffuse: a rough dielectric coat (GGX alpha, IOR eta) over a Lambertian base of albedo R.
//
// The approximation (an analytic layered model, not a stochastic walk through the layers):
//   f = f_coat + f_base
//   f_coat(wo, wi) = F(wo.m) D(m) G2 / (4 cos_o cos_i)           the coat's GGX specular reflection
//   f_base(wo, wi) = R (1 - E(cos_o)) (1 - E(cos_i)) (1 - F_int)
//                    / (pi (1 - E_avg) (1 - R F_int))
// where E(mu) is the coat's tabulated directional albedo (the energy its specular lobe reflects,
// AlbedoTable), E_avg = 2 int E(mu) mu dmu its cosine-weighted average, and
// F_int = 1 - (1 - E_avg) / eta^2 the diffuse reflectance of the coat's underside (the light the base
// scatters back up is partly reflected down again; summing that geometric series gives the
// 1 / (1 - R F_int) term, which also saturates the base colour as real coats do).
// Properties this keeps:
//   - reciprocal (both terms are symmetric in wo and wi);
//   - energy: the base term integrates to (1 - E(cos_o)) R (1 - F_int) / (1 - R F_int) <= 1 - E(cos_o),
//     so the total albedo is E + that <= 1, with equality for a white base: a white coated surface
//     loses no energy (the coat's single-scattering loss is handed to the base);
//   - for a smooth coat (E -> Fresnel, E_avg -> the hemispherical Fresnel average) f_base becomes the
//     classic smooth-plastic model R (1 - F_o)(1 - F_i) / (pi eta^2 (1 - R F_int)).
// What it ignores: refraction of the light inside the coat (the base lobe stays a cosine lobe, not
// narrowed toward the normal), absorption and thickness of the coat, and correlation between the
// coat's roughness and the directions that reach the base.
//
// Sampling: the coat's visible-normal reflection with probability E(cos_o) / (E(cos_o) + A_base(cos_o))
// (the two terms' albedos), else a cosine-weighted direction; the pdf is the same mixture.
// Two-sided like the other reflectors: a wo below is mirrored through the origin with wi.
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

class CoatedDiffuseLobe final : public Lobe {
 public:
  CoatedDiffuseLobe(Rgb base, float alpha, float eta)
      : base_(lobe::sanitize_color(base)), alpha_(microfacet::sanitize_alpha(alpha)) {
    eta_ = std::isfinite(eta) && eta > 0 ? eta : 1.0f;
    const float e = eta_;
    table_ = microfacet::AlbedoTable::build(
        alpha_, [e](float c) { return microfacet::fresnel_dielectric(c, e); }, 0.0f);
    const float e_avg = std::min(table_.average_reflection(), 0.999f);
    f_int_ = std::clamp(1.0f - (1.0f - e_avg) / (eta_ * eta_), 0.0f, 0.999f);
    auto channel = [&](float r) { return r * (1.0f - f_int_) / (kPi * (1.0f - e_avg) * (1.0f - r * f_int_)); };
    base_scale_ = {channel(base_.r), channel(base_.g), channel(base_.b)};
    auto albedo = [&](float r) { return r * (1.0f - f_int_) / (1.0f - r * f_int_); };
    base_albedo_ = {albedo(base_.r), albedo(base_.g), albedo(base_.b)};
  }

  Rgb eval(Vec3 wo, Vec3 wi) const override { return terms<true, false>(wo, wi).f; }
  float pdf(Vec3 wo, Vec3 wi) const override { return terms<false, true>(wo, wi).pdf; }
  Rgb eval_pdf(Vec3 wo, Vec3 wi, float* pdf) const override {
    const Terms t = terms<true, true>(wo, wi);
    *pdf = t.pdf;
    return t.f;
  }

  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float uc) const override {
    if (!microfacet::usable(wo)) return std::nullopt;
    const float s = wo.z > 0 ? 1.0f : -1.0f;
    const Vec3 wo_up = wo * s;
    Vec3 wi;
    const bool from_coat = uc < coat_probability(wo_up.z);
    if (from_coat) {
      const Vec3 m = microfacet::ggx_sample_visible_normal(wo_up, alpha_, u);
      if (!(dot(wo_up, m) > 0)) return std::nullopt;
      wi = microfacet::reflect(wo_up, m);
      if (!(wi.z > 0)) return std::nullopt;
    } else {
      wi = lobe::sample_cosine_hemisphere(u);
    }
    const Terms t = terms_up<true, true>(wo_up, wi);
    auto r = lobe::make_sample(wo, wi * s, t.f, t.pdf);
    if (r) r->diffuse = !from_coat;
    return r;
  }

  float albedo(Vec3 wo) const override {
    if (!microfacet::usable(wo)) return 0.0f;
    const float mu = std::abs(wo.z);
    return coat_energy(mu) + (1.0f - table_.reflection(mu)) * base_albedo_.average();
  }

  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    if (!microfacet::usable(wo)) return;
    const float mu = std::abs(wo.z);
    proxy.add_reflection(weight * coat_energy(mu), alpha_);
    proxy.add_diffuse(weight * (1.0f - table_.reflection(mu)) * base_albedo_.average());
  }

  std::string name() const override { return "coated_diffuse"; }

  /// The coat is the glossy reflection a LobeFilter widens or removes; the base stays as it is
  /// (its energy terms keep the original coat's table), as Cycles drops a Principled BSDF's coat
  /// closure and keeps its diffuse one.
  bool filtered(const LobeFilter& filter, std::shared_ptr<const Lobe>* changed) const override {
    const bool coat = coat_ && filter.reflection;
    const bool widen = coat && filter.min_alpha > alpha_;
    if (!widen && coat == coat_) return true;
    auto lobe = std::make_shared<CoatedDiffuseLobe>(*this);
    if (widen) lobe->alpha_ = filter.min_alpha;
    lobe->coat_ = coat;
    *changed = std::move(lobe);
    return true;
  }

 private:
  /// The energy the coat reflects for |cos theta_o| = mu (0 when a LobeFilter removed it).
  float coat_energy(float mu) const { return coat_ ? table_.reflection(mu) : 0.0f; }

  /// Probability of sampling the coat for |cos theta_o| = mu: its share of the albedo.
  float coat_probability(float mu) const {
    const float e = coat_energy(mu), d = (1.0f - table_.reflection(mu)) * base_albedo_.average();
    return e + d > 0 ? e / (e + d) : (coat_ ? 1.0f : 0.0f);
  }

  struct Terms {
    Rgb f;
    float pdf = 0;
  };

  /// f and / or the pdf (kValue, kPdf): one body for eval, pdf and eval_pdf.
  template <bool kValue, bool kPdf>
  Terms terms(Vec3 wo, Vec3 wi) const {
    if (!microfacet::usable(wo) || !microfacet::usable(wi)) return {};
    if (wo.z < 0) {
      wo = -wo;
      wi = -wi;
    }
    return terms_up<kValue, kPdf>(wo, wi);
  }

  /// The same for wo above the surface.
  template <bool kValue, bool kPdf>
  Terms terms_up(Vec3 wo, Vec3 wi) const {
    Terms t;
    if (!(wi.z > 0)) return t;
    const microfacet::GgxReflection g = microfacet::ggx_reflection_terms<kValue, kPdf>(wo, wi, alpha_);
    if (kValue) {
      const float coat = g.value > 0 && coat_ ? microfacet::fresnel_dielectric(g.cos_h, eta_) * g.value : 0.0f;
      const float b = (1.0f - table_.reflection(wo.z)) * (1.0f - table_.reflection(wi.z));
      t.f = Rgb{coat, coat, coat} + base_scale_ * b;
    }
    if (kPdf) {
      const float pc = coat_probability(wo.z);
      t.pdf = pc * g.pdf + (1.0f - pc) * lobe::cosine_hemisphere_pdf(wi.z);
    }
    return t;
  }

  Rgb base_;
  float alpha_, eta_ = 1.0f;
  bool coat_ = true;  ///< false when a LobeFilter removed the coat's reflection
  float f_int_ = 0;
  Rgb base_scale_;   ///< R (1 - F_int) / (pi (1 - E_avg) (1 - R F_int))
  Rgb base_albedo_;  ///< R (1 - F_int) / (1 - R F_int)
  microfacet::AlbedoTable table_;
};

}  // namespace

std::shared_ptr<const Lobe> make_coated_diffuse(Rgb base, float alpha, float eta) {
  return std::make_shared<CoatedDiffuseLobe>(base, alpha, eta);
}

}  // namespace envpis::render
