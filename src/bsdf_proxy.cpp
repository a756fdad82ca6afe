// SPDX-License-Identifier: Apache-2.0
#include "envpis/bsdf_proxy.h"

#include <algorithm>
#include <cmath>

#define ENVPIS_KERNEL_NS scalar
#include "proxy_lobe_impl.h"
#include "proxy_internal.h"

namespace envpis {

namespace {
bool positive(float w) { return w > 0 && std::isfinite(w); }
float sanitize_alpha(float a) { return std::isfinite(a) ? std::clamp(a, 0.0f, 1.0f) : 1.0f; }

#include "proxy_roughness_fit.inc"

// Where x falls in the increasing grid g[0..n): index i of the cell [g[i], g[i+1]] and the fraction.
void grid_cell(const float* g, int n, float x, int& i, float& f) {
  x = std::clamp(x, g[0], g[n - 1]);
  i = std::clamp(static_cast<int>(std::upper_bound(g, g + n, x) - g) - 1, 0, n - 2);
  f = (x - g[i]) / (g[i + 1] - g[i]);
}

// The fitted a' (scripts/fit-proxy-roughness.py), bilinear in alpha and cos_o; below the grid's
// smallest alpha, a' scales with alpha (the lobe's shape no longer changes, only its width).
float fitted_alpha(float alpha, float cos_o) {
  int i, j;
  float fa, fc;
  grid_cell(kFitAlphas, kFitAlphaCount, alpha, i, fa);
  grid_cell(kFitCosO, kFitCosOCount, cos_o, j, fc);
  const auto row = [&](int r) { return kFitAlphaPrime[r][j] + fc * (kFitAlphaPrime[r][j + 1] - kFitAlphaPrime[r][j]); };
  const float a = row(i) + fa * (row(i + 1) - row(i));
  return alpha < kFitAlphas[0] ? a * alpha / kFitAlphas[0] : a;
}
}  // namespace

RoughnessTransform parse_roughness_transform(const std::string& s) {
  if (s == "slides") return RoughnessTransform::Slides;
  if (s == "abstract") return RoughnessTransform::Abstract;
  if (s == "hybrid") return RoughnessTransform::Hybrid;
  if (s == "fitted") return RoughnessTransform::Fitted;
  throw Error("unknown roughness transform '" + s + "' (expected slides, abstract, hybrid or fitted)");
}

const char* to_string(RoughnessTransform t) {
  switch (t) {
    case RoughnessTransform::Slides: return "slides";
    case RoughnessTransform::Abstract: return "abstract";
    case RoughnessTransform::Hybrid: return "hybrid";
    case RoughnessTransform::Fitted: return "fitted";
  }
  return "?";
}

ReflectionLobe parse_reflection_lobe(const std::string& s) {
  if (s == "mirror") return ReflectionLobe::Mirror;
  if (s == "half-vector") return ReflectionLobe::HalfVector;
  throw Error("unknown reflection lobe '" + s + "' (expected mirror or half-vector)");
}

const char* to_string(ReflectionLobe l) { return l == ReflectionLobe::HalfVector ? "half-vector" : "mirror"; }

void BsdfProxy::add_diffuse(float w) {
  if (positive(w)) diffuse += w;
}

void BsdfProxy::add_translucent(float w) {
  if (positive(w)) translucent += w;
}

void BsdfProxy::add_reflection(float w, float alpha) {
  if (!positive(w)) return;
  alpha_reflection = (alpha_reflection * reflection + sanitize_alpha(alpha) * w) / (reflection + w);
  reflection += w;
}

void BsdfProxy::add_refraction(float w, float alpha, float eta) {
  if (!positive(w)) return;
  if (!(eta > 0) || !std::isfinite(eta)) eta = 1.0f;
  const float total = refraction + w;
  alpha_refraction = (alpha_refraction * refraction + sanitize_alpha(alpha) * w) / total;
  ior = refraction > 0 ? (ior * refraction + eta * w) / total : eta;
  refraction = total;
}

float widen_roughness(float alpha, float cos_divergence) {
  if (!(cos_divergence > 0)) return 1.0f;
  const float c2 = std::min(cos_divergence * cos_divergence, 1.0f);
  const float tan2 = (1.0f - c2) / c2;
  return std::min(1.0f, std::sqrt(tan2 / 8.0f + alpha * alpha));
}

namespace {
// Below this refraction roughness, total internal reflection folds the refraction weight into the
// reflection lobe; at or above it the refraction lobe stays, grazing (see prepare_proxy).
constexpr float kTirFoldAlpha = 0.05f;
}  // namespace

PreparedProxy prepare_proxy(const BsdfProxy& proxy, Vec3 n, Vec3 wo, const ProxyOptions& options) {
  PreparedProxy p;
  if (!is_valid_direction(n) || !is_valid_direction(wo) || proxy.is_zero()) return p;
  n = normalize(n);
  wo = normalize(wo);
  float eta = (proxy.ior > 0 && std::isfinite(proxy.ior)) ? proxy.ior : 1.0f;
  float cos_o = dot(n, wo);
  if (cos_o < 0) {  // seen from below: describe the BSDF from wo's side
    n = -n;
    cos_o = -cos_o;
    eta = 1.0f / eta;
  }
  cos_o = std::min(cos_o, 1.0f);
  p.n = n;
  p.eta = eta;
  p.r = normalize(n * (2.0f * cos_o) - wo);

  float wd = positive(proxy.diffuse) ? proxy.diffuse : 0.0f;
  float wt_diffuse = positive(proxy.translucent) ? proxy.translucent : 0.0f;
  float wr = positive(proxy.reflection) ? proxy.reflection : 0.0f;
  float wt = positive(proxy.refraction) ? proxy.refraction : 0.0f;
  float ar = sanitize_alpha(proxy.alpha_reflection), at = sanitize_alpha(proxy.alpha_refraction);

  // Refracted direction T (Snell, eta = n_other / n_wo_side).
  const float sin2_t = (1.0f - cos_o * cos_o) / (eta * eta);
  float cos_t = 0;
  if (sin2_t >= 1.0f) {
    p.tir = wt > 0;
    const Vec3 tangent = wo - n * cos_o;  // non-zero (sin_o > eta) but for rounding with a tiny eta
    if (wt > 0 && at >= kTirFoldAlpha && dot(tangent, tangent) > 1e-20f) {
      // A rough interface still transmits (microfacets tilted towards wo), into directions near the
      // horizon: the refracted direction's limit at the critical angle, grazing, away from wo. cos_t
      // = 0 takes a_t' to the cap below. Folding this weight into the reflection lobe put the
      // product's samples where a closed object blocks them and left the transmitted light to BSDF
      // sampling (docs/proxy.md, "Total internal reflection").
      p.t = normalize(tangent) * -1.0f;
    } else {
      // A (nearly) smooth one reflects everything beyond the critical angle. (T stays finite for the
      // translucent lobe's gate even when there is no refraction weight.)
      if (wt > 0) {
        ar = (ar * wr + at * wt) / (wr + wt);
        wr += wt;
        wt = 0;
      }
      p.t = -n;
    }
  } else {
    cos_t = std::sqrt(1.0f - sin2_t);
    p.t = normalize(wo * (-1.0f / eta) + n * (cos_o / eta - cos_t));
  }

  // Roughness transform (half-vector -> incoming direction).
  const bool slides_r = options.transform != RoughnessTransform::Abstract;
  // Hybrid: for refraction the abstract's a_t' when entering a denser medium (eta > 1), the slides'
  // when leaving one (eta < 1, e.g. inside glass), each where it covered the true lobe better
  // (tests/test_bsdf_proxy.cpp, ProxyLobesCoverTheTrueGgxLobes; docs/proxy.md).
  const bool slides_t = options.transform == RoughnessTransform::Slides ||
                        (options.transform != RoughnessTransform::Abstract && eta < 1.0f);
  const float ar_t = options.transform == RoughnessTransform::Fitted ? fitted_alpha(ar, cos_o)
                     : slides_r                                      ? 2.0f * ar
                                                                     : ar * std::sqrt(4.0f * cos_o);
  float at_t = 1.0f;
  if (wt > 0)
    at_t = slides_t ? at * (cos_t + eta * cos_o) / std::max(cos_t, 1e-4f)
                    : at * (cos_t * eta + cos_o) / std::sqrt(std::max(cos_t * eta * eta, 1e-8f));
  const float floor = std::max(options.min_alpha, 1e-3f);
  float cap = options.max_alpha;
  if (!(cap <= 1.0f)) cap = 1.0f;  // NaN or above 1
  cap = std::max(cap, floor);      // a cap below the floor gives way to the floor
  p.half_vector = options.reflection_lobe == ReflectionLobe::HalfVector;
  p.alpha_r = p.half_vector ? std::min(std::sqrt(ar * ar + 0.25f * floor * floor), cap) : std::clamp(ar_t, floor, cap);
  p.alpha_t = std::clamp(at_t, floor, cap);
  p.kd = wd * kInvPi;
  p.kt = wt_diffuse * kInvPi;
  p.wr = wr;
  p.wt = wt;
  p.ok = true;
  return p;
}

float PreparedProxy::eval_cone(Vec3 axis, float cos_half_angle, float sin_half_angle) const {
  if (!ok) return 0.0f;
  const detail::scalar::LobeV<float> l(detail::to_lobe_params(*this));
  return detail::scalar::proxy_cone_value<float>(l, axis.x, axis.y, axis.z, cos_half_angle, sin_half_angle);
}

float PreparedProxy::eval(Vec3 wi) const { return eval_cone(wi, 1.0f, 0.0f); }

}  // namespace envpis
