// SPDX-License-Identifier: Apache-2.0
// Portals (issue 24): validation, the exact ray test, the cell fractions' guarantee, and the portal
// samplers (PortalEnvironmentSampler, ProductSampler with a PortalView): chi-square against their
// pdf, the pdf's integral, zero density where no portal is, the invalid cases, and that no view
// leaves the product bit-identical.
#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "chi2.h"
#include "test_util.h"

using namespace envpis;
using namespace envpis::test;

namespace {

// A quad centred at c with half-extents u and v; its normal u x v points out of the room.
Quad quad(Vec3 c, Vec3 u, Vec3 v) { return {{c - u - v, c + u - v, c + u + v, c - u + v}}; }

// The room: the box [-2, 2] x [-2, 2] x [0, 3], z up.
Quad east_window() { return quad({2, 0, 1.5f}, {0, 0.8f, 0}, {0, 0, 0.5f}); }
Quad skylight() { return quad({0, 0, 3}, {0.5f, 0, 0}, {0, 0.5f, 0}); }
Quad north_window() { return quad({0, 2, 1.2f}, {0, 0, 0.5f}, {0.6f, 0, 0}); }
// A window cut at an angle through the corner above (-2, -2): its normal is (-1, -1, 1) / sqrt 3.
Quad corner_window() {
  const Vec3 n = normalize(Vec3{-1, -1, 1}), u = normalize(Vec3{1, -1, 0}) * 0.4f;
  return quad({-1.7f, -1.7f, 2.6f}, u, cross(n, u) * (0.3f / length(cross(n, u))));
}

struct Scene {
  std::string label;
  std::vector<Quad> quads;
  Vec3 p, n;
};

// Points inside the room, portals at several orientations; every one sees some portal in front of
// its surface.
std::vector<Scene> scenes() {
  return {
      {"east window, floor", {east_window()}, {0, 0, 0.01f}, {0, 0, 1}},
      {"skylight, floor", {skylight()}, {0.5f, 0.3f, 0.5f}, {0, 0, 1}},
      {"north window, south wall", {north_window()}, {0, -1.99f, 1.5f}, {0, 1, 0}},
      {"corner window, tilted normal", {corner_window()}, {0.5f, 0.5f, 1}, normalize(Vec3{-1, -1, 1})},
      {"window partly behind the surface", {east_window()}, {0, 0, 1.5f}, {0, 0, 1}},
      {"window at a grazing angle", {east_window()}, {1.9f, -1.9f, 1.5f}, {0, 1, 0}},
      {"two portals", {east_window(), skylight()}, {-1, 0.5f, 0.8f}, {0, 0, 1}},
      {"four portals", {east_window(), skylight(), north_window(), corner_window()}, {0, 0, 1},
       normalize(Vec3{0.3f, 0.2f, 1})},
  };
}

BsdfProxy plastic() {
  BsdfProxy b;
  b.add_diffuse(0.6f);
  b.add_reflection(0.4f, 0.2f);
  return b;
}

std::shared_ptr<ImportanceTable> table(int subdivision) {
  ImportanceTableOptions o;
  o.subdivision = subdivision;
  return std::make_shared<ImportanceTable>(synthetic_sky(256, 128), o);
}

Chi2Options options(const ImportanceTable& t, std::uint64_t seed, int tests) {
  Chi2Options opt = table_aligned(t.fine_resolution());
  opt.samples = 100000;
  opt.seed = seed;
  opt.test_count = tests;
  return opt;
}

// The sampler's checks beside the chi-square: sample() only where pdf() agrees and V > 0.
template <class Sampler>
void check_samples(const Sampler& s, const PortalView& view, const std::string& label) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> U(0, 1);
  for (int i = 0; i < 4000; ++i) {
    const DirectionSample d = s.sample({U(rng), U(rng)});
    ASSERT_GT(d.pdf, 0.0f) << label;
    ASSERT_TRUE(std::isfinite(d.pdf)) << label;
    ASSERT_GT(view.cell_fraction(d.cell), 0.0f) << label;
    ASSERT_NEAR(s.pdf(d.direction), d.pdf, 1e-3f * d.pdf) << label;
  }
}

}  // namespace

