// SPDX-License-Identifier: Apache-2.0
// The renderer's materials: weighted sums of lobes, each with eval / sample / pdf, evaluated in the
// local shading frame (normal = +Z), plus accumulation into the library's BsdfProxy.
//
// Conventions (pbrt-like): wo and wi point away from the surface; eval() returns the BSDF value f
// (NOT multiplied by |cos theta_i|); pdf() is per unit solid angle of wi; sample() returns f, wi, pdf
// and weight = f * |cos theta_i| / pdf. Directions are unit vectors in the local frame.
//
// Further conventions of the lobes in render/materials/:
//   - Degenerate input (wo.z == 0, wi.z == 0, zero or non-finite vectors) gives eval 0, pdf 0 and no
//     sample; nothing returns NaN or Inf.
//   - "alpha" is the GGX roughness itself (no squaring remap). Below 1e-3 it is clamped to 1e-3: a
//     near-mirror lobe, never a delta, so eval, pdf and sample always agree.
//   - The reflecting lobes (Lambert, conductor, coated diffuse) are two-sided: seen from below, they
//     reflect into the lower hemisphere. The translucent and dielectric lobes transmit across.
//   - The dielectric's refraction term is the flux-conserving form (no 1/eta^2 radiance scaling): its
//     albedo is <= 1 from both sides; for paths that enter and leave closed objects the factor
//     cancels (see render/materials/dielectric.cpp).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "envpis/envpis.h"

namespace envpis::render {

struct BsdfSample {
  Rgb f;          ///< BSDF value
  Vec3 wi;        ///< sampled incoming direction (local frame)
  float pdf = 0;  ///< solid-angle density of the whole material's sampling of wi
  Rgb weight;     ///< f * |cos theta_i| / pdf
  bool transmission = false;
  /// Drawn from a diffuse component (Lambert, translucent, a coat's base): Cycles' LABEL_DIFFUSE,
  /// which its caustics switches test (render/regularization.h).
  bool diffuse = false;
};

/// What path regularization (render/regularization.h) leaves of a lobe at one vertex: GGX roughness
/// raised to at least min_alpha (Cycles' Filter Glossy), and whether glossy reflection and glossy
/// refraction stay (Cycles' reflective and refractive caustics switches). Diffuse parts always stay.
struct LobeFilter {
  float min_alpha = 0;
  bool reflection = true;
  bool refraction = true;
};

/// One lobe. Implementations live in render/materials/, one file per lobe.
class Lobe {
 public:
  virtual ~Lobe() = default;
  virtual Rgb eval(Vec3 wo, Vec3 wi) const = 0;
  virtual float pdf(Vec3 wo, Vec3 wi) const = 0;
  /// eval() and pdf() together, the same values (*pdf receives pdf()): a lobe whose two share work
  /// (a half vector, D, Lambda) overrides it; the oracle and the analyzer need both per direction.
  virtual Rgb eval_pdf(Vec3 wo, Vec3 wi, float* pdf) const {
    *pdf = this->pdf(wo, wi);
    return eval(wo, wi);
  }
  /// u: 2D sample, uc: a further 1D sample (e.g. reflect vs refract). nullopt when sampling fails.
  virtual std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float uc) const = 0;
  /// Directional albedo estimate used to pick this lobe in a mixture and as its proxy weight.
  virtual float albedo(Vec3 wo) const = 0;
  /// Adds this lobe (scaled by `weight`) to the proxy as the paper describes.
  virtual void add_to_proxy(BsdfProxy& proxy, Vec3 wo, float weight) const = 0;
  virtual std::string name() const = 0;
  /// The lobe under `filter`: false when nothing of it is left; otherwise *changed receives a new
  /// lobe when the filter changes it and stays null when it does not (a diffuse lobe never changes).
  /// A changed lobe keeps the original's albedo tables, which only weigh the lobe choice and the proxy
  /// (and a coat's base), so eval, pdf, sample and the proxy still all describe the same lobe.
  virtual bool filtered(const LobeFilter& filter, std::shared_ptr<const Lobe>* changed) const {
    (void)filter;
    (void)changed;
    return true;
  }
};

