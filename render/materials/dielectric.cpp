// SPDX-License-Identifier: Apache-2.0
// Rough GGX dielectric interface with reflection and refraction (Walter, Marschner, Li, Torrance,
// "Microfacet Models for Refraction through Rough Surfaces", EGSR 2007).
//
// eta = n_inside / n_outside, the normal (+Z) points outside. Every evaluation is reduced to wo above
// the surface: a wo below is mirrored through the origin together with wi and eta is inverted (the
// interface seen from inside). With eta the relative IOR seen from wo (n on wi's side / n on wo's side):
//   reflection (wi on wo's side), m = normalize(wo + wi):
//     f = F(wo.m) D(m) G2 / (4 |cos_o| |cos_i|)
//   refraction (wi on the other side), m = +-normalize(wo + eta wi) oriented to m_z > 0, requiring
//   wo.m > 0 > wi.m:
//     f = tint (1 - F(wo.m)) D(m) G2 |wo.m| |wi.m| eta^2 / (|cos_o| |cos_i| (wo.m + eta wi.m)^2)
//     pdf = (1 - P_r) D_wo(m) eta^2 |wi.m| / (wo.m + eta wi.m)^2
// where P_r = F / (F + (1 - F) avg(tint)) is the probability of reflecting off the sampled normal
// (P_r = F for clear glass; a dark tint sends fewer samples into the absorbed transmission), and the
// reflection pdf is P_r D_wo(m) / (4 wo.m).
// For refraction F(wo.m) is computed from both cosines (fresnel_dielectric_pair): the same value,
// but accurate near the critical angle and exactly reciprocal.
// Sampling: m ~ D_wo (Heitz 2018 visible normals), reflect with probability P_r (decided by uc), else
// refract; for clear glass the sample weight f |cos_i| / pdf is then G2 / G1(wo).
//
// Transport convention: the refraction term is the flux-conserving ("importance") form, i.e. it does
// NOT carry the 1/eta^2 radiance compression of pbrt-v4's TransportMode::Radiance. Consequences:
// the lobe's albedo (integral of f |cos_i|) is <= 1 from both sides (R + T = 1 up to the
// single-scattering loss of the GGX model), a clear glass's sample weight never exceeds 1, and the BTDF obeys
// the generalized reciprocity f(wo, wi) / n_i^2 = f(wi, wo) / n_o^2 (n_i: index on wi's side). For
// paths that start and end outside a closed dielectric object (the renderer's only case: the camera
// and the environment are outside) every entry is paired with an exit and the omitted eta^2 factors
// cancel exactly, so the images are the same as with the radiance form.
//
// eta == 1 (an index-matched interface) is invisible: it transmits straight through whatever its
// roughness, a delta that a non-delta lobe cannot represent. eta within 1% of 1 is therefore moved to
// 1 +- 0.01 and alpha to the minimum 1e-3: a very sharp but finite transmission (width ~1e-5 rad,
// reflectance 2.5e-5, weight ~1) around the macro-surface refraction, which is within
// 0.01 tan(theta_o) of -wo. Keeping the roughness would add nothing visible but
// GGX's spurious masking loss (3.5% at alpha 0.3).
// Total internal reflection: F = 1 for normals where refraction is impossible, so all energy reflects.
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

float sanitize_eta(float eta) { return std::isfinite(eta) && eta > 0 ? eta : 1.0f; }

bool index_matched(float eta) { return std::abs(eta - 1.0f) < 0.01f; }

class DielectricLobe final : public Lobe {
 public:
  DielectricLobe(float alpha, float eta, Rgb tint)
      : alpha_(microfacet::sanitize_alpha(alpha)), eta_(sanitize_eta(eta)), tint_(lobe::sanitize_color(tint)) {
    if (index_matched(eta_)) {
      eta_ = eta_ >= 1.0f ? 1.01f : 0.99f;
      alpha_ = microfacet::kMinAlpha;
      index_matched_ = true;
    }
    const float e = eta_;
    outside_ = microfacet::AlbedoTable::build(
        alpha_, [e](float c) { return microfacet::fresnel_dielectric(c, e); }, e);
    inside_ = microfacet::AlbedoTable::build(
        alpha_, [e](float c) { return microfacet::fresnel_dielectric(c, 1.0f / e); }, 1.0f / e);
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
    const float eta = wo.z > 0 ? eta_ : 1.0f / eta_;
    const Vec3 wo_up = wo * s;
    const Vec3 m = microfacet::ggx_sample_visible_normal(wo_up, alpha_, u);
    const float c = dot(wo_up, m);
    if (!(c > 0)) return std::nullopt;
    const float f = microfacet::fresnel_dielectric(c, eta);
    Vec3 wi;
    if (uc < reflect_probability(f)) {
      wi = microfacet::reflect(wo_up, m);
      if (!(wi.z > 0)) return std::nullopt;  // shadowed: the pdf has no mass here
    } else {
      if (!microfacet::refract(wo_up, m, eta, wi) || !(wi.z < 0)) return std::nullopt;
    }
    const Terms t = terms_up<true, true>(wo_up, wi, eta);
    return lobe::make_sample(wo, wi * s, t.f, t.pdf);
  }

  float albedo(Vec3 wo) const override {
    if (!microfacet::usable(wo)) return 0.0f;
    const microfacet::AlbedoTable& t = wo.z > 0 ? outside_ : inside_;
    return reflected(t, wo.z) + transmitted(t, wo.z);
  }

