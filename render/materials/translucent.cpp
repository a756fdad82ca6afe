// Diffuse transmission: f = T / pi for wi on the side opposite to wo, sampled with a cosine-weighted
// hemisphere mirrored into that side. Symmetric in wo and wi, so it is reciprocal.
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

class TranslucentLobe final : public Lobe {
 public:
  explicit TranslucentLobe(Rgb transmittance) : t_(lobe::sanitize_color(transmittance)) {}

  Rgb eval(Vec3 wo, Vec3 wi) const override {
    if (!microfacet::usable(wo) || !microfacet::usable(wi) || (wo.z > 0) == (wi.z > 0)) return {};
    return t_ * kInvPi;
  }

  float pdf(Vec3 wo, Vec3 wi) const override {
    if (!microfacet::usable(wo) || !microfacet::usable(wi) || (wo.z > 0) == (wi.z > 0)) return 0.0f;
    return lobe::cosine_hemisphere_pdf(std::abs(wi.z));
  }

  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float) const override {
    if (!microfacet::usable(wo)) return std::nullopt;
    Vec3 wi = lobe::sample_cosine_hemisphere(u);
    if (wo.z > 0) wi.z = -wi.z;
    return lobe::make_sample(wo, wi, eval(wo, wi), pdf(wo, wi));
  }

  float albedo(Vec3 wo) const override { return microfacet::usable(wo) ? t_.average() : 0.0f; }

  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    proxy.add_translucent(weight * albedo(wo));
  }

  std::string name() const override { return "translucent"; }

 private:
  Rgb t_;
};

}  // namespace

std::shared_ptr<const Lobe> make_translucent(Rgb transmittance) {
  return std::make_shared<TranslucentLobe>(transmittance);
}

}  // namespace envpis::render