TEST(Portals, RejectsBadQuadsWithAClearMessage) {
  auto message = [](const Quad& q) {
    try {
      Portals p({q});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  Quad nan = east_window();
  nan.v[2].y = std::nanf("");
  EXPECT_NE(message(nan).find("not finite"), std::string::npos) << message(nan);
  Quad repeated = east_window();
  repeated.v[1] = repeated.v[0];
  EXPECT_NE(message(repeated).find("degenerate"), std::string::npos) << message(repeated);
  const Quad collinear{{{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}}};
  EXPECT_NE(message(collinear).find("degenerate"), std::string::npos) << message(collinear);
  const Quad point{{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1}}};
  EXPECT_NE(message(point).find("degenerate"), std::string::npos) << message(point);
  Quad bent = east_window();
  bent.v[2].x += 0.3f;
  EXPECT_NE(message(bent).find("not planar"), std::string::npos) << message(bent);
  const Quad dart{{{0, 0, 0}, {2, 0, 0}, {0.5f, 0.5f, 0}, {0, 2, 0}}};
  EXPECT_NE(message(dart).find("not convex"), std::string::npos) << message(dart);
  const Quad bowtie{{{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}}};
  EXPECT_NE(message(bowtie).find("portal 0"), std::string::npos) << message(bowtie);
  Portals many;
  for (int i = 0; i < Portals::kMaxPortals; ++i) many.add(east_window());
  EXPECT_THROW(many.add(east_window()), Error);
  EXPECT_THROW(PortalView(*table(1), many, PortalViewOptions{PortalEstimate::Grid, 0}), Error);
  EXPECT_THROW(parse_portal_estimate("cones"), Error);
}

TEST(Portals, RayTestIsExactAndOneSided) {
  const Portals portals({east_window()});
  const Vec3 p{0, 0, 1.5f};
  EXPECT_NEAR(portals.normal(0).x, 1.0f, 1e-6f);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> U(-1, 1);
  for (int i = 0; i < 2000; ++i) {
    const float a = U(rng), b = U(rng);
    const Vec3 inside{2, 0.8f * a * 0.999f, 1.5f + 0.5f * b * 0.999f};
    const Vec3 outside{2, 0.8f * (1.001f + std::abs(a)) * (a < 0 ? -1 : 1), 1.5f + 0.5f * b};
    EXPECT_TRUE(portals.passes(p, inside - p));
    EXPECT_FALSE(portals.passes(p, p - inside));  // away from the window
    EXPECT_FALSE(portals.passes(p, outside - p));
    const Vec3 q{4, 0, 1.5f};  // outside the room: one-sided
    EXPECT_FALSE(portals.passes(q, inside - q));
  }
}

// V[c] = 0 only where no direction of the cell passes through a portal, on the top cells and the
// sub-cells, for both estimates.
TEST(Portals, CellFractionsAreZeroOnlyWhereNoPortalIs) {
  const auto t = table(4);
  std::mt19937_64 rng(11);
  for (PortalEstimate est : {PortalEstimate::Cone, PortalEstimate::Grid}) {
    for (const Scene& s : scenes()) {
      PortalView view(*t, Portals(s.quads), {est, 4});
      ASSERT_TRUE(view.prepare(s.p)) << s.label;
      int zero = 0, passing = 0;
      float sub[64];
      for (int i = 0; i < 20000; ++i) {
        const Vec3 d = random_direction(rng);
        const Point2 q = equal_area_sphere_to_square(d);
        const int c = t->cell_of(q), S = t->subdivision(), TS = t->top_resolution() * S;
        const int s_ = (std::min(TS - 1, int(q.y * TS)) % S) * S + std::min(TS - 1, int(q.x * TS)) % S;
        view.subcell_fractions(c, sub);
        const bool through = view.passes(d);
        passing += through;
        if (view.cell_fraction(c) == 0.0f) ++zero;
        if (through) {
          ASSERT_GT(view.cell_fraction(c), 0.0f) << s.label << " " << to_string(est);
          ASSERT_GT(sub[s_], 0.0f) << s.label << " " << to_string(est);
        }
      }
      EXPECT_GT(zero, 10000) << s.label;  // most cells see no portal
      EXPECT_GT(passing, 0) << s.label;
    }
  }
}

// The top cells' and the sub-cells' pass run in the kernel of PortalViewOptions::simd: every
// instruction set this CPU runs gives the scalar reference's fractions (up to FMA round-off) and keeps
// V > 0 wherever a direction passes a portal.
TEST(Portals, EverySimdGivesTheScalarFractions) {
  std::mt19937_64 rng(12);
  for (int S : {1, 3, 8}) {  // sub-cells padded to 16 lanes (S = 3) and four vectors of them (S = 8)
    const auto t = table(S);
    for (Simd simd : {Simd::SSE2, Simd::AVX2, Simd::AVX512}) {
      if (!simd_supported(simd)) continue;
      for (const Scene& s : scenes()) {
        const std::string label = s.label + " S=" + std::to_string(S) + " " + to_string(simd);
        PortalView ref(*t, Portals(s.quads), {PortalEstimate::Cone, 4, Simd::Scalar});
        PortalView view(*t, Portals(s.quads), {PortalEstimate::Cone, 4, simd});
        ASSERT_EQ(ref.prepare(s.p), view.prepare(s.p)) << label;
        float a[64], b[64];
        for (int c = 0; c < t->cell_count(); ++c) {
          ASSERT_NEAR(view.cell_fraction(c), ref.cell_fraction(c), 1e-4f) << label;
          ASSERT_EQ(view.cell_fraction(c) > 0.0f, ref.cell_fraction(c) > 0.0f) << label;
          ASSERT_EQ(view.subcell_fractions(c, a), ref.subcell_fractions(c, b)) << label;
          for (int k = 0; k < S * S; ++k) {
            ASSERT_NEAR(a[k], b[k], 1e-4f) << label << " cell " << c << " sub-cell " << k;
            ASSERT_EQ(a[k] > 0.0f, b[k] > 0.0f) << label << " cell " << c << " sub-cell " << k;
          }
        }
        for (int i = 0; i < 5000; ++i) {
          const Vec3 d = random_direction(rng);
          if (view.passes(d)) ASSERT_GT(view.cell_fraction(t->cell_of(equal_area_sphere_to_square(d))), 0.0f);
        }
      }
    }
  }
}

TEST(Portals, EnvironmentSamplerChiSquareAndIntegral) {
  const auto tables = {table(1), table(4)};
  int k = 0, tests = 2 * 2 * int(scenes().size());
  for (const auto& t : tables)
    for (PortalEstimate est : {PortalEstimate::Cone, PortalEstimate::Grid})
      for (const Scene& s : scenes()) {
        const std::string label = s.label + " S=" + std::to_string(t->subdivision()) + " " + to_string(est);
        PortalView view(*t, Portals(s.quads), {est, 4});
        ASSERT_TRUE(view.prepare(s.p)) << label;
        PortalEnvironmentSampler env(*t);
        ASSERT_TRUE(env.prepare(view)) << label;
        check_samples(env, view, label);
        const Chi2Result r = sampler_chi2(env, options(*t, 500 + k++, tests));
        EXPECT_TRUE(r.passed) << label << ": " << r.message;
        EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3) << label;
      }
}

