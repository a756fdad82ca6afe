// SPDX-License-Identifier: Apache-2.0
// Shared GGX microfacet and Fresnel helpers for the lobes in render/materials/.
//
// Everything works in the local shading frame (normal = +Z) on unit vectors. The GGX distribution is
// isotropic with roughness alpha (the GGX alpha itself, no squaring remap). Formulas:
//   D(m)       = alpha^2 / (pi (m_x^2 + m_y^2 + alpha^2 m_z^2)^2)          (m unit, m_z > 0)
//   Lambda(w)  = (sqrt(1 + alpha^2 tan^2 theta) - 1) / 2                    (Smith, GGX)
//   G1(w)      = 1 / (1 + Lambda(w)),   G2(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi))  (height-correlated)
//   D_wo(m)    = G1(wo) max(0, wo.m) D(m) / wo_z                           (distribution of visible normals)
// Visible normals are sampled with Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), 2018.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "envpis/common.h"

namespace envpis::render::microfacet {

/// Smallest alpha the lobes use: alpha 0 (a mirror) becomes a very sharp but finite GGX lobe, so eval,
/// pdf and sample stay consistent and nothing divides by zero.
constexpr float kMinAlpha = 1e-3f;

/// The alpha the lobes use: NaN/Inf -> 1, below kMinAlpha -> kMinAlpha.
inline float sanitize_alpha(float alpha) { return std::isfinite(alpha) ? std::max(alpha, kMinAlpha) : 1.0f; }

// ---- small vector helpers ----

/// True for a direction the lobes accept: finite and not on the tangent plane (wo.z == 0 is degenerate).
inline bool usable(Vec3 w) { return std::isfinite(w.x) && std::isfinite(w.y) && std::isfinite(w.z) && w.z != 0; }

/// wo mirrored about the microfacet normal m.
inline Vec3 reflect(Vec3 wo, Vec3 m) { return m * (2.0f * dot(wo, m)) - wo; }

/// Refracts wo (with dot(wo, m) > 0) through the microfacet normal m. eta = n_transmitted / n_incident.
/// Returns false under total internal reflection.
inline bool refract(Vec3 wo, Vec3 m, float eta, Vec3& wt) {
  const float cos_i = dot(wo, m);
  const float sin2_t = std::max(0.0f, 1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return false;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  wt = wo * (-1.0f / eta) + m * (cos_i / eta - cos_t);
  return true;
}

// ---- GGX ----

/// GGX normal distribution for a unit microfacet normal m (0 when m is below the surface).
inline float ggx_d(Vec3 m, float alpha) {
  if (!(m.z > 0)) return 0.0f;
  const float a2 = alpha * alpha;
  // 1 + (a^2 - 1) cos^2 = sin^2 + a^2 cos^2, written with m_x, m_y to avoid cancellation near the peak.
  const float s = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
  return a2 / (kPi * s * s);
}

/// Smith's Lambda for GGX; +Inf for grazing directions (w.z == 0).
inline float ggx_lambda(Vec3 w, float alpha) {
  const float s2 = w.x * w.x + w.y * w.y, z2 = w.z * w.z;
  if (s2 == 0) return 0.0f;
  const float t = alpha * alpha * s2 / z2;  // alpha^2 tan^2 theta
  if (!std::isfinite(t)) return std::numeric_limits<float>::infinity();
  return 0.5f * t / (1.0f + std::sqrt(1.0f + t));  // == (sqrt(1 + t) - 1) / 2 without cancellation
}

/// G1 and G2 from the Lambdas of wo and wi, for a caller that needs both (the fused evaluations).
inline float ggx_g1_of(float lambda_o) { return 1.0f / (1.0f + lambda_o); }
inline float ggx_g2_of(float lambda_o, float lambda_i) { return 1.0f / (1.0f + lambda_o + lambda_i); }

/// Smith masking G1 for GGX.
inline float ggx_g1(Vec3 w, float alpha) { return ggx_g1_of(ggx_lambda(w, alpha)); }

/// Height-correlated masking-shadowing G2 for GGX.
inline float ggx_g2(Vec3 wo, Vec3 wi, float alpha) { return ggx_g2_of(ggx_lambda(wo, alpha), ggx_lambda(wi, alpha)); }

/// D_wo(m) from its factors G1(wo), wo.m > 0, D(m) and wo_z > 0.
inline float ggx_visible_normal_density(float g1_o, float wo_m, float d, float wo_z) { return g1_o * wo_m * d / wo_z; }

/// Density of visible normals D_wo(m) (per solid angle of m); wo must be above the surface.
inline float ggx_visible_normal_pdf(Vec3 wo, Vec3 m, float alpha) {
  if (!(wo.z > 0)) return 0.0f;
  const float c = dot(wo, m);
  if (!(c > 0)) return 0.0f;
  return ggx_visible_normal_density(ggx_g1(wo, alpha), c, ggx_d(m, alpha), wo.z);
}

/// Samples a microfacet normal from D_wo (Heitz 2018): stretch wo to the unit-roughness
/// configuration, sample the projected hemisphere seen from it, unstretch. wo must be above the surface.
inline Vec3 ggx_sample_visible_normal(Vec3 wo, float alpha, Point2 u) {
  const Vec3 vh = normalize(Vec3(alpha * wo.x, alpha * wo.y, wo.z));
  const float len2 = vh.x * vh.x + vh.y * vh.y;
  const Vec3 t1 = len2 > 0 ? Vec3(-vh.y, vh.x, 0.0f) * (1.0f / std::sqrt(len2)) : Vec3(1.0f, 0.0f, 0.0f);
  const Vec3 t2 = cross(vh, t1);
  const float r = std::sqrt(u.x), phi = 2.0f * kPi * u.y;
  const float p1 = r * std::cos(phi);
  float p2 = r * std::sin(phi);
  const float s = 0.5f * (1.0f + vh.z);
  p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
  const Vec3 nh = t1 * p1 + t2 * p2 + vh * std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2));
  return normalize(Vec3(alpha * nh.x, alpha * nh.y, std::max(0.0f, nh.z)));
}

