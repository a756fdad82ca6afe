// SPDX-License-Identifier: Apache-2.0
// Diffuse lobes, f = C / pi: Lambertian reflection into wo's hemisphere (two-sided: a surface seen
// from below reflects into the lower hemisphere) or diffuse transmission into the opposite one. Both
// are sampled with a cosine-weighted hemisphere on their side, and both are symmetric in wo and wi,
// so reciprocal.
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

class DiffuseLobe final : public Lobe {
 public:
  DiffuseLobe(Rgb color, bool transmits) : c_(lobe::sanitize_color(color)), transmits_(transmits) {}

  Rgb eval(Vec3 wo, Vec3 wi) const override { return on_side(wo, wi) ? c_ * kInvPi : Rgb{}; }

  float pdf(Vec3 wo, Vec3 wi) const override {
    return on_side(wo, wi) ? lobe::cosine_hemisphere_pdf(std::abs(wi.z)) : 0.0f;
  }

  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float) const override {
    if (!microfacet::usable(wo)) return std::nullopt;
    Vec3 wi = lobe::sample_cosine_hemisphere(u);
    if ((wo.z < 0) != transmits_) wi.z = -wi.z;
    auto s = lobe::make_sample(wo, wi, eval(wo, wi), pdf(wo, wi));
    if (s) s->diffuse = true;
    return s;
  }

  float albedo(Vec3 wo) const override { return microfacet::usable(wo) ? c_.average() : 0.0f; }

  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    if (transmits_)
      proxy.add_translucent(weight * albedo(wo));
    else
      proxy.add_diffuse(weight * albedo(wo));
  }

  std::string name() const override { return transmits_ ? "translucent" : "lambert"; }

 private:
  // wi on the lobe's side of the surface: wo's for reflection, the other for transmission.
  bool on_side(Vec3 wo, Vec3 wi) const {
    return microfacet::usable(wo) && microfacet::usable(wi) && ((wo.z > 0) == (wi.z > 0)) != transmits_;
  }

  Rgb c_;
  bool transmits_;
};

}  // namespace

std::shared_ptr<const Lobe> make_lambert(Rgb albedo) { return std::make_shared<DiffuseLobe>(albedo, false); }

std::shared_ptr<const Lobe> make_translucent(Rgb transmittance) {
  return std::make_shared<DiffuseLobe>(transmittance, true);
}

}  // namespace envpis::render