// The product through portals on three set-ups: the paper's one level (S = 1); the refined product
// (S = 4, refine_cells 4); the unrefined product on the S = 4 table (the sub-cell level is then the
// portal-masked environment's) with the moments estimate and a defensive mixture.
TEST(Portals, ProductSamplerChiSquareAndIntegral) {
  struct Setup {
    std::shared_ptr<ImportanceTable> table;
    ProductSamplerOptions options;
    std::string label;
  };
  std::vector<Setup> setups(3);
  setups[0] = {table(1), {}, "S=1"};
  setups[1] = {table(4), {}, "S=4 refined"};
  setups[1].options.refine = true;
  setups[1].options.refine_cells = 4;
  setups[2] = {setups[1].table, {}, "S=4 unrefined, moments, env_mix 0.1"};
  setups[2].options.cell_estimate = CellEstimate::Moments;
  setups[2].options.env_mix = 0.1f;
  int k = 0, tests = 3 * 2 * int(scenes().size());
  for (const Setup& u : setups)
    for (PortalEstimate est : {PortalEstimate::Cone, PortalEstimate::Grid})
      for (const Scene& s : scenes()) {
        const ImportanceTable& t = *u.table;
        const std::string label = s.label + " " + u.label + " " + to_string(est);
        PortalView view(t, Portals(s.quads), {est, 4});
        ASSERT_TRUE(view.prepare(s.p)) << label;
        ProductSampler ps(t, u.options);
        const Vec3 wo = normalize(s.n + Vec3{0.3f, -0.2f, 0.1f});
        ASSERT_TRUE(ps.prepare(s.n, wo, plastic(), &view)) << label;
        check_samples(ps, view, label);
        const Chi2Result r = sampler_chi2(ps, options(t, 900 + k++, tests));
        EXPECT_TRUE(r.passed) << label << ": " << r.message;
        EXPECT_NEAR(r.pdf_integral, 1.0, 2e-3) << label;
      }
}