/// Half vector of a reflection pair (wo, wi both above the surface); false if it is undefined.
inline bool reflection_half_vector(Vec3 wo, Vec3 wi, Vec3& m) {
  const Vec3 h = wo + wi;
  const float l2 = dot(h, h);
  if (!(l2 > 1e-24f)) return false;
  m = h * (1.0f / std::sqrt(l2));
  return true;
}

/// GGX reflection without Fresnel for wo and wi above the surface: the value D(m) G2(wo, wi) /
/// (4 wo_z wi_z) and the density D_wo(m) / (4 wo.m) of wi = reflect(wo, m) with m ~ D_wo, and
/// cos_h = wo.m (the cosine for the Fresnel term). Value and density are 0 for any other configuration.
struct GgxReflection {
  float value = 0, pdf = 0, cos_h = 0;
};

/// The terms kValue and kPdf ask for, sharing the half vector, D(m) and Lambda(wo) between them.
template <bool kValue, bool kPdf>
inline GgxReflection ggx_reflection_terms(Vec3 wo, Vec3 wi, float alpha) {
  GgxReflection r;
  Vec3 m;
  if (!(wo.z > 0) || !(wi.z > 0) || !reflection_half_vector(wo, wi, m)) return r;
  r.cos_h = dot(wo, m);
  if (!(r.cos_h > 0)) return r;
  const float d = ggx_d(m, alpha), lambda_o = ggx_lambda(wo, alpha);
  if constexpr (kValue) r.value = d * ggx_g2_of(lambda_o, ggx_lambda(wi, alpha)) / (4.0f * wo.z * wi.z);
  if constexpr (kPdf) r.pdf = ggx_visible_normal_density(ggx_g1_of(lambda_o), r.cos_h, d, wo.z) / (4.0f * r.cos_h);
  return r;
}

/// The value alone; cos_h receives wo.m.
inline float ggx_reflection(Vec3 wo, Vec3 wi, float alpha, float& cos_h) {
  const GgxReflection r = ggx_reflection_terms<true, false>(wo, wi, alpha);
  cos_h = r.cos_h;
  return r.value;
}

