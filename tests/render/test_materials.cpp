// SPDX-License-Identifier: Apache-2.0
// Tests of the renderer's materials (render/material.h, render/materials/): the GGX and Fresnel
// helpers, a chi-square test of every lobe's sampler and of multi-lobe materials, reciprocity, energy
// (Monte-Carlo and quadrature albedos), sample/eval/pdf consistency, degenerate inputs, proxy
// accumulation and a white furnace with analytic spheres.
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "chi2.h"
#include "render/material.h"
#include "render/materials/microfacet.h"

namespace envpis::render {
namespace {

namespace mf = microfacet;

const Rgb kGoldEta{0.143f, 0.374f, 1.442f};
const Rgb kGoldK{3.983f, 2.385f, 1.603f};
const Rgb kWhite{1, 1, 1};

/// Unit direction with cos theta = z at azimuth phi.
Vec3 dir(float z, float phi = 0.7f) {
  const float s = std::sqrt(std::max(0.0f, 1.0f - z * z));
  return {s * std::cos(phi), s * std::sin(phi), z};
}

Vec3 uniform_sphere(std::mt19937_64& rng) {
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  const float z = 1.0f - 2.0f * U(rng), phi = 2.0f * kPi * U(rng);
  return dir(z, phi);
}

bool finite(Rgb c) { return std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b); }
float max_channel(Rgb c) { return std::max(c.r, std::max(c.g, c.b)); }

/// Integral over the sphere of g(w) by the midpoint rule on an n x n equal-area grid (equal solid angles).
template <class G>
double sphere_quadrature(int n, G g) {
  double acc = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x)
      acc += g(equal_area_square_to_sphere(Point2{(x + 0.5f) / n, (y + 0.5f) / n}));
  return acc * 4.0 * M_PI / (double(n) * n);
}

/// Monte-Carlo directional albedo: mean sample weight per channel (failed draws count as 0).
template <class S>
Rgb mc_albedo(const S& bsdf, Vec3 wo, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  double r = 0, g = 0, b = 0;
  for (int i = 0; i < n; ++i) {
    const Point2 u{U(rng), U(rng)};
    const auto s = bsdf.sample(wo, u, U(rng));
    if (!s) continue;
    r += s->weight.r;
    g += s->weight.g;
    b += s->weight.b;
  }
  return {float(r / n), float(g / n), float(b / n)};
}

// ------------------------------------------------------------------------------------------------
// GGX and Fresnel helpers

TEST(MaterialMicrofacet, FresnelKnownValues) {
  EXPECT_NEAR(mf::fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);
  EXPECT_NEAR(mf::fresnel_dielectric(-1.0f, 1.5f), 0.04f, 1e-6f);  // same from inside at normal incidence
  EXPECT_EQ(mf::fresnel_dielectric(0.7f, 1.0f), 0.0f);
  EXPECT_NEAR(mf::fresnel_dielectric(0.0f, 1.5f), 1.0f, 1e-6f);  // grazing
  // From inside glass, beyond the critical angle (cos = sqrt(1 - 1/1.5^2) = 0.745): total reflection.
  EXPECT_EQ(mf::fresnel_dielectric(-0.7f, 1.5f), 1.0f);
  EXPECT_LT(mf::fresnel_dielectric(-0.8f, 1.5f), 1.0f);
  // Brewster angle: tan theta_B = 1.5, the parallel part vanishes: F = r_perp^2 / 2.
  const float cb = std::cos(std::atan(1.5f));
  const float ct = std::sqrt(1.0f - (1.0f - cb * cb) / 2.25f);
  const float rp = (cb - 1.5f * ct) / (cb + 1.5f * ct);
  EXPECT_NEAR(mf::fresnel_dielectric(cb, 1.5f), 0.5f * rp * rp, 1e-6f);
  // A conductor with k = 0 is a dielectric; at normal incidence ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
  for (float c : {1.0f, 0.8f, 0.4f, 0.1f}) EXPECT_NEAR(mf::fresnel_conductor(c, 1.5f, 0.0f), mf::fresnel_dielectric(c, 1.5f), 1e-5f);
  const float n = 0.143f, k = 3.983f;
  EXPECT_NEAR(mf::fresnel_conductor(1.0f, n, k), ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k), 1e-5f);
  EXPECT_NEAR(mf::fresnel_conductor(0.0f, n, k), 1.0f, 1e-5f);
  // Against the complex-arithmetic Fresnel equations (double precision).
  auto complex_fresnel = [](double c, double eta, double kk) {
    using C = std::complex<double>;
    const C n(eta, kk), ct = std::sqrt(C(1.0) - C(1.0 - c * c) / (n * n));
    const C rp = (n * c - ct) / (n * c + ct), rs = (C(c) - n * ct) / (C(c) + n * ct);
    return 0.5 * (std::norm(rp) + std::norm(rs));
  };
  for (auto [e, kk] : {std::pair{0.143f, 3.983f}, {1.442f, 1.603f}, {2.9f, 3.0f}, {1.5f, 0.0f}, {0.2f, 0.0f}})
    for (float c : {1.0f, 0.9f, 0.6f, 0.3f, 0.1f, 0.01f})
      EXPECT_NEAR(mf::fresnel_conductor(c, e, kk), complex_fresnel(c, e, kk), 2e-5) << e << " " << kk << " " << c;
  EXPECT_NEAR(mf::fresnel_schlick(1.0f, 0.3f), 0.3f, 1e-7f);
  EXPECT_NEAR(mf::fresnel_schlick(0.0f, 0.3f), 1.0f, 1e-7f);
  // The two-cosine form agrees with the one-cosine form on Snell pairs and is symmetric in the sides.
  for (float eta : {1.5f, 1.33f, 0.8f})
    for (float c : {1.0f, 0.9f, 0.5f, 0.2f, 0.01f}) {
      const float s2 = (1 - c * c) / (eta * eta);
      if (s2 >= 1) continue;
      const float ct = std::sqrt(1 - s2);
      EXPECT_NEAR(mf::fresnel_dielectric_pair(c, ct, eta), mf::fresnel_dielectric(c, eta), 1e-5f);
      EXPECT_NEAR(mf::fresnel_dielectric_pair(ct, c, 1 / eta), mf::fresnel_dielectric_pair(c, ct, eta), 1e-6f);
    }
}

