// Lambertian diffuse reflection: f = R / pi in wo's hemisphere (two-sided: a surface seen from below
// reflects into the lower hemisphere), sampled with a cosine-weighted hemisphere.
#include "render/materials/lobe_common.h"

namespace envpis::render {
namespace {

class LambertLobe final : public Lobe {
 public:
  explicit LambertLobe(Rgb albedo) : r_(lobe::sanitize_color(albedo)) {}

  Rgb eval(Vec3 wo, Vec3 wi) const override {
    if (!microfacet::usable(wo) || !microfacet::usable(wi) || (wo.z > 0) != (wi.z > 0)) return {};
    return r_ * kInvPi;
  }

  float pdf(Vec3 wo, Vec3 wi) const override {
    if (!microfacet::usable(wo) || !microfacet::usable(wi) || (wo.z > 0) != (wi.z > 0)) return 0.0f;
    return lobe::cosine_hemisphere_pdf(std::abs(wi.z));
  }

  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float) const override {
    if (!microfacet::usable(wo)) return std::nullopt;
    Vec3 wi = lobe::sample_cosine_hemisphere(u);
    if (wo.z < 0) wi.z = -wi.z;
    return lobe::make_sample(wo, wi, eval(wo, wi), pdf(wo, wi));
  }

  float albedo(Vec3 wo) const override { return microfacet::usable(wo) ? r_.average() : 0.0f; }

  void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const override {
    proxy.add_diffuse(weight * albedo(wo));
  }

  std::string name() const override { return "lambert"; }

 private:
  Rgb r_;
};

}  // namespace

std::shared_ptr<const Lobe> make_lambert(Rgb albedo) { return std::make_shared<LambertLobe>(albedo); }

}  // namespace envpis::render
