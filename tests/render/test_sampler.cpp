// SPDX-License-Identifier: Apache-2.0
// The renderer's pixel samplers: the Sobol generator against Boost's, the net property of the
// scrambled, shuffled pairs, determinism, and convergence through the library's warps.
#include <gtest/gtest.h>

#include <algorithm>
#include <boost/random/sobol.hpp>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "envpis/envpis.h"
#include "render/sampler.h"

namespace envpis::render {
namespace {

TEST(Sobol, MatricesReproduceBoostsSequence) {
  // Boost generates in Gray-code order and skips the origin; the first 2^m - 1 of its points plus the
  // origin are the first 2^m points in natural order. All kDimensions dimensions at once.
  const int D = sobol::kDimensions;
  for (int m : {4, 8, 12}) {
    boost::random::sobol_engine<std::uint32_t, 32> boost_gen(D);
    std::set<std::vector<std::uint32_t>> theirs{std::vector<std::uint32_t>(D, 0u)}, ours;
    for (std::uint32_t i = 0; i + 1 < (1u << m); ++i) {
      std::vector<std::uint32_t> p(D);
      for (auto& x : p) x = boost_gen();
      theirs.insert(p);
    }
    for (std::uint32_t i = 0; i < (1u << m); ++i) {
      std::vector<std::uint32_t> p(D);
      for (int d = 0; d < D; ++d) p[d] = sobol::sample_dim(i, d);
      ours.insert(p);
    }
    EXPECT_EQ(ours, theirs) << "m = " << m;
  }
  // Dimension 0 is van der Corput.
  for (std::uint32_t i = 0; i < 1000; ++i) EXPECT_EQ(sobol::sample_dim(i, 0), sobol::reverse_bits(i));
}

TEST(Sobol, TablesMatchTheColumnsForFullWordIndices) {
  // The shuffled indices the renderer uses have all 32 bits set at random; sample_dim reads them four
  // bits at a time from tables, which must equal the XOR of the generator matrix's columns.
  std::uint64_t state = 0x9e3779b97f4a7c15ULL;
  for (int n = 0; n < 20000; ++n) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const std::uint32_t i = static_cast<std::uint32_t>(state >> 32);
    const int d = n % sobol::kDimensions;
    const std::uint32_t* v = sobol::matrix(d);
    std::uint32_t expect = 0;
    for (int k = 0; k < 32; ++k)
      if (i & (1u << k)) expect ^= v[k];
    ASSERT_EQ(sobol::sample_dim(i, d), expect) << "index " << i << ", dimension " << d;
  }
  EXPECT_EQ(sobol::sample_dim(0xffffffffu, 0), 0xffffffffu);  // van der Corput of all ones
}

TEST(Sobol, ScrambledDimensionIsTheScrambleOfThePoint) {
  // scrambled_dim reads the points bit-reversed to save two reversals: it must equal the nested
  // uniform scramble of the plain point, bit for bit; reverse_bits must be an involution that
  // reverses (bit k to bit 31 - k).
  std::uint64_t state = 0x2545f4914f6cdd1dULL;
  for (int n = 0; n < 20000; ++n) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    const auto i = static_cast<std::uint32_t>(state >> 32), seed = static_cast<std::uint32_t>(state);
    const int d = n % sobol::kDimensions;
    ASSERT_EQ(sobol::scrambled_dim(sobol::nibble_tables(d), i, seed), sobol::nested_uniform_scramble(sobol::sample_dim(i, d), seed))
        << "index " << i << ", dimension " << d;
    ASSERT_EQ(sobol::reverse_bits(sobol::reverse_bits(i)), i);
  }
  for (int k = 0; k < 32; ++k) EXPECT_EQ(sobol::reverse_bits(1u << k), 1u << (31 - k));
}

TEST(Sobol, ScrambleAndShuffleAreBijectionsThatKeepBlocks) {
  // The shuffle maps each aligned block of 2^m indices onto one aligned block (the property that keeps
  // prefixes stratified); the scramble is a bijection.
  for (std::uint32_t seed : {1u, 0xdeadbeefu, 0x12345678u}) {
    for (int m : {3, 7}) {
      std::set<std::uint32_t> block;
      for (std::uint32_t i = 0; i < (1u << m); ++i) block.insert(sobol::nested_uniform_scramble(i, seed) >> m);
      EXPECT_EQ(block.size(), 1u) << "seed " << seed << " m " << m;
    }
    std::set<std::uint32_t> values;
    for (std::uint32_t i = 0; i < 4096; ++i) values.insert(sobol::nested_uniform_scramble(i << 20, seed));
    EXPECT_EQ(values.size(), 4096u);
  }
}

