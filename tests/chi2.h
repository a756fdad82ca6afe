// SPDX-License-Identifier: Apache-2.0
// Shared chi-square goodness-of-fit harness for direction samplers (after Mitsuba 3's chi2 test).
//
// Bins are a B x B grid on Clarberg's equal-area square, so every bin subtends the same solid angle.
// The expected count of a bin is N times the integral of the sampler's pdf over it (midpoint rule on
// an R x R sub-grid per bin: exact when the pdf is piecewise constant on a grid aligned with it).
// Failed draws (no direction) form one more bin whose expected count is N (1 - integral of the pdf).
// Bins with expected count below 5 are pooled. The test fails when a sample lands in a bin whose
// integrated pdf is exactly zero, or when the p-value is below the Sidak-corrected significance.
//
// A failing test writes its histograms as B x B PFM images (one float per bin; top row = the square's
// y = 0) under <build>/Testing/chi2: NAME-observed.pfm, NAME-expected.pfm and NAME-residual.pfm
// ((observed - expected) / sqrt(expected)), NAME from the running GoogleTest test. The failure
// message names them.
#pragma once

#include <boost/math/distributions/chi_squared.hpp>
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "envpis/envpis.h"

namespace envpis::test {

struct Chi2Result {
  bool passed = false;
  double p_value = 0;
  double statistic = 0;
  int dof = 0;
  double pdf_integral = 0;  ///< integral of the pdf over the sphere
  std::string message;
};

struct Chi2Options {
  int bins = 32;              ///< B: B x B bins
  int sub = 8;                ///< R: midpoint sub-grid per bin axis for integrating the pdf
  std::size_t samples = 200000;
  double significance = 0.01; ///< family-wise level
  int test_count = 1;         ///< number of tests in the family (Sidak correction)
  std::uint64_t seed = 1;
};

/// Largest divisor of n that is <= cap: a bin grid aligned with a table of n x n texels, so that the
/// midpoint integration of a pdf that is constant on each texel is exact.
inline int aligned_bins(int n, int cap = 64) {
  for (int b = cap; b > 1; --b)
    if (n % b == 0) return b;
  return 1;
}

/// Options whose bins are aligned with an n x n table and whose sub-grid reaches its texels.
inline Chi2Options table_aligned(int n) {
  Chi2Options opt;
  opt.bins = aligned_bins(n);
  opt.sub = n / opt.bins;
  return opt;
}

namespace chi2_detail {

/// B x B + 1 bins (the last: failed draws).
struct Histograms {
  int B = 0;
  std::vector<double> expected, observed;
  double integral = 0;
};

inline void integrate_expected(Histograms& h, const std::function<double(Vec3)>& pdf, const Chi2Options& opt) {
  const int B = opt.bins, R = opt.sub;
  const std::size_t nb = static_cast<std::size_t>(B) * B;
  // Each bin has solid angle 4 pi / B^2; each sub-cell 4 pi / (B R)^2.
  const double sub_sr = 4.0 * M_PI / (double(B) * R * double(B) * R);
  for (int by = 0; by < B; ++by)
    for (int bx = 0; bx < B; ++bx) {
      double acc = 0;
      for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) {
          const Point2 p{float((bx * R + i + 0.5) / (double(B) * R)), float((by * R + j + 0.5) / (double(B) * R))};
          acc += pdf(equal_area_square_to_sphere(p)) * sub_sr;
        }
      h.expected[by * B + bx] = acc * opt.samples;
      h.integral += acc;
    }
  h.expected[nb] = std::max(0.0, 1.0 - h.integral) * opt.samples;
}

inline void draw_observed(Histograms& h, const std::function<std::optional<Vec3>(float, float)>& sample,
                          const Chi2Options& opt) {
  const int B = opt.bins;
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  for (std::size_t k = 0; k < opt.samples; ++k) {
    const float u1 = U(rng), u2 = U(rng);
    const auto d = sample(u1, u2);
    if (!d) {
      h.observed[std::size_t(B) * B] += 1;
      continue;
    }
    const Point2 p = equal_area_sphere_to_square(*d);
    const int bx = std::min(B - 1, int(p.x * B)), by = std::min(B - 1, int(p.y * B));
    h.observed[by * B + bx] += 1;
  }
}

/// The statistic and p-value, or a failure message for samples where the pdf is zero.
inline Chi2Result evaluate(const Histograms& h, const Chi2Options& opt) {
  const std::size_t n = h.expected.size();
  Chi2Result r;
  r.pdf_integral = h.integral;
  std::ostringstream msg;
  for (std::size_t i = 0; i < n; ++i)
    if (h.expected[i] == 0 && h.observed[i] > 0) {
      msg << "samples landed in bin " << i << " where the pdf is zero (" << h.observed[i] << " samples)";
      r.message = msg.str();
      return r;
    }
  // Pool low-expectation bins.
  double stat = 0, pool_e = 0, pool_o = 0;
  int used = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (h.expected[i] < 5) {
      pool_e += h.expected[i];
      pool_o += h.observed[i];
      continue;
    }
    const double d = h.observed[i] - h.expected[i];
    stat += d * d / h.expected[i];
    ++used;
  }
  if (pool_e > 0) {
    if (pool_e < 5 && used > 0) {
      // still too small to be its own bin: its deviation counts only if grossly off
      if (pool_o > 5 * pool_e + 20) {
        msg << "pooled low-expectation bins got " << pool_o << " samples, expected " << pool_e;
        r.message = msg.str();
        return r;
      }
    } else {
      const double d = pool_o - pool_e;
      stat += d * d / pool_e;
      ++used;
    }
  }
  r.statistic = stat;
  r.dof = std::max(1, used - 1);
  boost::math::chi_squared_distribution<double> dist(r.dof);
  r.p_value = boost::math::cdf(boost::math::complement(dist, stat));
  const double alpha = 1.0 - std::pow(1.0 - opt.significance, 1.0 / std::max(1, opt.test_count));
  r.passed = r.p_value >= alpha;
  msg << "chi2=" << stat << " dof=" << r.dof << " p=" << r.p_value << " (threshold " << alpha
      << "), pdf integral " << h.integral;
  r.message = msg.str();
  return r;
}