TEST(MaterialMicrofacet, GgxNormalizationAndVisibleNormals) {
  for (float alpha : {0.1f, 0.4f, 1.0f}) {
    // Projected microfacet area: int D(m) m_z dm = 1.
    const double proj = sphere_quadrature(1024, [&](Vec3 m) { return mf::ggx_d(m, alpha) * std::max(0.0f, m.z); });
    EXPECT_NEAR(proj, 1.0, 3e-3) << "alpha " << alpha;
    for (float z : {1.0f, 0.6f, 0.15f}) {
      const Vec3 wo = dir(z);
      // The visible-normal density integrates to 1 (Smith G1 is exactly the visible-area normalization).
      const double vis = sphere_quadrature(1024, [&](Vec3 m) { return mf::ggx_visible_normal_pdf(wo, m, alpha); });
      EXPECT_NEAR(vis, 1.0, 5e-3) << "alpha " << alpha << " wo.z " << z;
    }
  }
}

// ------------------------------------------------------------------------------------------------
// Chi-square tests of the samplers

using SampleFn = std::function<std::optional<BsdfSample>(Vec3, Point2, float)>;
using PdfFn = std::function<float(Vec3, Vec3)>;

struct Chi2Case {
  std::string label;
  SampleFn sample;
  PdfFn pdf;
  Vec3 wo;
  float sharpest_alpha;  ///< the narrowest lobe: chooses the pdf-integration sub-grid
};

Chi2Case lobe_case(const std::string& label, std::shared_ptr<const Lobe> l, Vec3 wo, float alpha) {
  return {label + " wo.z=" + std::to_string(wo.z),
          [l](Vec3 o, Point2 u, float uc) { return l->sample(o, u, uc); },
          [l](Vec3 o, Vec3 i) { return l->pdf(o, i); }, wo, alpha};
}

Chi2Case material_case(const std::string& label, std::shared_ptr<const Material> m, Vec3 wo, float alpha) {
  return {label + " wo.z=" + std::to_string(wo.z),
          [m](Vec3 o, Point2 u, float uc) { return m->sample(o, u, uc); },
          [m](Vec3 o, Vec3 i) { return m->pdf(o, i); }, wo, alpha};
}

const std::vector<float> kAlphas{0.05f, 0.2f, 0.5f, 1.0f};

const std::vector<Chi2Case>& diffuse_cases() {
  static const std::vector<Chi2Case> v = [] {
    std::vector<Chi2Case> c;
    const auto lambert = make_lambert({0.8f, 0.5f, 0.2f});
    for (float z : {1.0f, 0.5f, 0.05f, -0.6f}) c.push_back(lobe_case("lambert", lambert, dir(z), 1.0f));
    const auto translucent = make_translucent({0.3f, 0.6f, 0.9f});
    for (float z : {0.7f, -0.3f}) c.push_back(lobe_case("translucent", translucent, dir(z), 1.0f));
    return c;
  }();
  return v;
}

const std::vector<Chi2Case>& conductor_cases() {
  static const std::vector<Chi2Case> v = [] {
    std::vector<Chi2Case> c;
    for (float a : kAlphas) {
      const auto l = make_conductor(a, kGoldEta, kGoldK);
      for (float z : {1.0f, 0.6f, 0.08f}) c.push_back(lobe_case("conductor a=" + std::to_string(a), l, dir(z), a));
    }
    const auto schlick = make_conductor_reflectance(0.3f, {0.9f, 0.6f, 0.3f});
    for (float z : {0.4f, -0.5f}) c.push_back(lobe_case("conductor-schlick a=0.3", schlick, dir(z), 0.3f));
    return c;
  }();
  return v;
}

const std::vector<Chi2Case>& dielectric_cases() {
  static const std::vector<Chi2Case> v = [] {
    std::vector<Chi2Case> c;
    for (float a : kAlphas) {
      const auto l = make_dielectric(a, 1.5f);
      // outside (normal-ish and grazing), inside below and beyond the critical angle (cos 0.745)
      for (float z : {0.9f, 0.15f, -0.8f, -0.3f})
        c.push_back(lobe_case("dielectric eta=1.5 a=" + std::to_string(a), l, dir(z), a));
    }
    c.push_back(lobe_case("dielectric eta=1.33 tinted a=0.3", make_dielectric(0.3f, 1.33f, {0.9f, 0.7f, 0.5f}),
                          dir(0.5f), 0.3f));
    c.push_back(lobe_case("dielectric eta=0.8 a=0.3", make_dielectric(0.3f, 0.8f), dir(0.6f), 0.3f));
    // a dark tint shifts the reflect/refract choice toward reflection
    const auto dark = make_dielectric(0.1f, 1.5f, {0.1f, 0.2f, 0.05f});
    for (float z : {0.7f, -0.9f}) c.push_back(lobe_case("dielectric dark tint a=0.1", dark, dir(z), 0.1f));
    return c;
  }();
  return v;
}

const std::vector<Chi2Case>& coated_cases() {
  static const std::vector<Chi2Case> v = [] {
    std::vector<Chi2Case> c;
    for (float a : kAlphas) {
      const auto l = make_coated_diffuse({0.7f, 0.3f, 0.1f}, a, 1.5f);
      for (float z : {0.8f, 0.1f}) c.push_back(lobe_case("coated a=" + std::to_string(a), l, dir(z), a));
    }
    c.push_back(lobe_case("coated a=0.2", make_coated_diffuse({0.5f, 0.5f, 0.5f}, 0.2f, 1.5f), dir(-0.5f), 0.2f));
    return c;
  }();
  return v;
}

std::shared_ptr<const Material> plastic_like() {
  auto m = std::make_shared<Material>();
  m->add(make_lambert({0.5f, 0.4f, 0.3f}), 1.0f);
  m->add(make_conductor_reflectance(0.1f, {0.04f, 0.04f, 0.04f}), 1.0f);
  return m;
}

