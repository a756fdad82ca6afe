// SPDX-License-Identifier: Apache-2.0
// The BSDF proxy of Conty Estevez & Lecocq (2018), section 3: seven floats that summarize a
// multi-lobe BSDF for shaping the light-sampling distribution (never for shading).
//
// Almost every lobe of a production BSDF revolves around one of four axes, all implied by the
// shading normal N and the outgoing direction wo: N (diffuse), -N (translucent), the mirror direction
// R (glossy reflection) and the refracted direction T (glossy transmission). The proxy keeps a weight
// per axis, the weight-averaged GGX roughness of the reflection and refraction lobes, and the IOR.
//
// "Roughness" here is the GGX alpha (no squaring remap): alpha = 0 is a mirror, alpha = 1 very rough.
//
// Lobe shapes, evaluated at an incoming direction wi whose angle to the lobe axis is t:
//   diffuse      w_d / pi * max(0, cos t)         around  N      (only for wi above the surface)
//   translucent  w_t / pi * max(0, cos t)         around -N      (only for wi below the surface)
//   reflection   w_r * D(cos t, a_r')             around  R      (only for wi above the surface)
//   refraction   w_T * D(cos t, a_t')             around  T      (only for wi below the surface)
// with the simplified GGX D(c, a) = a^2 / (pi (1 + (a^2 - 1) c^2)^2) for c > 0 (0 otherwise), which is
// the paper's w / (a^2 (cos^2 t + sin^2 t / a^2)^2) with the 1/pi that makes its peak 1/(pi a^2) match
// GGX's and keeps its scale consistent with the diffuse 1/pi.
//
// The roughnesses are transformed once per shading point (the half-vector to incoming-direction
// change of variables widens the lobe). The talk's abstract and the authors' slides differ:
//   Slides:             a_r' = 2 a_r,               a_t' = a_t (cos_t + eta cos_o) / cos_t
//   Abstract:           a_r' = a_r sqrt(4 cos_o),   a_t' = a_t (cos_t eta + cos_o) / sqrt(cos_t eta^2)
//   Hybrid (default):   the slides' a_r'; the abstract's a_t' for eta > 1, the slides' for eta < 1
//   Fitted:             a_r' from a table over (a_r, cos_o) fitted offline to the true GGX lobe x cos
//                       (scripts/fit-proxy-roughness.py, src/proxy_roughness_fit.inc); a_t' as Hybrid
// where cos_o = |N.wo|, cos_t = |N.T| and eta is the IOR seen from wo's side. The default is what
// covers the true GGX lobes best (tests/test_bsdf_proxy.cpp, ProxyLobesCoverTheTrueGgxLobes;
// measurements in docs/proxy.md): the abstract's a_r' is too narrow at grazing views, and for
// refraction each transform is too wide on one side of eta = 1 and too narrow on the other. Then a' is
// clamped to [min_alpha, max_alpha]: the floor is a low-roughness remedy (a near-mirror lobe gives its
// peak value to every cell its axis touches and starves the cells reached only by its tail;
// docs/decisions.md, "The roughness floor"); the cap keeps rough lobes peaked: at a' = 1 the GGX-like
// shape is flat (and above 1 it would peak at the horizon), so with the slides' 2a every a >= 0.5
// would become a flat proxy that no longer favours the lobe's side of the sky (docs/proxy.md,
// "Roughness cap").
//
// Special cases (all handled inside prepare_proxy):
//   - wo below the surface (N.wo < 0): N is flipped and eta inverted, so the proxy describes the
//     BSDF seen from wo's side.
//   - total internal reflection of the macro-surface (no refracted direction): for a (nearly) smooth
//     refraction lobe (alpha < 0.05) its weight and roughness are folded into the reflection lobe,
//     where the energy goes; a rough one keeps its weight (a rough interface still transmits, through
//     microfacets tilted towards wo) on the grazing exit direction away from wo, the refracted
//     direction's limit at the critical angle, with a' at the cap (docs/proxy.md, "Total internal
//     reflection").
//   - roughness 0: allowed; the floor (or a minimum of 1e-3 when the floor is 0) keeps the lobe finite.
//   - IOR: any positive value; IOR 1 refracts straight through (T = -wo); below 1 is a valid ratio
//     (e.g. leaving glass); NaN, 0 or negative is treated as 1.
//   - an all-zero proxy, or a zero/NaN normal or wo: prepare_proxy returns a proxy with valid() false.
//   - shading normals that diverge from the proxy's normal: widen the lobe's roughness with
//     widen_roughness() before adding it.
#pragma once