/// A B x B greyscale PFM (rows bottom to top, as the format has it, so the square's y = 0 is on top).
inline bool write_pfm(const std::filesystem::path& path, int B, const std::vector<float>& v) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  std::fprintf(f, "Pf\n%d %d\n-1.0\n", B, B);  // negative scale: little-endian
  for (int y = B - 1; y >= 0; --y) std::fwrite(&v[std::size_t(y) * B], sizeof(float), std::size_t(B), f);
  return std::fclose(f) == 0;
}

/// NAME for the files of the running test: Suite.Test, made file-safe, with a counter from the second
/// failing chi-square test of the same test on.
inline std::string dump_name() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = info ? std::string(info->test_suite_name()) + "." + info->name() : std::string("chi2");
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '-') c = '_';
  static std::map<std::string, int> seen;
  const int k = seen[name]++;
  return k == 0 ? name : name + "-" + std::to_string(k);
}

/// Writes the histograms; returns the text to add to the failure message.
inline std::string dump(const Histograms& h) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(ENVPIS_TEST_OUTPUT_DIR) / "chi2";
  std::error_code ec;
  fs::create_directories(dir, ec);
  const std::string base = (dir / dump_name()).string();
  const std::size_t nb = std::size_t(h.B) * h.B;
  std::vector<float> obs(nb), exp(nb), res(nb);
  for (std::size_t i = 0; i < nb; ++i) {
    obs[i] = float(h.observed[i]);
    exp[i] = float(h.expected[i]);
    res[i] = h.expected[i] > 0 ? float((h.observed[i] - h.expected[i]) / std::sqrt(h.expected[i]))
                               : (h.observed[i] > 0 ? INFINITY : 0.0f);
  }
  const bool ok = write_pfm(base + "-observed.pfm", h.B, obs) && write_pfm(base + "-expected.pfm", h.B, exp) &&
                  write_pfm(base + "-residual.pfm", h.B, res);
  std::ostringstream msg;
  msg << "; failed draws " << h.observed[nb] << " (expected " << h.expected[nb] << "); histograms "
      << (ok ? "" : "NOT written: ") << base << "-{observed,expected,residual}.pfm";
  return msg.str();
}

}  // namespace chi2_detail

/// sample(u1, u2) returns a direction, or nullopt for a failed draw. pdf(direction) is per solid angle.
inline Chi2Result chi2_test(const std::function<std::optional<Vec3>(float, float)>& sample,
                            const std::function<double(Vec3)>& pdf, const Chi2Options& opt = {}) {
  chi2_detail::Histograms h;
  h.B = opt.bins;
  h.expected.assign(std::size_t(opt.bins) * opt.bins + 1, 0.0);
  h.observed = h.expected;
  chi2_detail::integrate_expected(h, pdf, opt);
  chi2_detail::draw_observed(h, sample, opt);
  Chi2Result r = chi2_detail::evaluate(h, opt);
  if (!r.passed) r.message += chi2_detail::dump(h);
  return r;
}

/// The test of a direction sampler: anything with sample(Point2) -> DirectionSample (a pdf of 0 is a
/// failed draw) and pdf(Vec3) per solid angle (ImportanceTable, ProductSampler, ...).
template <class Sampler>
Chi2Result sampler_chi2(const Sampler& sampler, const Chi2Options& opt) {
  return chi2_test(
      [&](float u1, float u2) -> std::optional<Vec3> {
        const DirectionSample s = sampler.sample({u1, u2});
        if (s.pdf <= 0) return std::nullopt;
        return s.direction;
      },
      [&](Vec3 d) { return double(sampler.pdf(d)); }, opt);
}


/// The test of a sampler whose density is constant over each texel of a w x h lat-long map (an
/// ImportanceTable with FineTexels::Map and the samplers on it): one bin per map texel, its expected
/// count exactly N pdf(texel centre) times the texel's solid angle. texel(d) is the map's texel of
/// direction d (row-major index), centre(t) the world direction of texel t's centre.
inline Chi2Result texel_chi2(const std::function<std::optional<Vec3>(float, float)>& sample,
                             const std::function<double(Vec3)>& pdf, int w, int h,
                             const std::function<std::size_t(Vec3)>& texel,
                             const std::function<Vec3(std::size_t)>& centre, const Chi2Options& opt = {}) {
  chi2_detail::Histograms hist;
  const std::size_t n = static_cast<std::size_t>(w) * h;
  hist.expected.assign(n + 1, 0.0);
  hist.observed = hist.expected;
  for (std::size_t t = 0; t < n; ++t) {
    const int y = static_cast<int>(t / w);
    const double sr = 2.0 * M_PI / w * (std::cos(M_PI * y / h) - std::cos(M_PI * (y + 1) / h));
    const double mass = pdf(centre(t)) * sr;
    hist.expected[t] = mass * opt.samples;
    hist.integral += mass;
  }
  hist.expected[n] = std::max(0.0, 1.0 - hist.integral) * opt.samples;
  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  for (std::size_t k = 0; k < opt.samples; ++k) {
    const float u1 = U(rng), u2 = U(rng);
    const auto d = sample(u1, u2);
    hist.observed[d ? texel(*d) : n] += 1;
  }
  return chi2_detail::evaluate(hist, opt);
}

}  // namespace envpis::test
