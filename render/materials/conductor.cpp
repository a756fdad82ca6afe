// SPDX-License-Identifier: Apache-2.0
// GGX microfacet conductor (Cook-Torrance with the height-correlated Smith G2):
//   f(wo, wi) = F(wo.m) D(m) G2(wo, wi) / (4 |cos theta_o| |cos theta_i|),  m = normalize(wo + wi),
// with F the exact conductor Fresnel of a complex IOR eta + i k, or Schlick's from an RGB f0.
// Sampling: a visible normal m ~ D_wo (Heitz 2018), wi = reflect(wo, m); pdf = D_wo(m) / (4 wo.m).
// Two-sided: a wo below the surface is handled by mirroring both directions through the origin
// (the isotropic GGX surface looks the same from below).
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

class ConductorLobe final : public Lobe {
 public:
  ConductorLobe(float alpha, bool complex_ior, Rgb a, Rgb b)
      : alpha_(microfacet::sanitize_alpha(alpha)), complex_(complex_ior), a_(a), b_(b) {
    if (complex_) {
      auto ior = [](float v) { return std::isfinite(v) && v > 0 ? v : 1.0f; };  // eta: positive
      auto ext = [](float v) { return std::isfinite(v) && v > 0 ? v : 0.0f; };  // k: non-negative
      a_ = {ior(a.r), ior(a.g), ior(a.b)};
      b_ = {ext(b.r), ext(b.g), ext(b.b)};
    } else {
      auto f0 = [](float v) { return std::isfinite(v) ? std::clamp(v, 0.0f, 1.0f) : 0.0f; };
      a_ = {f0(a.r), f0(a.g), f0(a.b)};
    }
    table_ = microfacet::AlbedoTable::build(alpha_, [this](float c) { return fresnel(c).average(); }, 0.0f);
  }

  Rgb eval(Vec3 wo, Vec3 wi) const override { return terms<true, false>(wo, wi).f; }
  float pdf(Vec3 wo, Vec3 wi) const override { return terms<false, true>(wo, wi).pdf; }
  Rgb eval_pdf(Vec3 wo, Vec3 wi, float* pdf) const override {
    const Terms t = terms<true, true>(wo, wi);
    *pdf = t.pdf;
    return t.f;
  }

  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float) const override {
    if (!microfacet::usable(wo)) return std::nullopt;
    const float s = wo.z > 0 ? 1.0f : -1.0f;
    const Vec3 wo_up = wo * s;
    const Vec3 m = microfacet::ggx_sample_visible_normal(wo_up, alpha_, u);
    if (!(dot(wo_up, m) > 0)) return std::nullopt;
    const Vec3 wi = microfacet::reflect(wo_up, m);
    if (!(wi.z > 0)) return std::nullopt;  // shadowed by the microsurface: no sample (pdf has no mass here)
    float p;
    const Rgb f = eval_pdf(wo, wi * s, &p);
    return lobe::make_sample(wo, wi * s, f, p);
  }

  float albedo(Vec3 wo) const override { return microfacet::usable(wo) ? table_.reflection(wo.z) : 0.0f; }

  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    proxy.add_reflection(weight * albedo(wo), alpha_);
  }

  std::string name() const override { return "conductor"; }

  bool filtered(const LobeFilter& filter, std::shared_ptr<const Lobe>* changed) const override {
    if (!filter.reflection) return false;
    if (filter.min_alpha > alpha_) {
      auto wide = std::make_shared<ConductorLobe>(*this);
      wide->alpha_ = filter.min_alpha;
      *changed = std::move(wide);
    }
    return true;
  }

 private:
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
    const microfacet::GgxReflection g = microfacet::ggx_reflection_terms<kValue, kPdf>(wo, wi, alpha_);
    Terms t;
    if (kValue && g.value > 0) t.f = fresnel(g.cos_h) * g.value;
    t.pdf = g.pdf;
    return t;
  }

  Rgb fresnel(float c) const {
    if (complex_)
      return {microfacet::fresnel_conductor(c, a_.r, b_.r), microfacet::fresnel_conductor(c, a_.g, b_.g),
              microfacet::fresnel_conductor(c, a_.b, b_.b)};
    return {microfacet::fresnel_schlick(c, a_.r), microfacet::fresnel_schlick(c, a_.g),
            microfacet::fresnel_schlick(c, a_.b)};
  }

  float alpha_;
  bool complex_;
  Rgb a_, b_;  ///< complex IOR (eta, k), or (f0, unused) for Schlick
  microfacet::AlbedoTable table_;
};

}  // namespace

std::shared_ptr<const Lobe> make_conductor(float alpha, Rgb eta, Rgb k) {
  return std::make_shared<ConductorLobe>(alpha, true, eta, k);
}

std::shared_ptr<const Lobe> make_conductor_reflectance(float alpha, Rgb f0) {
  return std::make_shared<ConductorLobe>(alpha, false, f0, Rgb{});
}

}  // namespace envpis::render