// A Monte Carlo integral of the pdf over the sphere (uniform directions), apart from the chi-square's
// midpoint rule; and pdf 0 wherever V = 0 (there no direction passes through a portal).
TEST(Portals, PdfIntegratesToOneAndIsZeroWhereNoPortalIs) {
  const auto t = table(4);
  std::mt19937_64 rng(5);
  for (const Scene& s : scenes()) {
    PortalView view(*t, Portals(s.quads));
    ASSERT_TRUE(view.prepare(s.p));
    PortalEnvironmentSampler env(*t);
    ProductSamplerOptions o;
    o.refine = true;
    ProductSampler ps(*t, o);
    ASSERT_TRUE(env.prepare(view));
    ASSERT_TRUE(ps.prepare(s.n, s.n, plastic(), &view));
    const int n = 400000;
    double sum_env = 0, sum_ps = 0, sq_env = 0, sq_ps = 0;
    for (int i = 0; i < n; ++i) {
      const Vec3 d = random_direction(rng);
      const double pe = env.pdf(d) * 4 * M_PI, pp = ps.pdf(d) * 4 * M_PI;
      sum_env += pe, sq_env += pe * pe, sum_ps += pp, sq_ps += pp * pp;
      if (view.cell_fraction(t->cell_of_direction(d)) == 0.0f) {
        ASSERT_EQ(env.pdf(d), 0.0f) << s.label;
        ASSERT_EQ(ps.pdf(d), 0.0f) << s.label;
        ASSERT_FALSE(view.passes(d)) << s.label;
      }
    }
    const double me = sum_env / n, mp = sum_ps / n;
    const double se = std::sqrt((sq_env / n - me * me) / n), sp = std::sqrt((sq_ps / n - mp * mp) / n);
    EXPECT_NEAR(me, 1.0, 4 * se + 1e-3) << s.label;
    EXPECT_NEAR(mp, 1.0, 4 * sp + 1e-3) << s.label;
  }
}

// No sample, pdf 0 everywhere, never NaN: a point outside the room (portals are one-sided), a NaN
// point, and for the product every portal behind an opaque surface.
TEST(Portals, InvalidCasesHaveNoSample) {
  const auto t = table(4);
  std::mt19937_64 rng(9);
  auto nothing = [&](const auto& sampler, const std::string& label) {
    for (int i = 0; i < 1000; ++i) {
      const DirectionSample d = sampler.sample({0.001f * i, 0.5f});
      EXPECT_EQ(d.pdf, 0.0f) << label;
      const float p = sampler.pdf(random_direction(rng));
      EXPECT_EQ(p, 0.0f) << label;
    }
  };
  ProductSamplerOptions o;
  o.refine = true;
  PortalEnvironmentSampler env(*t);
  ProductSampler ps(*t, o);
  PortalView view(*t, Portals({east_window()}));
  for (Vec3 p : {Vec3{4, 0, 1.5f}, Vec3{std::nanf(""), 0, 1}, Vec3{2, 0, 1.5f}}) {
    EXPECT_FALSE(view.prepare(p));
    EXPECT_FALSE(env.prepare(view));
    EXPECT_FALSE(ps.prepare({0, 0, 1}, {0, 0, 1}, plastic(), &view));
    nothing(env, "outside");
    nothing(ps, "outside");
  }
  PortalView empty(*t, Portals{});
  EXPECT_FALSE(empty.prepare({0, 0, 1}));
  // Inside, facing away from the only window: the environment sampler samples it, the product not.
  ASSERT_TRUE(view.prepare({1.5f, 0, 1.5f}));
  EXPECT_TRUE(env.prepare(view));
  EXPECT_FALSE(ps.prepare({-1, 0, 0}, {-1, 0.2f, 0}, plastic(), &view));
  nothing(ps, "behind the surface");
}