std::shared_ptr<const Material> leaf_like() {
  auto m = std::make_shared<Material>();
  m->add(make_coated_diffuse({0.2f, 0.6f, 0.1f}, 0.3f, 1.4f), 0.6f);
  m->add(make_translucent({0.3f, 0.8f, 0.2f}), 0.4f);
  return m;
}

std::shared_ptr<const Material> glass_mix() {
  auto m = std::make_shared<Material>();
  m->add(make_dielectric(0.2f, 1.5f), 0.5f);
  m->add(make_lambert({0.6f, 0.6f, 0.6f}), 0.2f);
  m->add(make_conductor(0.4f, kGoldEta, kGoldK), 0.3f);
  return m;
}

const std::vector<Chi2Case>& material_cases() {
  static const std::vector<Chi2Case> v = [] {
    std::vector<Chi2Case> c;
    for (float z : {0.7f, 0.2f}) c.push_back(material_case("material plastic", plastic_like(), dir(z), 0.1f));
    for (float z : {0.6f, -0.4f}) c.push_back(material_case("material leaf", leaf_like(), dir(z), 0.3f));
    for (float z : {0.5f, -0.7f}) c.push_back(material_case("material glass-mix", glass_mix(), dir(z), 0.2f));
    return c;
  }();
  return v;
}

int chi2_family_size() {
  return int(diffuse_cases().size() + conductor_cases().size() + dielectric_cases().size() +
             coated_cases().size() + material_cases().size());
}

void run_chi2(const std::vector<Chi2Case>& cases, std::uint64_t seed_base) {
  double min_p = 1;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const Chi2Case& c = cases[i];
    std::mt19937_64 rng(seed_base * 1000003u + i);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    test::Chi2Options opt;
    opt.bins = 32;
    // Pdf integration sub-grid: fine enough for sharp lobes and for the pdf's discontinuities (the
    // horizon, the edge where the microfacet turns away from wo) that cross a bin.
    opt.sub = c.sharpest_alpha < 0.1f ? 48 : 32;
    opt.samples = 100000;
    opt.test_count = chi2_family_size();
    opt.seed = seed_base + 7919u * i;
    const auto r = test::chi2_test(
        [&](float u1, float u2) -> std::optional<Vec3> {
          const auto s = c.sample(c.wo, Point2{u1, u2}, U(rng));
          if (!s) return std::nullopt;
          return s->wi;
        },
        [&](Vec3 d) { return double(c.pdf(c.wo, d)); }, opt);
    EXPECT_TRUE(r.passed) << c.label << ": " << r.message;
    EXPECT_LE(r.pdf_integral, 1.01) << c.label;
    std::printf("  chi2 %-44s p=%.4f dof=%d pdf-integral=%.4f\n", c.label.c_str(), r.p_value, r.dof,
                r.pdf_integral);
    min_p = std::min(min_p, r.p_value);
  }
  std::printf("  %zu tests, min p = %.4g (family of %d)\n", cases.size(), min_p, chi2_family_size());
}

TEST(MaterialChi2, DiffuseAndTranslucent) { run_chi2(diffuse_cases(), 11); }
TEST(MaterialChi2, Conductor) { run_chi2(conductor_cases(), 23); }
TEST(MaterialChi2, Dielectric) { run_chi2(dielectric_cases(), 37); }
TEST(MaterialChi2, CoatedDiffuse) { run_chi2(coated_cases(), 41); }
TEST(MaterialChi2, MultiLobeMaterial) { run_chi2(material_cases(), 53); }

// ------------------------------------------------------------------------------------------------
// Reciprocity

void expect_rgb_near(Rgb a, Rgb b, float rel, const std::string& what) {
  const float tol = rel * std::max(max_channel(a), max_channel(b)) + 1e-6f;
  EXPECT_NEAR(a.r, b.r, tol) << what;
  EXPECT_NEAR(a.g, b.g, tol) << what;
  EXPECT_NEAR(a.b, b.b, tol) << what;
}

TEST(MaterialReciprocity, ReflectiveLobesAreSymmetric) {
  std::vector<std::pair<std::string, std::shared_ptr<const Lobe>>> lobes{
      {"lambert", make_lambert({0.8f, 0.5f, 0.2f})},
      {"translucent", make_translucent({0.3f, 0.6f, 0.9f})},
      {"coated a=0.3", make_coated_diffuse({0.7f, 0.3f, 0.1f}, 0.3f, 1.5f)},
      {"coated a=0.05", make_coated_diffuse({0.7f, 0.3f, 0.1f}, 0.05f, 1.5f)},
  };
  for (float a : {0.1f, 0.3f, 0.7f}) {
    lobes.push_back({"conductor a=" + std::to_string(a), make_conductor(a, kGoldEta, kGoldK)});
    lobes.push_back({"schlick a=" + std::to_string(a), make_conductor_reflectance(a, {0.9f, 0.6f, 0.3f})});
    lobes.push_back({"dielectric a=" + std::to_string(a), make_dielectric(a, 1.5f)});
  }
  std::mt19937_64 rng(5);
  for (const auto& [name, l] : lobes) {
    int nonzero = 0;
    for (int i = 0; i < 4000; ++i) {
      const Vec3 wo = uniform_sphere(rng), wi = uniform_sphere(rng);
      if (name.rfind("dielectric", 0) == 0 && (wo.z > 0) != (wi.z > 0)) continue;  // refraction: below
      const Rgb f1 = l->eval(wo, wi), f2 = l->eval(wi, wo);
      if (max_channel(f1) > 0) ++nonzero;
      expect_rgb_near(f1, f2, 2e-3f, name);
    }
    EXPECT_GT(nonzero, 500) << name;  // the test compared real values, not zeros
  }
}

