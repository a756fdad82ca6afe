// Shared chi-square goodness-of-fit harness for direction samplers (after Mitsuba 3's chi2 test).
//
// Bins are a B x B grid on Clarberg's equal-area square, so every bin subtends the same solid angle.
// The expected count of a bin is N times the integral of the sampler's pdf over it (midpoint rule on
// an R x R sub-grid per bin: exact when the pdf is piecewise constant on a grid aligned with it).
// Failed draws (no direction) form one more bin whose expected count is N (1 - integral of the pdf).
// Bins with expected count below 5 are pooled. The test fails when a sample lands in a bin whose
// integrated pdf is exactly zero, or when the p-value is below the Sidak-corrected significance.
#pragma once

#include <boost/math/distributions/chi_squared.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "envpis/equal_area.h"

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

/// sample(u1, u2) returns a direction, or nullopt for a failed draw. pdf(direction) is per solid angle.
inline Chi2Result chi2_test(const std::function<std::optional<Vec3>(float, float)>& sample,
                            const std::function<double(Vec3)>& pdf, const Chi2Options& opt = {}) {
  const int B = opt.bins, R = opt.sub;
  const std::size_t nb = static_cast<std::size_t>(B) * B;
  std::vector<double> expected(nb + 1, 0.0), observed(nb + 1, 0.0);
  // Integrate the pdf: each bin has solid angle 4 pi / B^2; each sub-cell 4 pi / (B R)^2.
  const double sub_sr = 4.0 * M_PI / (double(B) * R * double(B) * R);
  double integral = 0;
  for (int by = 0; by < B; ++by)
    for (int bx = 0; bx < B; ++bx) {
      double acc = 0;
      for (int j = 0; j < R; ++j)
        for (int i = 0; i < R; ++i) {
          const Point2 p{float((bx * R + i + 0.5) / (double(B) * R)), float((by * R + j + 0.5) / (double(B) * R))};
          acc += pdf(equal_area_square_to_sphere(p)) * sub_sr;
        }
      expected[by * B + bx] = acc * opt.samples;
      integral += acc;
    }
  expected[nb] = std::max(0.0, 1.0 - integral) * opt.samples;

  std::mt19937_64 rng(opt.seed);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  for (std::size_t k = 0; k < opt.samples; ++k) {
    const float u1 = U(rng), u2 = U(rng);
    const auto d = sample(u1, u2);
    if (!d) {
      observed[nb] += 1;
      continue;
    }
    const Point2 p = equal_area_sphere_to_square(*d);
    const int bx = std::min(B - 1, int(p.x * B)), by = std::min(B - 1, int(p.y * B));
    observed[by * B + bx] += 1;
  }

  Chi2Result r;
  r.pdf_integral = integral;
  std::ostringstream msg;
  // Samples where the pdf integrates to zero: a hard failure.
  for (std::size_t i = 0; i < nb + 1; ++i)
    if (expected[i] == 0 && observed[i] > 0) {
      msg << "samples landed in bin " << i << " where the pdf is zero (" << observed[i] << " samples)";
      r.message = msg.str();
      return r;
    }
  // Pool low-expectation bins.
  double stat = 0, pool_e = 0, pool_o = 0;
  int used = 0;
  for (std::size_t i = 0; i < nb + 1; ++i) {
    if (expected[i] < 5) {
      pool_e += expected[i];
      pool_o += observed[i];
      continue;
    }
    const double d = observed[i] - expected[i];
    stat += d * d / expected[i];
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
      << "), pdf integral " << integral;
  r.message = msg.str();
  return r;
}

}  // namespace envpis::test