// A (t,m,2)-net: every elementary interval 2^-a x 2^-(m-t-a) holds exactly 2^t of the points.
bool is_net(const std::vector<Point2>& pts, int m, int t = 0) {
  for (int a = 0; a <= m - t; ++a) {
    const int nx = 1 << a, ny = 1 << (m - t - a);
    std::vector<int> count(static_cast<std::size_t>(nx) * ny, 0);
    for (const Point2& p : pts) {
      const int x = std::min(nx - 1, static_cast<int>(p.x * nx)), y = std::min(ny - 1, static_cast<int>(p.y * ny));
      if (++count[static_cast<std::size_t>(y) * nx + x] > (1 << t)) return false;
    }
  }
  return true;
}

// The smallest t for which the 2^m points are a (t,m,2)-net.
int net_quality(const std::vector<Point2>& pts, int m) {
  int t = 0;
  while (t < m && !is_net(pts, m, t)) ++t;
  return t;
}

std::vector<Point2> pixel_points(std::uint64_t seed, std::uint64_t pixel, std::uint32_t dim, std::uint32_t first,
                                 std::uint32_t count, SamplerKind kind = SamplerKind::Sobol) {
  std::vector<Point2> pts;
  for (std::uint32_t i = first; i < first + count; ++i) {
    PixelSampler s(kind, seed, pixel, i);
    s.set_dimension(dim);
    pts.push_back(s.next2d());
  }
  return pts;
}

TEST(PixelSampler, SobolPairsAreNetsForEveryPrefixAndBlock) {
  // Samples [k 2^m, (k+1) 2^m) of a pixel, several seeds and pixels: the pixel position (dimensions
  // 0, 1) and the padded pairs past the full sequence's dimensions are (0,m,2)-nets; the leading pairs
  // the integrator uses for the light and BSDF samples of the first vertices are (t,m,2)-nets with the
  // t of Joe and Kuo's numbers (scrambling and the block shuffle preserve it).
  for (std::uint32_t dim : {0u, 2u, 4u, 10u, 12u, 64u, 66u, 80u}) {
    for (int m = 0; m <= 10; ++m) {
      int t = 0;  // padded pairs: (0,2)-sequences
      if (dim < sobol::kDimensions) {
        std::vector<Point2> plain;
        for (std::uint32_t i = 0; i < (1u << m); ++i)
          plain.push_back({sobol::to_unit_float(sobol::sample_dim(i, int(dim))),
                           sobol::to_unit_float(sobol::sample_dim(i, int(dim) + 1))});
        t = net_quality(plain, m);
      }
      if (dim < 6) EXPECT_LE(t, 3) << "dim " << dim << " m " << m;  // vertex 0: light and BSDF pairs
      for (std::uint64_t seed : {0ull, 7ull})
        for (std::uint64_t pixel : {0ull, 1234ull})
          for (std::uint32_t k : {0u, 1u, 5u}) {
            const std::vector<Point2> pts = pixel_points(seed, pixel, dim, k << m, 1u << m);
            ASSERT_TRUE(is_net(pts, m, t)) << "seed " << seed << " pixel " << pixel << " dim " << dim << " m " << m
                                           << " block " << k;
          }
    }
  }
}

// Padded: every pair is a (0,2)-sequence, so vertex 0's light and BSDF samples are (0,m,2)-nets for
// every prefix and aligned block, where the full sequence's pairs at those dimensions have t up to 3
// (docs/sampling.md: what each costs where).
TEST(PixelSampler, PaddedPairsAreZeroNetsWhereTheFullSequencesAreNot) {
  const SamplerKind kind = SamplerKind::Padded;
  for (std::uint32_t dim : {0u, 2u, 4u, 10u, 12u, 64u})
    for (int m = 0; m <= 10; ++m)
      for (std::uint64_t seed : {0ull, 7ull})
        for (std::uint64_t pixel : {0ull, 1234ull})
          for (std::uint32_t k : {0u, 1u, 5u})
            ASSERT_TRUE(is_net(pixel_points(seed, pixel, dim, k << m, 1u << m, kind), m, 0))
                << "seed " << seed << " pixel " << pixel << " dim " << dim << " m " << m << " block " << k;
  // The full sequence at the light and BSDF pairs: not (0,m,2)-nets at some m <= 8.
  for (std::uint32_t dim : {2u, 4u}) {
    bool worse = false;
    for (int m = 1; m <= 8; ++m) worse = worse || !is_net(pixel_points(3, 5, dim, 0, 1u << m), m, 0);
    EXPECT_TRUE(worse) << "dim " << dim;
  }
  // Two pairs of one sample are decorrelated: each has its own scramble and index shuffle.
  PixelSampler s(kind, 1, 2, 3);
  const Point2 p = s.next2d(), q = s.next2d();
  EXPECT_NE(p.x, q.x);
}

