// SPDX-License-Identifier: Apache-2.0
#include "render/analyzer_sums.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace envpis::render::analyzer_detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline double channel(Rgb c, int k) { return k == 0 ? c.r : (k == 1 ? c.g : c.b); }
}  // namespace

TexelSplits texel_splits(int n, const std::vector<int>& levels) {
  TexelSplits out;
  for (int t : levels) {
    out.emplace_back();
    for (int x = 0; x < n; ++x) out.back().push_back(split(double(x) / n, 1.0 / n, t));
  }
  return out;
}

/// Adds a batch to the sums, one running sum at a time over a chunk of points (each strategy's sums
/// stay in registers): every sum gets the same terms in the same order as point by point.
void accumulate(const Batch& b, const AnalyzerOptions& o, const std::vector<int>& distribution, Sums& s) {
  constexpr std::size_t kChunk = 64;
  const bool power = o.heuristic == Heuristic::Power;
  double f[kChunk][3], f2[kChunk][3], w[kChunk], w_over_pb[kChunk];
  double w_over_pl[kChunk][kMaxDistributions];  // w / p per density, one division each (0 where p is 0)
  for (std::size_t j0 = 0; j0 < b.count; j0 += kChunk) {
    const std::size_t m = std::min(kChunk, b.count - j0);
    const DirectionValues* v = b.v + j0;
    for (std::size_t j = 0; j < m; ++j) {
      w[j] = b.q ? b.q[j0 + j].w : b.texel_area;
      for (int c = 0; c < 3; ++c) {
        f[j][c] = channel(v[j].f, c);
        f2[j][c] = f[j][c] * f[j][c];
        s.integral[c] += w[j] * f[j][c];
      }
      s.integral_blind += w[j] * v[j].f_blind;
      for (std::size_t k = 0; k < kMaxDistributions; ++k)
        w_over_pl[j][k] = v[j].p_light[k] > 0 ? w[j] / double(v[j].p_light[k]) : 0.0;
      w_over_pb[j] = v[j].p_bsdf > 0 ? w[j] / double(v[j].p_bsdf) : 0.0;
    }
    for (std::size_t i = 0; i < o.strategies.size(); ++i) {
      const Strategy st = o.strategies[i];
      const int k = distribution[i];
      StrategySums& ss = s.strategies[i];
      std::array<double, 3> a_light = ss.a_light, a_bsdf = ss.a_bsdf, b_light = ss.b_light, b_bsdf = ss.b_bsdf;
      for (std::size_t j = 0; j < m; ++j) {
        const float pl = k >= 0 ? v[j].p_light[static_cast<std::size_t>(k)] : 0.0f, pb = v[j].p_bsdf;
        float wl = 1, wb = 1;  // the integrator's weights (Integrator::li)
        if (st == Strategy::Bsdf) wl = 0;
        else if (st == Strategy::Env) wb = 0;
        else {
          wl = power ? power_heuristic(1, pl, 1, pb) : balance_heuristic(1, pl, 1, pb);
          wb = power ? power_heuristic(1, pb, 1, pl) : balance_heuristic(1, pb, 1, pl);
        }
        if (pl > 0 && wl > 0) {
          const double a = double(wl) * wl * w_over_pl[j][static_cast<std::size_t>(k)], bw = w[j] * wl;
          for (int c = 0; c < 3; ++c) {
            a_light[c] += a * f2[j][c];
            b_light[c] += bw * f[j][c];
          }
        }
        if (pb > 0 && wb > 0) {
          const double a = double(wb) * wb * w_over_pb[j], bw = w[j] * wb;
          for (int c = 0; c < 3; ++c) {
            a_bsdf[c] += a * f2[j][c];
            b_bsdf[c] += bw * f[j][c];
          }
        }
      }
      ss.a_light = a_light;
      ss.a_bsdf = a_bsdf;
      ss.b_light = b_light;
      ss.b_bsdf = b_bsdf;
    }
    for (std::size_t k = 0; k < kMaxDistributions; ++k) {
      std::array<double, 3> sq = s.light_sq[k], mean = s.light_mean[k];
      for (std::size_t j = 0; j < m; ++j) {
        if (!(v[j].p_light[k] > 0)) continue;
        for (int c = 0; c < 3; ++c) {
          sq[c] += w_over_pl[j][k] * f2[j][c];
          mean[c] += w[j] * f[j][c];
        }
      }
      s.light_sq[k] = sq;
      s.light_mean[k] = mean;
    }
    for (std::size_t j = 0; j < m; ++j)
      if (v[j].f_blind > 0) {
        const double w_over_blind = w[j] / double(v[j].f_blind);
        for (int c = 0; c < 3; ++c) s.product_sq[c] += w_over_blind * f2[j][c];
      }
    for (std::size_t j = 0; j < m; ++j) {
      const double add[4] = {w[j] * v[j].f_blind, w_over_pl[j][0] * f2[j][0], w_over_pl[j][0] * f2[j][1],
                             w_over_pl[j][0] * f2[j][2]};
      for (std::size_t l = 0; l < o.exact_levels.size(); ++l) {
        const int t = o.exact_levels[l];
        Split sx, sy;
        if (b.q) {
          const QuadraturePoint& q = b.q[j0 + j];
          sx = split(q.x, q.size, t);
          sy = split(q.y, q.size, t);
        } else {
          sx = (*b.splits)[l][static_cast<std::size_t>(b.texel[j0 + j][0])];
          sy = (*b.splits)[l][static_cast<std::size_t>(b.texel[j0 + j][1])];
        }
        for (int cy = sy.c0; cy <= sy.c1; ++cy)
          for (int cx = sx.c0; cx <= sx.c1; ++cx) {
            const double share = (cx == sx.c0 ? sx.f0 : 1 - sx.f0) * (cy == sy.c0 ? sy.f0 : 1 - sy.f0);
            auto& cell = s.exact[l][static_cast<std::size_t>(cy) * t + cx];
            for (int c = 0; c < 4; ++c) cell[c] += share * add[c];
          }
      }
    }
  }
}