TEST(MaterialReciprocity, DielectricRefractionGeneralized) {
  // f(wo, wi) / n_i^2 == f(wi, wo) / n_o^2 with n the index on each direction's side.
  for (float eta : {1.5f, 1.33f, 0.8f}) {
    for (float a : {0.1f, 0.3f, 0.7f}) {
      const auto l = make_dielectric(a, eta);
      std::mt19937_64 rng(17);
      int nonzero = 0;
      for (int i = 0; i < 4000; ++i) {
        const Vec3 wo = uniform_sphere(rng);
        Vec3 wi = uniform_sphere(rng);
        if ((wo.z > 0) == (wi.z > 0)) wi.z = -wi.z;
        const float n_o = wo.z > 0 ? 1.0f : eta, n_i = wi.z > 0 ? 1.0f : eta;
        const Rgb f1 = l->eval(wo, wi) * (1.0f / (n_i * n_i)), f2 = l->eval(wi, wo) * (1.0f / (n_o * n_o));
        if (max_channel(f1) > 1e-4f) ++nonzero;
        expect_rgb_near(f1, f2, 2e-3f, "eta " + std::to_string(eta) + " alpha " + std::to_string(a));
      }
      EXPECT_GT(nonzero, 300) << eta << " " << a;
    }
  }
}

// ------------------------------------------------------------------------------------------------
// Energy

struct NamedLobe {
  std::string name;
  std::shared_ptr<const Lobe> lobe;
};

std::vector<NamedLobe> energy_lobes() {
  std::vector<NamedLobe> v{{"lambert white", make_lambert(kWhite)},
                           {"translucent white", make_translucent(kWhite)}};
  for (float a : {0.0f, 0.05f, 0.2f, 0.5f, 1.0f}) {
    const std::string s = " a=" + std::to_string(a);
    v.push_back({"conductor gold" + s, make_conductor(a, kGoldEta, kGoldK)});
    v.push_back({"conductor f0=1" + s, make_conductor_reflectance(a, kWhite)});
    v.push_back({"dielectric 1.5" + s, make_dielectric(a, 1.5f)});
    v.push_back({"dielectric 1.0" + s, make_dielectric(a, 1.0f)});
    v.push_back({"coated white" + s, make_coated_diffuse(kWhite, a, 1.5f)});
    v.push_back({"coated red" + s, make_coated_diffuse({0.9f, 0.1f, 0.1f}, a, 1.5f)});
  }
  return v;
}

TEST(MaterialEnergy, AlbedoAtMostOneAndTablesAgree) {
  int k = 0;
  for (const auto& [name, l] : energy_lobes()) {
    for (float z : {1.0f, 0.7f, 0.3f, 0.05f, -0.4f, -0.9f}) {
      const Rgb a = mc_albedo(*l, dir(z), 20000, 1000 + k++);
      EXPECT_LE(max_channel(a), 1.01f) << name << " wo.z " << z;
      EXPECT_TRUE(finite(a)) << name;
      // The lobe's own estimate (tabulated single-scattering energy) against Monte Carlo.
      EXPECT_NEAR(l->albedo(dir(z)), a.average(), 0.02f) << name << " wo.z " << z;
    }
  }
}

TEST(MaterialEnergy, WhiteLambertIsOne) {
  const auto l = make_lambert(kWhite);
  for (float z : {1.0f, 0.4f, -0.7f}) {
    const Vec3 wo = dir(z);
    // Quadrature of f |cos| (independent of the sampler) and Monte Carlo with the sampler.
    const double q = sphere_quadrature(512, [&](Vec3 wi) { return l->eval(wo, wi).g * std::abs(wi.z); });
    EXPECT_NEAR(q, 1.0, 0.01) << z;
    const Rgb a = mc_albedo(*l, wo, 20000, 3);
    EXPECT_NEAR(a.g, 1.0f, 0.01f);
  }
}

TEST(MaterialEnergy, EvalIntegralMatchesSampledAlbedo) {
  // The chi-square tests tie sample() to pdf(); this ties eval() to them: the quadrature of
  // f |cos theta_i| over the sphere must equal the mean sample weight f |cos| / pdf.
  std::vector<NamedLobe> lobes{{"translucent", make_translucent({0.3f, 0.6f, 0.9f})}};
  for (float a : {0.2f, 0.5f, 1.0f}) {
    const std::string s = " a=" + std::to_string(a);
    lobes.push_back({"conductor" + s, make_conductor(a, kGoldEta, kGoldK)});
    lobes.push_back({"dielectric" + s, make_dielectric(a, 1.5f, {1.0f, 0.8f, 0.6f})});
    lobes.push_back({"coated" + s, make_coated_diffuse({0.7f, 0.3f, 0.1f}, a, 1.5f)});
  }
  int k = 0;
  for (const auto& [name, l] : lobes)
    for (float z : {0.8f, 0.3f, -0.6f}) {
      const Vec3 wo = dir(z);
      const double q = sphere_quadrature(768, [&](Vec3 wi) { return l->eval(wo, wi).b * std::abs(wi.z); });
      const Rgb a = mc_albedo(*l, wo, 40000, 77 + k++);
      EXPECT_NEAR(q, a.b, 0.015 + 0.01 * q) << name << " wo.z " << z;
    }
}

TEST(MaterialEnergy, GgxSingleScatteringLossMatchesAnalytic) {
  // A white (F = 1) GGX reflector at alpha 1 and normal incidence: D is uniform, wi = reflect about m
  // is above the horizon for theta_m < 45 deg, and G2 / G1 = 2 cos(2 theta_m) / (1 + cos(2 theta_m)):
  // the albedo is int_0^1 x / (1 + x) dx = 1 - ln 2 (single scattering loses 69% here).
  const auto l = make_conductor_reflectance(1.0f, kWhite);
  const float expected = 1.0f - std::log(2.0f);
  EXPECT_NEAR(mc_albedo(*l, {0, 0, 1}, 100000, 12).g, expected, 0.005f);
  EXPECT_NEAR(sphere_quadrature(1024, [&](Vec3 wi) { return l->eval({0, 0, 1}, wi).g * std::abs(wi.z); }), expected,
              0.003);
  EXPECT_NEAR(l->albedo({0, 0, 1}), expected, 0.003f);
}