TEST(PixelSampler, SobolIsStratifiedAcrossPairs) {
  // What padding alone cannot give: the pixel position and the light sample are stratified jointly.
  // Dimensions 0 and 2 (pixel x, light u) of 2^m samples are a net, as in the unscrambled sequence.
  for (int m = 2; m <= 10; ++m) {
    std::vector<Point2> pts;
    for (std::uint32_t i = 0; i < (1u << m); ++i) {
      PixelSampler s(SamplerKind::Sobol, 3, 5, i);
      const Point2 pixel = s.next2d(), light = s.next2d();
      pts.push_back({pixel.x, light.x});
    }
    std::vector<Point2> plain;
    for (std::uint32_t i = 0; i < (1u << m); ++i)
      plain.push_back({sobol::to_unit_float(sobol::sample_dim(i, 0)), sobol::to_unit_float(sobol::sample_dim(i, 2))});
    EXPECT_TRUE(is_net(pts, m, net_quality(plain, m))) << "m " << m;
    EXPECT_LE(net_quality(plain, m), 1) << "m " << m;
  }
}

TEST(PixelSampler, SobolSingleDimensionsAreStratified) {
  for (std::uint32_t dim : {6u, 7u, 14u}) {
    for (int m = 0; m <= 12; ++m) {
      std::vector<int> count(1u << m, 0);
      for (std::uint32_t i = 0; i < (1u << m); ++i) {
        PixelSampler s(SamplerKind::Sobol, 3, 99, i);
        s.set_dimension(dim);
        const float u = s.next1d();
        ASSERT_GE(u, 0.0f);
        ASSERT_LT(u, 1.0f);
        ++count[std::min((1u << m) - 1, static_cast<std::uint32_t>(u * float(1u << m)))];
      }
      for (int c : count) ASSERT_EQ(c, 1) << "dim " << dim << " m " << m;
    }
  }
}

TEST(PixelSampler, DeterministicAndDecorrelated) {
  for (SamplerKind kind : {SamplerKind::Sobol, SamplerKind::Padded, SamplerKind::Independent}) {
    PixelSampler a(kind, 7, 123, 4), b(kind, 7, 123, 4), c(kind, 7, 124, 4), d(kind, 8, 123, 4);
    for (int i = 0; i < 16; ++i) {
      const Point2 pa = a.next2d(), pb = b.next2d();
      EXPECT_EQ(pa.x, pb.x);
      EXPECT_EQ(pa.y, pb.y);
    }
    EXPECT_NE(c.next2d().x, PixelSampler(kind, 7, 123, 4).next2d().x);
    EXPECT_NE(d.next2d().x, PixelSampler(kind, 7, 123, 4).next2d().x);
    EXPECT_NE(PixelSampler(kind, 7, 123, 4).stream(0), PixelSampler(kind, 7, 123, 5).stream(0));
  }
  // Two pairs of one Sobol sample are not the same numbers (each pair has its own scramble).
  PixelSampler s(SamplerKind::Sobol, 1, 2, 3);
  const Point2 p = s.next2d(), q = s.next2d();
  EXPECT_NE(p.x, q.x);
}

TEST(PixelSampler, IndependentIsUniform) {
  double sum = 0, sum2 = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    PixelSampler s(SamplerKind::Independent, 5, 77, static_cast<std::uint64_t>(i));
    const float u = s.next1d();
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    sum += u;
    sum2 += double(u) * u;
  }
  // Mean 1/2 and variance 1/12: z-scores against their standard errors.
  const double mean = sum / n, var = sum2 / n - mean * mean;
  EXPECT_LT(std::fabs(mean - 0.5) / std::sqrt(1.0 / 12.0 / n), 4.0);
  EXPECT_LT(std::fabs(var - 1.0 / 12.0) / std::sqrt(1.0 / 180.0 / n), 4.0);
}