// Without a view the product is the product: the same cells, samples and pdfs, bit for bit.
TEST(Portals, NoViewIsBitIdentical) {
  for (int S : {1, 4}) {
    const auto t = table(S);
    ProductSamplerOptions o;
    o.refine = S > 1;
    ProductSampler a(*t, o), b(*t, o);
    PortalView view(*t, Portals({east_window()}));
    ASSERT_TRUE(view.prepare({0, 0, 1}));
    std::mt19937_64 rng(13);
    std::uniform_real_distribution<float> U(0, 1);
    for (int i = 0; i < 50; ++i) {
      const Vec3 n = random_direction(rng), wo = normalize(n + random_direction(rng) * 0.5f);
      ASSERT_TRUE(a.prepare(n, wo, plastic()));
      b.prepare(n, wo, plastic(), &view);  // the same sampler used with a view in between
      ASSERT_TRUE(b.prepare(n, wo, plastic(), nullptr));
      for (int c = 0; c < t->cell_count(); ++c) ASSERT_EQ(a.cell_probability(c), b.cell_probability(c));
      for (int j = 0; j < 20; ++j) {
        const Point2 u{U(rng), U(rng)};
        const DirectionSample sa = a.sample(u), sb = b.sample(u);
        ASSERT_EQ(sa.pdf, sb.pdf);
        ASSERT_EQ(sa.direction.x, sb.direction.x);
        ASSERT_EQ(a.pdf(sa.direction), b.pdf(sa.direction));
      }
    }
  }
}

// How many light samples pass through a portal: the figure portals are for (printed; docs/portals.md).
TEST(Portals, MostPortalSamplesPassThroughAPortal) {
  const auto t = table(4);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<float> U(0, 1);
  for (PortalEstimate est : {PortalEstimate::Cone, PortalEstimate::Grid}) {
    double share[4] = {0, 0, 0, 0};
    for (const Scene& s : scenes()) {
      PortalView view(*t, Portals(s.quads), {est, 4});
      ASSERT_TRUE(view.prepare(s.p));
      PortalEnvironmentSampler env(*t);
      ProductSamplerOptions o;
      o.refine = true;
      ProductSampler ps(*t, o), plain(*t, o);
      ASSERT_TRUE(env.prepare(view));
      ASSERT_TRUE(ps.prepare(s.n, s.n, plastic(), &view));
      ASSERT_TRUE(plain.prepare(s.n, s.n, plastic()));
      const int n = 20000;
      for (int i = 0; i < n; ++i) {
        const Point2 u{U(rng), U(rng)};
        share[0] += view.passes(t->sample(u).direction) / double(n);
        share[1] += view.passes(plain.sample(u).direction) / double(n);
        share[2] += view.passes(env.sample(u).direction) / double(n);
        share[3] += view.passes(ps.sample(u).direction) / double(n);
      }
    }
    const double k = double(scenes().size());
    std::printf("%s: samples through a portal, mean over %d scenes: env %.3f, product %.3f, env+portals %.3f, "
                "product+portals %.3f\n", to_string(est), int(k), share[0] / k, share[1] / k, share[2] / k,
                share[3] / k);
    EXPECT_GT(share[2], 10 * share[0]);
    EXPECT_GT(share[3], 10 * share[1]);
    EXPECT_GT(share[3] / k, 0.4);
  }
}