TEST(MaterialEnergy, NonAbsorbingDielectricConserves) {
  // Reflection + transmission carry all the energy up to the single-scattering loss of the GGX
  // model (light that would scatter again on the microsurface is lost), which grows with roughness,
  // at grazing angles and from inside near total internal reflection.
  struct Case {
    float alpha, z, min_albedo;
  };
  const std::vector<Case> cases{
      // nearly smooth: everything, from both sides, including total internal reflection (-0.5)
      {0.01f, 1.0f, 0.995f}, {0.01f, 0.4f, 0.995f}, {0.01f, -0.9f, 0.995f}, {0.01f, -0.5f, 0.995f},
      {0.05f, 1.0f, 0.99f},  {0.05f, 0.7f, 0.99f},  {0.05f, 0.4f, 0.99f},   {0.05f, -1.0f, 0.99f},
      {0.05f, -0.8f, 0.99f}, {0.05f, -0.5f, 0.99f},
      // moderate roughness from outside: within a few percent
      {0.2f, 1.0f, 0.98f},   {0.2f, 0.7f, 0.97f},   {0.2f, 0.4f, 0.95f},
      // rougher or from inside: the single-scattering loss shows, but never a gain
      {0.2f, -1.0f, 0.93f},  {0.5f, 1.0f, 0.95f},   {0.5f, -0.8f, 0.6f}};
  for (const Case& c : cases) {
    const auto l = make_dielectric(c.alpha, 1.5f);
    const Rgb e = mc_albedo(*l, dir(c.z), 40000, 900);
    EXPECT_GT(e.g, c.min_albedo) << "alpha " << c.alpha << " wo.z " << c.z;
    EXPECT_LT(e.g, 1.005f) << "alpha " << c.alpha << " wo.z " << c.z;
  }
  // eta 1: everything passes straight through (eta is moved to 1.01 and the interface made smooth,
  // so the rays bend by ~(eta - 1) tan theta = 0.013 rad here, the macro-surface refraction).
  const auto m = make_dielectric(0.3f, 1.0f);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  const Vec3 wo = dir(0.6f);
  Vec3 t;
  ASSERT_TRUE(mf::refract(wo, {0, 0, 1}, 1.01f, t));
  EXPECT_GT(dot(t, -wo), 0.9999f);
  double mean_cos = 0, weight = 0;
  int got = 0;
  for (int i = 0; i < 4000; ++i) {
    const auto s = m->sample(wo, {U(rng), U(rng)}, U(rng));
    if (!s) continue;
    ++got;
    EXPECT_TRUE(s->transmission);
    EXPECT_GT(dot(s->wi, t), 0.9999f);
    mean_cos += dot(s->wi, t);
    weight += s->weight.g;
  }
  EXPECT_GT(got, 0.99 * 4000);
  EXPECT_GT(mean_cos / got, 1.0 - 1e-7);  // on the refracted direction
  EXPECT_NEAR(weight / 4000, 1.0, 0.01);
}

TEST(MaterialEnergy, CoatedWhiteBaseLosesNothing) {
  for (float a : {0.05f, 0.3f, 1.0f})
    for (float eta : {1.3f, 1.5f, 2.0f}) {
      const auto l = make_coated_diffuse(kWhite, a, eta);
      for (float z : {1.0f, 0.5f, 0.1f}) {
        const Rgb e = mc_albedo(*l, dir(z), 20000, 31);
        EXPECT_NEAR(e.r, 1.0f, 0.02f) << "alpha " << a << " eta " << eta << " wo.z " << z;
      }
    }
  // A black base leaves the coat's specular reflection only, about 4% at normal incidence for eta 1.5.
  const auto black = make_coated_diffuse({0, 0, 0}, 0.05f, 1.5f);
  EXPECT_NEAR(mc_albedo(*black, dir(1.0f), 20000, 3).r, 0.04f, 0.004f);
}

// ------------------------------------------------------------------------------------------------
// sample() against eval() and pdf()

TEST(MaterialSample, WeightPdfAndValueAreConsistent) {
  std::vector<NamedLobe> lobes = energy_lobes();
  lobes.push_back({"translucent", make_translucent({0.3f, 0.6f, 0.9f})});
  lobes.push_back({"dielectric tinted eta 0.8", make_dielectric(0.3f, 0.8f, {0.2f, 0.5f, 0.9f})});
  struct NamedMaterial {
    std::string name;
    std::shared_ptr<const Material> m;
  };
  std::vector<NamedMaterial> materials{{"plastic", plastic_like()}, {"leaf", leaf_like()}, {"glass-mix", glass_mix()}};
  auto single = std::make_shared<Material>();
  single->add(make_conductor(0.2f, kGoldEta, kGoldK), 0.5f);
  materials.push_back({"single weighted lobe", single});

  std::mt19937_64 rng(99);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  auto check = [&](const std::string& name, auto&& bsdf) {
    int got = 0;
    for (int i = 0; i < 3000; ++i) {
      Vec3 wo = uniform_sphere(rng);
      if (std::abs(wo.z) < 1e-3f) continue;
      const auto s = bsdf.sample(wo, Point2{U(rng), U(rng)}, U(rng));
      if (!s) continue;
      ++got;
      ASSERT_TRUE(finite(s->f) && finite(s->weight) && std::isfinite(s->pdf)) << name;
      ASSERT_GT(s->pdf, 0.0f) << name;
      EXPECT_NEAR(length(s->wi), 1.0f, 1e-3f) << name;
      EXPECT_EQ(s->transmission, (wo.z > 0) != (s->wi.z > 0)) << name;
      const float p = bsdf.pdf(wo, s->wi);
      EXPECT_NEAR(s->pdf, p, 1e-4f * p) << name;
      expect_rgb_near(s->f, bsdf.eval(wo, s->wi), 1e-4f, name + " f");
      expect_rgb_near(s->weight, s->f * (std::abs(s->wi.z) / s->pdf), 1e-4f, name + " weight");
    }
    EXPECT_GT(got, 1000) << name;
  };
  for (const auto& [name, l] : lobes) check(name, *l);
  for (const auto& [name, m] : materials) check(name, *m);
}

// ------------------------------------------------------------------------------------------------
// Degenerate inputs and extreme parameters