/// One point.
void accumulate(const DirectionValues& v, const QuadraturePoint& q, const AnalyzerOptions& o,
                const std::vector<int>& distribution, Sums& s) {
  accumulate(Batch{&v, &q, 1}, o, distribution, s);
}

bool finish(const Sums& s, const AnalyzerOptions& options_, const std::vector<int>& distribution_,
            const std::vector<std::vector<double>>& cell_mass_, PointAnalysis* r) {
  const double peak = std::max({s.integral[0], s.integral[1], s.integral[2]});
  if (!(peak > 0) || !std::isfinite(peak) || !(s.integral_blind > 0)) return false;
  std::vector<int> channels;
  for (int c = 0; c < 3; ++c) {
    r->integral[c] = s.integral[c];
    if (s.integral[c] > 1e-12 * peak) channels.push_back(c);
  }
  auto mean_over_channels = [&](auto term) {
    double acc = 0;
    for (int c : channels) acc += term(c, s.integral[c]);
    return acc / double(channels.size());
  };
  for (std::size_t i = 0; i < options_.strategies.size(); ++i) {
    const StrategySums& ss = s.strategies[i];
    r->v.push_back(mean_over_channels([&](int c, double I) {
      const double var = ss.a_light[c] + ss.a_bsdf[c] - ss.b_light[c] * ss.b_light[c] - ss.b_bsdf[c] * ss.b_bsdf[c];
      return var / (I * I);
    }));
    r->bias.push_back(mean_over_channels([&](int c, double I) { return (ss.b_light[c] + ss.b_bsdf[c] - I) / I; }));
    const int k = distribution_[i];
    if (k < 0) {
      r->v_light.push_back(kNaN);
      continue;
    }
    // The light sample alone: relative mean squared error (its variance when p_l > 0 wherever f > 0).
    r->v_light.push_back(mean_over_channels([&](int c, double I) {
      const double mean = s.light_mean[k][c];
      return (s.light_sq[k][c] - mean * mean + (I - mean) * (I - mean)) / (I * I);
    }));
  }
  r->v_product = mean_over_channels([&](int c, double I) { return s.integral_blind * s.product_sq[c] / (I * I) - 1; });
  for (std::size_t l = 0; l < options_.exact_levels.size(); ++l) {
    const auto& cells = s.exact[l];
    const auto& mass = cell_mass_[l];
    r->v_exact.push_back(mean_over_channels([&](int c, double I) {
      // p(w) = (S1[cell] / I_blind) p_env(w) / mass[cell]: integral f^2 / p = sum I_blind mass / S1 * S2.
      double acc = 0;
      for (std::size_t j = 0; j < cells.size(); ++j)
        if (cells[j][0] > 0 && mass[j] > 0) acc += s.integral_blind * mass[j] / cells[j][0] * cells[j][1 + c];
      return acc / (I * I) - 1;
    }));
  }
  return true;
}

}  // namespace envpis::render::analyzer_detail