// No bias: direct lighting at a point in the room (a diffuse floor, the environment seen only through
// the windows), estimated with MIS (power heuristic) of a light sampler and cosine BSDF sampling, the
// light sampler being the plain product, the product through the windows, the product through a
// portal covering only half of the east window (the other half is then BSDF samples' alone), and the
// environment through the windows. Every estimate must agree with the plain product's (z < 4).
TEST(Portals, MisEstimatesAgreeWithAndWithoutPortals) {
  const EnvironmentMap map = synthetic_sky(256, 128);
  ImportanceTableOptions to;
  to.subdivision = 4;
  const ImportanceTable t(map, to);
  const Portals windows({east_window(), skylight()});
  const Quad east = east_window();
  const Quad half{{east.v[0], (east.v[0] + east.v[1]) * 0.5f, (east.v[3] + east.v[2]) * 0.5f, east.v[3]}};
  const Portals half_window({half, skylight()});
  const Vec3 p{-1, 0.5f, 0.3f}, n{0, 0, 1};
  BsdfProxy diffuse;
  diffuse.add_diffuse(1);
  ProductSamplerOptions o;
  o.refine = true;
  auto radiance = [&](Vec3 d) { return windows.passes(p, d) ? double(map.eval(d).average()) : 0.0; };
  // One strategy's mean and variance of the MIS estimate over `count` pairs of samples.
  auto estimate = [&](const auto& light, std::uint64_t seed, double& mean, double& var) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> U(0, 1);
    const int count = 200000;
    double sum = 0, sq = 0;
    for (int i = 0; i < count; ++i) {
      double f = 0;
      const DirectionSample s = light.sample({U(rng), U(rng)});
      if (s.pdf > 0) {
        const float cos = std::max(0.0f, dot(s.direction, n)), pb = cos * kInvPi;
        if (cos > 0) f += radiance(s.direction) * (cos * kInvPi) / s.pdf * power_heuristic(1, s.pdf, 1, pb);
      }
      const float r = std::sqrt(U(rng)), phi = 2 * kPi * U(rng);  // cosine-weighted about +z
      const Vec3 d{r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - r * r))};
      const float pb = d.z * kInvPi;
      if (pb > 0) f += radiance(d) * (d.z * kInvPi) / pb * power_heuristic(1, pb, 1, light.pdf(d));
      sum += f, sq += f * f;
    }
    mean = sum / count;
    var = (sq / count - mean * mean) / count;
  };
  ProductSampler plain(t, o), through(t, o), through_half(t, o);
  PortalEnvironmentSampler env(t);
  PortalView view(t, windows), view_half(t, half_window);
  ASSERT_TRUE(view.prepare(p));
  ASSERT_TRUE(view_half.prepare(p));
  ASSERT_TRUE(plain.prepare(n, n, diffuse));
  ASSERT_TRUE(through.prepare(n, n, diffuse, &view));
  ASSERT_TRUE(through_half.prepare(n, n, diffuse, &view_half));
  ASSERT_TRUE(env.prepare(view));
  double m0, v0, m, v;
  estimate(plain, 1, m0, v0);
  ASSERT_GT(m0, 0.0);
  int k = 2;
  for (const auto& [label, mean_var] :
       {std::pair<const char*, int>{"product through the windows", 0}, {"product through half a window", 1},
        {"environment through the windows", 2}}) {
    if (mean_var == 0) estimate(through, k++, m, v);
    if (mean_var == 1) estimate(through_half, k++, m, v);
    if (mean_var == 2) estimate(env, k++, m, v);
    const double z = (m - m0) / std::sqrt(v + v0);
    std::printf("%s: %.5f +- %.5f against the plain product's %.5f +- %.5f (z = %.2f, variance ratio %.2f)\n",
                label, m, std::sqrt(v), m0, std::sqrt(v0), z, v0 / v);
    EXPECT_LT(std::abs(z), 4.0) << label;
    if (mean_var == 0) EXPECT_GT(v0 / v, 4.0) << label;  // and the portals pay: measured 24.9
  }
}