  /// Reflection and refraction lobes with their single-scattering energies as weights; the proxy
  /// itself inverts eta when wo is below the surface.
  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    if (!microfacet::usable(wo)) return;
    const microfacet::AlbedoTable& t = wo.z > 0 ? outside_ : inside_;
    proxy.add_reflection(weight * reflected(t, wo.z), alpha_);
    proxy.add_refraction(weight * transmitted(t, wo.z), alpha_, eta_);
  }

  std::string name() const override { return "dielectric"; }

  /// Without reflection (or refraction) the lobe keeps the other part alone, sampled alone. An
  /// index-matched interface keeps its sharpness: widened, the invisible interface would show.
  bool filtered(const LobeFilter& filter, std::shared_ptr<const Lobe>* changed) const override {
    const bool reflect = reflect_ && filter.reflection, refract = refract_ && filter.refraction;
    if (!reflect && !refract) return false;
    const bool widen = filter.min_alpha > alpha_ && !index_matched_;
    if (!widen && reflect == reflect_ && refract == refract_) return true;
    auto lobe = std::make_shared<DielectricLobe>(*this);
    if (widen) lobe->alpha_ = filter.min_alpha;
    lobe->reflect_ = reflect;
    lobe->refract_ = refract;
    *changed = std::move(lobe);
    return true;
  }

  float eta() const { return eta_; }

 private:
  /// Generalized half vector of a refraction pair (wo above, wi below), oriented up, and its cosines.
  bool refraction_half_vector(Vec3 wo, Vec3 wi, float eta, Vec3& m, float& co, float& ci) const {
    Vec3 h = wo + wi * eta;
    const float l2 = dot(h, h);
    if (!(l2 > 1e-24f)) return false;
    h = h * (1.0f / std::sqrt(l2));
    if (h.z < 0) h = -h;
    co = dot(wo, h);
    ci = dot(wi, h);
    if (!(co > 0) || !(ci < 0)) return false;  // back-facing microfacet: no such path
    m = h;
    return true;
  }

  /// The energies of the two parts (0 for a part a LobeFilter removed).
  float reflected(const microfacet::AlbedoTable& t, float mu) const { return reflect_ ? t.reflection(mu) : 0.0f; }
  float transmitted(const microfacet::AlbedoTable& t, float mu) const {
    return refract_ ? t.transmission(mu) * tint_.average() : 0.0f;
  }

  /// Probability of reflecting off a microfacet of Fresnel reflectance f (the part that is left when
  /// a LobeFilter removed the other).
  float reflect_probability(float f) const {
    if (!refract_) return 1.0f;
    if (!reflect_) return 0.0f;
    const float d = f + (1.0f - f) * tint_.average();
    return d > 0 ? f / d : 1.0f;
  }

  struct Terms {
    Rgb f;
    float pdf = 0;
  };

  /// f and / or the pdf (kValue, kPdf): one body for eval, pdf and eval_pdf.
  template <bool kValue, bool kPdf>
  Terms terms(Vec3 wo, Vec3 wi) const {
    if (!microfacet::usable(wo) || !microfacet::usable(wi)) return {};
    if (wo.z > 0) return terms_up<kValue, kPdf>(wo, wi, eta_);
    return terms_up<kValue, kPdf>(-wo, -wi, 1.0f / eta_);
  }

  /// The same for wo above the surface; eta = n_below / n_above.
  template <bool kValue, bool kPdf>
  Terms terms_up(Vec3 wo, Vec3 wi, float eta) const {
    return wi.z > 0 ? reflection_up<kValue, kPdf>(wo, wi, eta) : refraction_up<kValue, kPdf>(wo, wi, eta);
  }

  template <bool kValue, bool kPdf>
  Terms reflection_up(Vec3 wo, Vec3 wi, float eta) const {
    Terms t;
    const microfacet::GgxReflection g = microfacet::ggx_reflection_terms<kValue, kPdf>(wo, wi, alpha_);
    const float f = microfacet::fresnel_dielectric(g.cos_h, eta);
    if (kValue && reflect_ && g.value > 0) {
      const float v = f * g.value;
      t.f = {v, v, v};
    }
    if (kPdf) t.pdf = reflect_probability(f) * g.pdf;
    return t;
  }

  template <bool kValue, bool kPdf>
  Terms refraction_up(Vec3 wo, Vec3 wi, float eta) const {
    Terms t;
    Vec3 m;
    float co, ci;
    if (!refraction_half_vector(wo, wi, eta, m, co, ci)) return t;
    const float f = microfacet::fresnel_dielectric_pair(co, -ci, eta);
    if (!(f < 1.0f)) return t;
    const float denom = co + eta * ci;
    const float d = microfacet::ggx_d(m, alpha_), lambda_o = microfacet::ggx_lambda(wo, alpha_);
    if (kValue && refract_) {
      const float v = (1.0f - f) * d * microfacet::ggx_g2_of(lambda_o, microfacet::ggx_lambda(wi, alpha_)) * co *
                      (-ci) * eta * eta / (wo.z * (-wi.z) * denom * denom);
      if (std::isfinite(v)) t.f = tint_ * v;
    }
    if (kPdf) {
      const float p = (1.0f - reflect_probability(f)) *
                      microfacet::ggx_visible_normal_density(microfacet::ggx_g1_of(lambda_o), co, d, wo.z) * eta *
                      eta * (-ci) / (denom * denom);
      t.pdf = std::isfinite(p) ? p : 0.0f;
    }
    return t;
  }

  float alpha_, eta_;
  Rgb tint_;
  bool index_matched_ = false;
  bool reflect_ = true, refract_ = true;  ///< the parts a LobeFilter left
  microfacet::AlbedoTable outside_, inside_;
};

}  // namespace

std::shared_ptr<const Lobe> make_dielectric(float alpha, float eta, Rgb tint) {
  return std::make_shared<DielectricLobe>(alpha, eta, tint);
}

}  // namespace envpis::render