TEST(PixelSampler, ParsesItsNames) {
  EXPECT_EQ(parse_sampler("sobol"), SamplerKind::Sobol);
  EXPECT_EQ(parse_sampler("independent"), SamplerKind::Independent);
  EXPECT_EQ(parse_sampler("padded"), SamplerKind::Padded);
  EXPECT_STREQ(to_string(SamplerKind::Sobol), "sobol");
  EXPECT_STREQ(to_string(SamplerKind::Padded), "padded");
  EXPECT_STREQ(to_string(SamplerKind::Independent), "independent");
  EXPECT_THROW(parse_sampler("pmj"), Error);
}

// ---- convergence through the library's warps ----

// A smooth lat-long map (bilinear between texels that vary slowly).
EnvironmentMap smooth_map() {
  const int w = 64, h = 32;
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double th = kPi * (y + 0.5) / h, ph = 2 * kPi * (x + 0.5) / w;
      const double v = 1.0 + 0.6 * std::sin(th) * std::cos(ph) + 0.5 * std::cos(th) * std::cos(th);
      for (int c = 0; c < 3; ++c) rgb[(static_cast<std::size_t>(y) * w + x) * 3 + c] = static_cast<float>(v);
    }
  return EnvironmentMap::from_pixels(w, h, std::move(rgb));
}

// log-log slope of the variance over scrambles of the mean of f/p against the sample count.
template <class Sample>
double variance_slope(SamplerKind kind, const EnvironmentMap& map, Sample sample, Vec3 n) {
  const int scrambles = 48;
  const std::vector<int> counts{64, 256, 1024, 4096};
  std::vector<double> lx, ly;
  for (int count : counts) {
    double s1 = 0, s2 = 0;
    for (int r = 0; r < scrambles; ++r) {
      double acc = 0;
      for (int i = 0; i < count; ++i) {
        PixelSampler ps(kind, 1000 + static_cast<std::uint64_t>(r), 17, static_cast<std::uint64_t>(i));
        const DirectionSample d = sample(ps.next2d());
        if (!(d.pdf > 0)) continue;
        const double f = map.eval(d.direction).average() * (1.0 + 0.5 * dot(d.direction, n));
        acc += f / d.pdf;
      }
      const double est = acc / count;
      s1 += est;
      s2 += est * est;
    }
    const double mean = s1 / scrambles, var = (s2 - scrambles * mean * mean) / (scrambles - 1);
    lx.push_back(std::log(double(count)));
    ly.push_back(std::log(var / (mean * mean)));
  }
  // Least-squares slope.
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    mx += lx[i] / lx.size();
    my += ly[i] / ly.size();
  }
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < lx.size(); ++i) {
    sxy += (lx[i] - mx) * (ly[i] - my);
    sxx += (lx[i] - mx) * (lx[i] - mx);
  }
  return sxy / sxx;
}

TEST(SobolThroughWarps, EnvironmentAndProductSamplingKeepStratification) {
  // Stratified u must stay stratified directions through the table's row / cell / texel choices: the
  // relative variance then falls faster than 1/N on a smooth integrand. Independent numbers are the
  // control (slope -1), so the test can tell the two apart.
  const EnvironmentMap map = smooth_map();
  const ImportanceTable table(map);
  const Vec3 n = normalize(Vec3{0.3f, -0.5f, 0.8f});
  auto env = [&](Point2 u) { return table.sample(u); };
  ProductSampler product(table);
  BsdfProxy proxy;
  proxy.add_diffuse(0.5f);
  proxy.add_reflection(0.5f, 0.4f);
  ASSERT_TRUE(product.prepare(n, normalize(Vec3{0.0f, 0.6f, 0.8f}), proxy));
  auto prod = [&](Point2 u) { return product.sample(u); };

  const double env_sobol = variance_slope(SamplerKind::Sobol, map, env, n);
  const double env_indep = variance_slope(SamplerKind::Independent, map, env, n);
  const double prod_sobol = variance_slope(SamplerKind::Sobol, map, prod, n);
  const double prod_indep = variance_slope(SamplerKind::Independent, map, prod, n);
  EXPECT_LT(env_sobol, -1.2);
  EXPECT_LT(prod_sobol, -1.2);
  EXPECT_NEAR(env_indep, -1.0, 0.2);
  EXPECT_NEAR(prod_indep, -1.0, 0.2);
  RecordProperty("slopes", std::to_string(env_sobol) + " " + std::to_string(prod_sobol));
  std::printf("variance slope env: sobol %.3f independent %.3f; product: sobol %.3f independent %.3f\n", env_sobol,
              env_indep, prod_sobol, prod_indep);
}

}  // namespace
}  // namespace envpis::render