TEST(MaterialRobustness, NoNanAtExtremes) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<std::shared_ptr<const Lobe>> lobes{make_lambert(kWhite), make_translucent(kWhite),
                                                 make_lambert({nan, -1.0f, 2.0f})};
  for (float a : {0.0f, 1e-5f, 1.0f, 3.0f, nan, -1.0f}) {
    lobes.push_back(make_conductor(a, kGoldEta, kGoldK));
    lobes.push_back(make_conductor(a, {0, 0, 0}, {0, 0, 0}));
    lobes.push_back(make_conductor_reflectance(a, {1.0f, 0.0f, 2.0f}));
    for (float eta : {1.0f, 1.001f, 0.999f, 1.5f, 0.5f, 3.0f, 0.0f, -2.0f, nan}) {
      lobes.push_back(make_dielectric(a, eta));
      lobes.push_back(make_coated_diffuse({0.5f, 1.0f, 0.0f}, a, eta));
    }
  }
  std::vector<Vec3> dirs{{0, 0, 1},       {0, 0, -1},       {1, 0, 0},          {0, 0, 0}, {nan, 0, 1},
                         dir(1e-6f),      dir(-1e-6f),      dir(0.5f),          dir(-0.5f), dir(0.999999f),
                         {0.6f, 0.0f, 0.8f}, {-0.6f, 0.0f, 0.8f}, {-0.6f, 0.0f, -0.8f}, {0.6f, 0.0f, -0.8f}};
  const std::vector<Point2> us{{0, 0}, {0.5f, 0.5f}, {0x1.fffffep-1f, 0x1.fffffep-1f}, {0, 0x1.fffffep-1f}, {0.25f, 0}};
  for (const auto& l : lobes) {
    for (Vec3 wo : dirs) {
      const bool degenerate = !(wo.z != 0) || !std::isfinite(wo.x);
      for (Vec3 wi : dirs) {
        const Rgb f = l->eval(wo, wi);
        const float p = l->pdf(wo, wi);
        ASSERT_TRUE(finite(f) && std::isfinite(p)) << l->name();
        EXPECT_GE(std::min(f.r, std::min(f.g, f.b)), 0.0f) << l->name();
        EXPECT_GE(p, 0.0f) << l->name();
        if (degenerate || !(wi.z != 0) || !std::isfinite(wi.x)) {
          EXPECT_EQ(max_channel(f), 0.0f) << l->name();
          EXPECT_EQ(p, 0.0f) << l->name();
        }
      }
      // wi = -wo and wi = wo: the degenerate configurations of the half vectors.
      for (Vec3 wi : {-wo, wo}) {
        ASSERT_TRUE(finite(l->eval(wo, wi)) && std::isfinite(l->pdf(wo, wi))) << l->name();
      }
      for (Point2 u : us)
        for (float uc : {0.0f, 0.5f, 0x1.fffffep-1f}) {
          const auto s = l->sample(wo, u, uc);
          if (degenerate) {
            EXPECT_FALSE(s) << l->name();
            continue;
          }
          if (!s) continue;
          ASSERT_TRUE(finite(s->f) && finite(s->weight) && std::isfinite(s->pdf)) << l->name();
          ASSERT_GT(s->pdf, 0.0f);
          ASSERT_TRUE(std::isfinite(s->wi.x) && std::isfinite(s->wi.y) && std::isfinite(s->wi.z));
        }
      const float a = l->albedo(wo);
      EXPECT_TRUE(std::isfinite(a) && a >= 0) << l->name();
      BsdfProxy proxy;
      l->add_to_proxy(proxy, wo, 1.0f);
      EXPECT_TRUE(std::isfinite(proxy.reflection) && std::isfinite(proxy.refraction) &&
                  std::isfinite(proxy.alpha_reflection) && std::isfinite(proxy.ior));
    }
  }
}

TEST(MaterialRobustness, NearMirrorStaysConsistent) {
  // alpha 0 is a very sharp GGX lobe, not a delta: samples land next to the mirror direction with
  // a large but finite pdf that pdf() reproduces.
  for (const auto& l : {make_conductor(0.0f, kGoldEta, kGoldK), make_dielectric(0.0f, 1.5f)}) {
    std::mt19937_64 rng(4);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    const Vec3 wo = dir(0.6f), mirror{-wo.x, -wo.y, wo.z};
    int reflected = 0, sharp = 0;
    for (int i = 0; i < 4000; ++i) {
      const auto s = l->sample(wo, {U(rng), U(rng)}, U(rng));
      if (!s) continue;  // GGX's tail can reflect below the horizon
      if (s->transmission) continue;
      ++reflected;
      // GGX's long tail: P(tan theta_m > t) = alpha^2 / (alpha^2 + t^2), so ~99% of the normals are
      // within 0.6 degrees of the normal, and the reflections within 1.2 degrees of the mirror.
      if (dot(s->wi, mirror) > 0.99978f) ++sharp;
      EXPECT_NEAR(l->pdf(wo, s->wi), s->pdf, 2e-3f * s->pdf);
    }
    EXPECT_GT(reflected, 100) << l->name();
    EXPECT_GT(sharp, 0.97 * reflected) << l->name();
    // The mirror direction itself has a large, finite density (GGX peak 1 / (pi alpha^2) ~ 3e5).
    const float p_mirror = l->pdf(wo, mirror);
    EXPECT_GT(p_mirror, 1e3f) << l->name();
    EXPECT_TRUE(std::isfinite(p_mirror) && finite(l->eval(wo, mirror)));
  }
}

// ------------------------------------------------------------------------------------------------
// Proxy accumulation