#include "envpis/common.h"

namespace envpis {

enum class RoughnessTransform { Slides, Abstract, Hybrid, Fitted };
RoughnessTransform parse_roughness_transform(const std::string& s);  ///< "slides" | "abstract" | "hybrid" | "fitted"
const char* to_string(RoughnessTransform t);

/// The reflection lobe's shape. Mirror: the paper's, a GGX-like lobe in c = R.wi around the mirror
/// direction R, at the transformed roughness a' (`transform`). HalfVector: the GGX distribution of the
/// half-vector h = normalize(wo + wi), D(N.h) / (4 N.wo), the true lobe's shape but for Fresnel and
/// shadowing, so no transform: its roughness is the BSDF's, widened in quadrature by half the floor,
/// sqrt(a^2 + (min_alpha / 2)^2) (a lobe in h is half as wide in wi as the mirror lobe of the same
/// roughness), and capped at max_alpha. docs/proxy.md, "The half-vector lobe".
enum class ReflectionLobe { Mirror, HalfVector };
ReflectionLobe parse_reflection_lobe(const std::string& s);  ///< "mirror" | "half-vector"
const char* to_string(ReflectionLobe l);

struct ProxyOptions {
  RoughnessTransform transform = RoughnessTransform::Hybrid;
  float min_alpha = 0.35f;  ///< floor on the transformed roughness a' (0 disables)
  float max_alpha = 0.8f;   ///< cap on the transformed roughness a', in [min_alpha, 1] (1 disables)
  ReflectionLobe reflection_lobe = ReflectionLobe::Mirror;
};

/// The seven floats. Accumulate lobes with the add_* calls (weights are the lobes' albedos or any
/// consistent measure of their energy; roughness and IOR become weight-averaged). Leave out lobes
/// whose directions a light sample can never use: e.g. on a closed object the lobes pointing inside
/// it, where the object itself blocks every shadow ray (docs/proxy.md, "Closed surfaces").
struct BsdfProxy {
  float diffuse = 0;
  float translucent = 0;
  float reflection = 0;
  float refraction = 0;
  float alpha_reflection = 0;
  float alpha_refraction = 0;
  float ior = 1;

  void add_diffuse(float weight);
  void add_translucent(float weight);
  void add_reflection(float weight, float alpha);
  void add_refraction(float weight, float alpha, float ior);
  bool is_zero() const { return !(diffuse > 0 || translucent > 0 || reflection > 0 || refraction > 0); }
};

/// Roughness widened for a lobe whose own normal makes angle t_d (cos t_d = cos_divergence) with the
/// proxy's normal: sqrt(tan^2(t_d) / 8 + alpha^2) (GGX truncated to 95% of its mass has variance about
/// 2 alpha^2). cos_divergence <= 0 gives 1.
float widen_roughness(float alpha, float cos_divergence);

/// The proxy made concrete for one shading point: unit axes and transformed roughnesses.
struct PreparedProxy {
  Vec3 n, r, t;                   ///< unit axes (n flipped towards wo)
  float kd = 0, kt = 0;           ///< diffuse / translucent coefficients (w / pi)
  float wr = 0, wt = 0;           ///< reflection / refraction weights
  float alpha_r = 1, alpha_t = 1; ///< transformed roughness
  float eta = 1;                  ///< IOR seen from wo's side
  bool tir = false;               ///< total internal reflection happened
  bool half_vector = false;       ///< the reflection lobe is ReflectionLobe::HalfVector (alpha_r its roughness)
  bool ok = false;

  bool valid() const { return ok; }
  /// Proxy value for incoming direction wi (unit).
  float eval(Vec3 wi) const;
  /// Proxy value at the direction of the cone closest to each lobe axis (the paper's cell estimate).
  float eval_cone(Vec3 axis, float cos_half_angle, float sin_half_angle) const;
};

PreparedProxy prepare_proxy(const BsdfProxy& proxy, Vec3 n, Vec3 wo, const ProxyOptions& options = {});

}  // namespace envpis