/// The density alone.
inline float ggx_reflection_pdf(Vec3 wo, Vec3 wi, float alpha) { return ggx_reflection_terms<false, true>(wo, wi, alpha).pdf; }

// ---- Fresnel ----

/// Unpolarized Fresnel reflectance of a smooth dielectric interface. cos_i is the cosine between the
/// incident direction and the normal, eta = n_other_side / n_normal_side. A negative cos_i means the
/// incident direction is on the other side: eta is inverted. Total internal reflection gives 1.
inline float fresnel_dielectric(float cos_i, float eta) {
  cos_i = std::clamp(cos_i, -1.0f, 1.0f);
  if (cos_i < 0) {
    eta = 1.0f / eta;
    cos_i = -cos_i;
  }
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  const float cos_t = std::sqrt(std::max(0.0f, 1.0f - sin2_t));
  const float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  return 0.5f * (r_par * r_par + r_perp * r_perp);
}

/// fresnel_dielectric for a refraction pair whose two cosines are both known (cos_i, cos_t > 0 with
/// eta = n_t / n_i and Snell's law holding between them). Needs no square root, so it stays accurate
/// near the critical angle, and it is exactly symmetric in the two sides: swapping (cos_i, cos_t) and
/// inverting eta gives the same value, which keeps the BTDF reciprocal in floating point.
inline float fresnel_dielectric_pair(float cos_i, float cos_t, float eta) {
  const float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const float f = 0.5f * (r_par * r_par + r_perp * r_perp);
  return std::isfinite(f) ? std::clamp(f, 0.0f, 1.0f) : 1.0f;
}

/// Exact Fresnel reflectance of a conductor with complex relative IOR eta + i k (unpolarized), for
/// 0 <= cos_i <= 1. Real-arithmetic form of the complex Fresnel equations: with
/// a^2 + b^2 = sqrt((eta^2 - k^2 - sin^2)^2 + 4 eta^2 k^2) and a^2 = (a^2 + b^2 + eta^2 - k^2 - sin^2) / 2,
///   R_s = (a^2 + b^2 - 2 a cos + cos^2) / (a^2 + b^2 + 2 a cos + cos^2)
///   R_p = R_s (cos^2 (a^2 + b^2) - 2 a cos sin^2 + sin^4) / (cos^2 (a^2 + b^2) + 2 a cos sin^2 + sin^4)
/// (tests/render/test_materials.cpp checks it against std::complex arithmetic).
inline float fresnel_conductor(float cos_i, float eta, float k) {
  cos_i = std::clamp(cos_i, 0.0f, 1.0f);
  if (cos_i == 0.0f) return 1.0f;  // grazing: a perfect mirror whatever the IOR
  const float c2 = cos_i * cos_i, s2 = 1.0f - c2;
  const float t0 = eta * eta - k * k - s2;
  const float ab2 = std::sqrt(t0 * t0 + 4.0f * eta * eta * k * k);
  const float a = std::sqrt(std::max(0.0f, 0.5f * (ab2 + t0)));
  const float rs = (ab2 - 2.0f * a * cos_i + c2) / (ab2 + 2.0f * a * cos_i + c2);
  const float p_num = c2 * ab2 - 2.0f * a * cos_i * s2 + s2 * s2;
  const float p_den = c2 * ab2 + 2.0f * a * cos_i * s2 + s2 * s2;
  const float f = p_den > 0 ? 0.5f * (rs + rs * p_num / p_den) : rs;
  return std::isfinite(f) ? std::clamp(f, 0.0f, 1.0f) : 1.0f;
}

/// Schlick's approximation from the reflectance at normal incidence.
inline float fresnel_schlick(float cos_i, float f0) {
  const float m = std::clamp(1.0f - cos_i, 0.0f, 1.0f), m2 = m * m;
  return f0 + (1.0f - f0) * m2 * m2 * m;
}

// ---- directional albedo tables ----