TEST(MaterialProxy, LobesFillTheirAxes) {
  const Vec3 wo = dir(0.8f);
  {
    BsdfProxy p;
    make_lambert({0.3f, 0.6f, 0.9f})->add_to_proxy(p, wo, 0.5f);
    EXPECT_NEAR(p.diffuse, 0.5f * 0.6f, 1e-6f);
    EXPECT_EQ(p.reflection + p.refraction + p.translucent, 0.0f);
  }
  {
    BsdfProxy p;
    make_translucent({0.3f, 0.6f, 0.9f})->add_to_proxy(p, wo, 2.0f);
    EXPECT_NEAR(p.translucent, 1.2f, 1e-6f);
    EXPECT_EQ(p.reflection + p.refraction + p.diffuse, 0.0f);
  }
  {
    BsdfProxy p;
    const auto l = make_conductor(0.25f, kGoldEta, kGoldK);
    l->add_to_proxy(p, wo, 0.5f);
    EXPECT_NEAR(p.reflection, 0.5f * l->albedo(wo), 1e-6f);
    EXPECT_GT(p.reflection, 0.2f);
    EXPECT_NEAR(p.alpha_reflection, 0.25f, 1e-6f);
    EXPECT_EQ(p.diffuse + p.refraction, 0.0f);
  }
  {
    BsdfProxy p;
    const auto l = make_dielectric(0.2f, 1.5f);
    l->add_to_proxy(p, wo, 1.0f);
    EXPECT_NEAR(p.reflection + p.refraction, l->albedo(wo), 1e-5f);
    EXPECT_GT(p.reflection, 0.03f);
    EXPECT_LT(p.reflection, 0.1f);
    EXPECT_GT(p.refraction, 0.85f);
    EXPECT_NEAR(p.ior, 1.5f, 1e-6f);
    EXPECT_NEAR(p.alpha_refraction, 0.2f, 1e-6f);
    // From inside beyond the critical angle a smooth interface reflects everything.
    BsdfProxy q;
    make_dielectric(0.01f, 1.5f)->add_to_proxy(q, dir(-0.5f), 1.0f);
    EXPECT_LT(q.refraction, 0.01f);
    EXPECT_GT(q.reflection, 0.98f);
    // and the prepared proxy sees the refracted axis bend away from the normal when leaving glass.
    BsdfProxy r;
    l->add_to_proxy(r, dir(-0.9f), 1.0f);
    const PreparedProxy pp = prepare_proxy(r, {0, 0, 1}, dir(-0.9f));
    ASSERT_TRUE(pp.valid());
    EXPECT_GT(pp.t.z, 0.0f);
    EXPECT_LT(pp.t.z, 0.9f);
  }
  {
    BsdfProxy p;
    const auto l = make_coated_diffuse({0.8f, 0.8f, 0.8f}, 0.1f, 1.5f);
    l->add_to_proxy(p, wo, 1.0f);
    EXPECT_GT(p.reflection, 0.03f);
    EXPECT_GT(p.diffuse, 0.5f);
    EXPECT_NEAR(p.reflection + p.diffuse, l->albedo(wo), 1e-5f);
    EXPECT_NEAR(p.alpha_reflection, 0.1f, 1e-6f);
  }
  {
    // A material adds each lobe scaled by its weight.
    BsdfProxy p;
    glass_mix()->fill_proxy(p, wo);
    EXPECT_GT(p.diffuse, 0.0f);
    EXPECT_GT(p.reflection, 0.0f);
    EXPECT_GT(p.refraction, 0.0f);
    EXPECT_NEAR(p.diffuse, 0.2f * 0.6f, 1e-6f);
    EXPECT_NEAR(p.diffuse + p.reflection + p.refraction, glass_mix()->albedo(wo), 1e-5f);
  }
}

// A closed surface keeps only the proxy lobes on its outside: seen from outside (wo.z > 0) the
// reflection and diffuse lobes, seen from inside the refraction and translucent lobes; an open one
// keeps everything; sampling and evaluation do not change.
TEST(MaterialProxy, ClosedSurfaceKeepsOnlyTheOutsideLobes) {
  Material m;
  m.add(make_dielectric(0.2f, 1.5f), 0.7f);
  m.add(make_translucent({0.5f, 0.5f, 0.5f}), 0.2f);
  m.add(make_lambert({0.5f, 0.5f, 0.5f}), 0.1f);
  ASSERT_FALSE(m.closed_surface());
  Material closed = m;
  closed.set_closed_surface(true);
  for (float cz : {0.9f, 0.3f, -0.3f, -0.9f}) {
    const Vec3 wo = dir(cz);
    BsdfProxy open_p, closed_p;
    m.fill_proxy(open_p, wo);
    closed.fill_proxy(closed_p, wo);
    ASSERT_GT(open_p.reflection, 0.0f);
    ASSERT_GT(open_p.refraction, 0.0f);
    ASSERT_GT(open_p.diffuse, 0.0f);
    ASSERT_GT(open_p.translucent, 0.0f);
    if (cz > 0) {
      EXPECT_FLOAT_EQ(closed_p.reflection, open_p.reflection);
      EXPECT_FLOAT_EQ(closed_p.alpha_reflection, open_p.alpha_reflection);
      EXPECT_FLOAT_EQ(closed_p.diffuse, open_p.diffuse);
      EXPECT_EQ(closed_p.refraction, 0.0f);
      EXPECT_EQ(closed_p.translucent, 0.0f);
    } else {
      EXPECT_FLOAT_EQ(closed_p.refraction, open_p.refraction);
      EXPECT_FLOAT_EQ(closed_p.alpha_refraction, open_p.alpha_refraction);
      EXPECT_FLOAT_EQ(closed_p.ior, open_p.ior);
      EXPECT_FLOAT_EQ(closed_p.translucent, open_p.translucent);
      EXPECT_EQ(closed_p.reflection, 0.0f);
      EXPECT_EQ(closed_p.diffuse, 0.0f);
    }
    const Vec3 wi = dir(-cz * 0.5f);
    EXPECT_EQ(closed.pdf(wo, wi), m.pdf(wo, wi));
    EXPECT_EQ(closed.eval(wo, wi).average(), m.eval(wo, wi).average());
  }
}

// ------------------------------------------------------------------------------------------------
// The mixture