/// A material: sum of weighted lobes. eval sums the lobes; sample picks a lobe with probability
/// proportional to weight * albedo(wo) and returns the mixture pdf (one-sample MIS over lobes).
/// A weight may be a colour (a texture's tint of a lobe shared by many shading points); the lobe
/// choice and the proxy then use its channel average.
class Material {
 public:
  void add(std::shared_ptr<const Lobe> lobe, float weight = 1.0f);
  void add(std::shared_ptr<const Lobe> lobe, Rgb weight);
  /// Removes every lobe, keeping the storage (a per-thread material rebuilt at each shading point).
  void clear_lobes() { lobes_.clear(); }
  Rgb eval(Vec3 wo, Vec3 wi) const;
  float pdf(Vec3 wo, Vec3 wi) const;
  /// eval() and pdf() together, the same values (*pdf receives pdf()), through Lobe::eval_pdf.
  Rgb eval_pdf(Vec3 wo, Vec3 wi, float* pdf) const;
  /// The lobe choice at outgoing direction wo (each lobe's probability), which eval_pdf() computes at
  /// every call: for a caller that evaluates many directions at one wo (the analyzer's quadrature).
  class Choice {
    friend class Material;
    const Material* material_ = nullptr;  // the material and wo it was made for
    Vec3 wo_;
    std::vector<float> probability_;
    bool usable_ = false;  // wo is a direction the lobes can take
  };
  Choice choice(Vec3 wo) const;
  /// eval_pdf() with the lobe choice given; the same values (a choice made by another material or at
  /// another wo is not used).
  Rgb eval_pdf(Vec3 wo, Vec3 wi, float* pdf, const Choice& choice) const;
  std::optional<BsdfSample> sample(Vec3 wo, Point2 u, float uc) const;
  /// Fills the proxy for outgoing direction wo (local frame). The caller calls
  /// ProductSampler::prepare(normal, wo_world, proxy) with the same normal the frame uses.
  /// With closed_surface() set, the lobes on the inside (local z < 0) are left out (see below).
  void fill_proxy(BsdfProxy& proxy, Vec3 wo) const;
  /// Declares that every surface with this material is closed and its local +Z (the outward normal
  /// of a one-sided, transmissive material) points out of the volume it bounds. A light sample, i.e. a
  /// shadow ray towards the environment, that leaves such a surface towards its inside (wi.z < 0)
  /// must cross the surface again and is always blocked; so fill_proxy omits the proxy lobes that
  /// point inside: refraction and translucency when wo is outside (wo.z > 0), reflection and diffuse
  /// when wo is inside. The light-sampling distribution then puts no samples where the integrand is
  /// 0 by visibility; eval / pdf / sample are unchanged, and BSDF sampling still covers every
  /// direction, so the estimate stays unbiased whatever this flag says. Scene::commit() sets it for
  /// transmissive materials used only by spheres and closed, outward-oriented meshes (render/scene.h);
  /// docs/proxy.md has the measurements. Meaningless for two-sided (opaque) materials, whose frame is
  /// flipped towards the viewer (they have no lobe below the surface anyway).
  void set_closed_surface(bool closed) { closed_surface_ = closed; }
  bool closed_surface() const { return closed_surface_; }
  /// Refills `out` with this material's lobes under `filter` (Lobe::filtered), same weights, same
  /// closed-surface flag (no allocation for unchanged lobes once out's storage has grown).
  void filter_into(const LobeFilter& filter, Material* out) const;
  /// Sum of weight * albedo(wo) over the lobes (the material's estimated directional albedo).
  float albedo(Vec3 wo) const;
  std::size_t lobe_count() const { return lobes_.size(); }
  const std::string& name() const { return name_; }
  void set_name(std::string n) { name_ = std::move(n); }
  bool empty() const { return lobes_.empty(); }

 private:
  struct Entry {
    std::shared_ptr<const Lobe> lobe;
    Rgb weight;
    float weight_average;  ///< for the lobe choice and the proxy
  };
  template <class Probability>
  Rgb eval_pdf_lobes(Vec3 wo, Vec3 wi, float* pdf, Probability probability) const;
  std::vector<Entry> lobes_;
  std::string name_;
  bool closed_surface_ = false;
};

// ---- factories (render/materials/*.cpp) ----
std::shared_ptr<const Lobe> make_lambert(Rgb albedo);
std::shared_ptr<const Lobe> make_translucent(Rgb transmittance);
/// GGX conductor, Fresnel from a complex IOR (eta + i k per channel)...
std::shared_ptr<const Lobe> make_conductor(float alpha, Rgb eta, Rgb k);
/// ...or from an RGB reflectance at normal incidence (Schlick).
std::shared_ptr<const Lobe> make_conductor_reflectance(float alpha, Rgb f0);
/// GGX rough dielectric (Walter et al. 2007): reflection + refraction. eta = n_inside / n_outside;
/// the normal points outside.
std::shared_ptr<const Lobe> make_dielectric(float alpha, float eta, Rgb tint = {1, 1, 1});
/// Dielectric coat (GGX, alpha, eta) over a Lambert base.
std::shared_ptr<const Lobe> make_coated_diffuse(Rgb base, float alpha, float eta);

}  // namespace envpis::render