/// Directional albedo of a GGX interface as a function of mu = |cos theta_o|, tabulated once per lobe
/// by deterministic quadrature over visible normals: for each mu, the mean over a stratified grid of
/// normals m ~ D_wo of F(wo.m) G2/G1(wo) for the reflected direction (when it is above the surface)
/// and of (1 - F) G2/G1(wo) for the refracted one (when it is below). This is the single-scattering
/// energy of the lobe, i.e. the integral of f |cos theta_i| over wi, which is what the lobes report
/// as albedo() and give the proxy.
class AlbedoTable {
 public:
  static constexpr int kSize = 32;  ///< nodes at mu = k / (kSize - 1)
#ifndef ENVPIS_ALBEDO_TABLE_GRID
#define ENVPIS_ALBEDO_TABLE_GRID 32
#endif
  /// kGrid x kGrid normals per node (fuzz/CMakeLists.txt lowers it: there the cost matters, not the accuracy)
  static constexpr int kGrid = ENVPIS_ALBEDO_TABLE_GRID;

  AlbedoTable() = default;

  /// fresnel(c) is the reflectance for wo.m = c > 0; eta (n_below / n_above) > 0 enables the refracted
  /// branch, eta <= 0 tabulates a reflector.
  template <class Fresnel>
  static AlbedoTable build(float alpha, Fresnel fresnel, float eta) {
    AlbedoTable t;
    for (int k = 0; k < kSize; ++k) {
      const float mu = std::max(float(k) / (kSize - 1), 1e-3f);
      const Vec3 wo(std::sqrt(std::max(0.0f, 1.0f - mu * mu)), 0.0f, mu);
      const float lo = ggx_lambda(wo, alpha);
      double r = 0, tr = 0;
      for (int j = 0; j < kGrid; ++j)
        for (int i = 0; i < kGrid; ++i) {
          const Point2 u{(i + 0.5f) / kGrid, (j + 0.5f) / kGrid};
          const Vec3 m = ggx_sample_visible_normal(wo, alpha, u);
          const float c = dot(wo, m);
          if (!(c > 0)) continue;
          const float f = std::clamp(fresnel(c), 0.0f, 1.0f);
          const Vec3 wr = reflect(wo, m);
          if (wr.z > 0) r += f * (1.0f + lo) / (1.0f + lo + ggx_lambda(wr, alpha));
          Vec3 wt;
          if (eta > 0 && f < 1.0f && refract(wo, m, eta, wt) && wt.z < 0)
            tr += (1.0f - f) * (1.0f + lo) / (1.0f + lo + ggx_lambda(wt, alpha));
        }
      t.r_[k] = float(r / (kGrid * kGrid));
      t.t_[k] = float(tr / (kGrid * kGrid));
    }
    // 2 * integral of mu E_r(mu) over [0, 1] for the piecewise-linear interpolant (Simpson is exact
    // on each segment: the integrand is quadratic there).
    double avg = 0;
    const double h = 1.0 / (kSize - 1);
    for (int k = 0; k + 1 < kSize; ++k) {
      const double a = k * h, b = a + h, m = 0.5 * (a + b);
      const double ea = t.r_[k], eb = t.r_[k + 1], em = 0.5 * (ea + eb);
      avg += h / 6.0 * (ea * a + 4.0 * em * m + eb * b);
    }
    t.avg_r_ = float(2.0 * avg);
    return t;
  }

  /// Reflected energy for |cos theta_o| = mu.
  float reflection(float mu) const { return lookup(r_, mu); }
  /// Transmitted energy (0 for a reflector).
  float transmission(float mu) const { return lookup(t_, mu); }
  /// Cosine-weighted hemispherical average 2 * int_0^1 E_r(mu) mu dmu of the reflected energy.
  float average_reflection() const { return avg_r_; }

 private:
  static float lookup(const std::array<float, kSize>& v, float mu) {
    const float a = std::abs(mu);
    const float x = (a <= 1.0f ? a : (a > 1.0f ? 1.0f : 0.0f)) * (kSize - 1);  // NaN -> 0
    const int i = std::min(int(x), kSize - 2);
    const float f = x - float(i);
    return v[i] + (v[i + 1] - v[i]) * f;
  }
  std::array<float, kSize> r_{}, t_{};
  float avg_r_ = 0;
};

}  // namespace envpis::render::microfacet