TEST(MaterialMixture, EvalPdfAndLobeSelection) {
  const auto lambert = make_lambert({0.6f, 0.6f, 0.6f});
  const auto translucent = make_translucent({0.2f, 0.2f, 0.2f});
  Material m;
  EXPECT_TRUE(m.empty());
  EXPECT_FALSE(m.sample(dir(0.5f), {0.3f, 0.3f}, 0.3f));
  EXPECT_EQ(m.pdf(dir(0.5f), dir(0.2f)), 0.0f);
  m.add(lambert, 0.5f);
  m.add(translucent, 1.5f);
  m.add(nullptr, 1.0f);           // ignored
  m.add(make_lambert(kWhite), 0.0f);  // ignored
  EXPECT_EQ(m.lobe_count(), 2u);
  const Vec3 wo = dir(0.5f);
  const Vec3 up = dir(0.3f, 2.0f), down = dir(-0.3f, 2.0f);
  EXPECT_NEAR(m.eval(wo, up).r, 0.5f * 0.6f / kPi, 1e-7f);
  EXPECT_NEAR(m.eval(wo, down).r, 1.5f * 0.2f / kPi, 1e-7f);
  // Selection probabilities 0.3 : 0.3 (weight * albedo) -> the mixture pdf.
  EXPECT_NEAR(m.pdf(wo, up), 0.5f * 0.3f / kPi, 1e-6f);
  EXPECT_NEAR(m.pdf(wo, down), 0.5f * 0.3f / kPi, 1e-6f);
  EXPECT_NEAR(m.albedo(wo), 0.6f, 1e-6f);

  // Selection frequency with unequal shares: 0.5 * 0.6 : 0.5 * 0.2 -> 75% reflection.
  Material n;
  n.add(lambert, 0.5f);
  n.add(translucent, 0.5f);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int transmitted = 0;
  const int N = 40000;
  for (int i = 0; i < N; ++i) {
    const auto s = n.sample(wo, {U(rng), U(rng)}, U(rng));
    ASSERT_TRUE(s);
    transmitted += s->transmission;
    EXPECT_NEAR(s->weight.r, 0.4f, 1e-5f);  // f cos / pdf is the total albedo for two cosine lobes
  }
  EXPECT_NEAR(double(transmitted) / N, 0.25, 4.0 * std::sqrt(0.25 * 0.75 / N));

  // A black material cannot be sampled.
  Material black;
  black.add(make_lambert({0, 0, 0}), 1.0f);
  EXPECT_FALSE(black.sample(wo, {0.5f, 0.5f}, 0.5f));
  EXPECT_EQ(black.pdf(wo, up), 0.0f);
}

// ------------------------------------------------------------------------------------------------
// White furnace: spheres under a constant white environment (radiance 1), traced analytically.

struct Onb {
  Vec3 t, b, n;
  explicit Onb(Vec3 nn) : n(nn) {  // Duff et al. 2017
    const float s = std::copysign(1.0f, n.z), a = -1.0f / (s + n.z), c = n.x * n.y * a;
    t = {1.0f + s * n.x * n.x * a, s * c, -s * n.x};
    b = {c, s + n.y * n.y * a, -n.y};
  }
  Vec3 to_local(Vec3 v) const { return {dot(v, t), dot(v, b), dot(v, n)}; }
  Vec3 to_world(Vec3 v) const { return t * v.x + b * v.y + n * v.z; }
};

/// Mean radiance seen through a unit sphere of `material` under a uniform environment of radiance 1.
/// `truncated`: fraction of paths still inside after max_depth bounces.
double furnace(const Material& material, int paths, int max_depth, std::uint64_t seed, double* truncated_out = nullptr) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  double sum = 0;
  int truncated = 0;
  for (int i = 0; i < paths; ++i) {
    // Orthographic camera ray toward -z through a uniformly chosen point of the sphere's disk.
    const float r = std::sqrt(U(rng)) * 0.999f, phi = 2.0f * kPi * U(rng);
    Vec3 o{r * std::cos(phi), r * std::sin(phi), 3.0f}, d{0, 0, -1};
    Rgb beta{1, 1, 1};
    bool escaped = false;
    for (int depth = 0; depth < max_depth; ++depth) {
      // Ray-sphere: |o + t d|^2 = 1, far root when inside.
      const float bq = dot(o, d), cq = dot(o, o) - 1.0f, disc = bq * bq - cq;
      float t = -1;
      if (disc > 0) {
        const float sq = std::sqrt(disc);
        t = -bq - sq > 1e-4f ? -bq - sq : -bq + sq;
      }
      if (!(t > 1e-4f)) {
        escaped = true;
        break;
      }
      const Vec3 p = normalize(o + d * t);
      const Onb frame(p);
      const auto s = material.sample(frame.to_local(-d), {U(rng), U(rng)}, U(rng));
      if (!s) {  // the microsurface absorbed it (single-scattering loss): the path ends dark
        escaped = false;
        beta = {};
        depth = max_depth;
        break;
      }
      beta = beta * s->weight;
      d = normalize(frame.to_world(s->wi));
      o = p + p * (s->wi.z > 0 ? 1e-4f : -1e-4f);
    }
    if (escaped) sum += beta.g;
    else if (beta.g > 0) ++truncated;
  }
  if (truncated_out) *truncated_out = double(truncated) / paths;
  return sum / paths;
}

TEST(MaterialFurnace, WhiteLambertSphere) {
  Material m;
  m.add(make_lambert(kWhite));
  EXPECT_NEAR(furnace(m, 20000, 8, 1), 1.0, 1e-4);  // every sample weighs exactly 1 and escapes
}

TEST(MaterialFurnace, NonAbsorbingDielectricSphere) {
  // Known answer 1 for a smooth sphere (every path that enters leaves: inside a sphere the angle of
  // incidence stays below the critical angle); roughness adds GGX's single-scattering loss at every
  // interaction (see NonAbsorbingDielectricConserves), but never a gain.
  for (float a : {0.0f, 0.05f, 0.3f}) {
    Material m;
    m.add(make_dielectric(a, 1.5f));
    double truncated = 0;
    const double v = furnace(m, 20000, 64, 2, &truncated);
    EXPECT_LT(v, 1.0 + 1e-3) << "alpha " << a;
    EXPECT_GT(v, a == 0.0f ? 0.997 : (a < 0.1f ? 0.97 : 0.6)) << "alpha " << a;
    EXPECT_LT(truncated, 2e-3) << "alpha " << a;
    std::printf("  furnace dielectric alpha %.2f: %.5f (paths cut at depth 64: %.2g)\n", a, v, truncated);
  }
}

}  // namespace
}  // namespace envpis::render
