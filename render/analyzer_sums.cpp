// SPDX-License-Identifier: Apache-2.0
#include "render/analyzer_sums.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace envpis::render::analyzer_detail {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline double channel(Rgb c, int k) { return k == 0 ? c.r : (k == 1 ? c.g : c.b); }

// Three channels and a zero lane: one register on AVX2, two on SSE2. A term left out by a branch in
// the integrator is added here as a zero, which leaves every sum's bits unchanged (sums of finite
// terms are never -0), so the strategies' and the light densities' loops have no branch per term.
// With GCC and clang the lanes are a vector type, so that each add is one instruction per register
// rather than whatever the loop vectorizer makes of four scalars (it kept most of them scalar).
// Internal functions only, so the vector ABI warning does not apply.
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
typedef double Lanes __attribute__((vector_size(32)));
inline void add_scaled(Lanes& acc, double a, const Lanes& x) { acc += a * x; }
inline Lanes square(const Lanes& x) { return x * x; }
#else
using Lanes = std::array<double, 4>;
inline void add_scaled(Lanes& acc, double a, const Lanes& x) {
  for (int c = 0; c < 4; ++c) acc[c] += a * x[c];
}
inline Lanes square(const Lanes& x) { return {x[0] * x[0], x[1] * x[1], x[2] * x[2], x[3] * x[3]}; }
#endif
inline Lanes lanes(const std::array<double, 3>& s) { return Lanes{s[0], s[1], s[2], 0.0}; }
inline void store(const Lanes& l, std::array<double, 3>& s) { s = {l[0], l[1], l[2]}; }

constexpr std::size_t kChunk = 64;

/// What a chunk of points contributes, per point: f and f^2 per lane, the weight w, w / p per light
/// density and w / p_bsdf (0 where the density is 0).
struct Chunk {
  std::size_t m = 0;
  Lanes f[kChunk], f2[kChunk];
  double w[kChunk], w_over_pb[kChunk];
  double w_over_pl[kChunk][kMaxDistributions];
};

/// One strategy's four running sums over a chunk. `weights(pl, pb)` gives the integrator's MIS weights
/// of the light and the BSDF sample (Integrator::li); k < 0: no light sample.
template <class Weights>
void strategy_sums(const Chunk& ch, const DirectionValues* v, int k, Weights weights, StrategySums& ss) {
  Lanes a_light = lanes(ss.a_light), a_bsdf = lanes(ss.a_bsdf), b_light = lanes(ss.b_light),
        b_bsdf = lanes(ss.b_bsdf);
  const std::size_t uk = static_cast<std::size_t>(std::max(k, 0));
  for (std::size_t j = 0; j < ch.m; ++j) {
    const float pl = k >= 0 ? v[j].p_light[uk] : 0.0f, pb = v[j].p_bsdf;
    const auto [wl, wb] = weights(pl, pb);
    if (k >= 0) {
      const bool on = pl > 0 && wl > 0;
      add_scaled(a_light, on ? double(wl) * wl * ch.w_over_pl[j][uk] : 0.0, ch.f2[j]);
      add_scaled(b_light, on ? ch.w[j] * wl : 0.0, ch.f[j]);
    }
    const bool on = pb > 0 && wb > 0;
    add_scaled(a_bsdf, on ? double(wb) * wb * ch.w_over_pb[j] : 0.0, ch.f2[j]);
    add_scaled(b_bsdf, on ? ch.w[j] * wb : 0.0, ch.f[j]);
  }
  store(a_light, ss.a_light);
  store(a_bsdf, ss.a_bsdf);
  store(b_light, ss.b_light);
  store(b_bsdf, ss.b_bsdf);
}

/// The chunk's per-point factors, and its share of the integrals.
void fill(const Batch& b, std::size_t j0, Chunk& ch, Sums& s) {
  Lanes integral = lanes(s.integral);
  for (std::size_t j = 0; j < ch.m; ++j) {
    const DirectionValues& v = b.v[j0 + j];
    const double w = b.q ? b.q[j0 + j].w : b.texel_area;
    ch.w[j] = w;
    // Built in a register and stored whole: lane by lane stores read back as one vector stall.
    const Lanes f = Lanes{channel(v.f, 0), channel(v.f, 1), channel(v.f, 2), 0.0};
    ch.f[j] = f;
    ch.f2[j] = square(f);
    add_scaled(integral, w, f);
    s.integral_blind += w * v.f_blind;
    for (std::size_t k = 0; k < kMaxDistributions; ++k)
      ch.w_over_pl[j][k] = v.p_light[k] > 0 ? w / double(v.p_light[k]) : 0.0;
    ch.w_over_pb[j] = v.p_bsdf > 0 ? w / double(v.p_bsdf) : 0.0;
  }
  store(integral, s.integral);
}

struct LightBsdfWeights {
  float l, b;
};

void chunk_strategies(const Chunk& ch, const DirectionValues* v, const AnalyzerOptions& o,
                      const std::vector<int>& distribution, Sums& s) {
  for (std::size_t i = 0; i < o.strategies.size(); ++i) {
    const Strategy st = o.strategies[i];
    const int k = distribution[i];
    StrategySums& ss = s.strategies[i];
    if (st == Strategy::Bsdf)
      strategy_sums(ch, v, -1, [](float, float) { return LightBsdfWeights{0, 1}; }, ss);
    else if (st == Strategy::Env)
      strategy_sums(ch, v, k, [](float, float) { return LightBsdfWeights{1, 0}; }, ss);
    else if (o.heuristic == Heuristic::Power)
      strategy_sums(ch, v, k, [](float pl, float pb) {
        return LightBsdfWeights{power_heuristic(1, pl, 1, pb), power_heuristic(1, pb, 1, pl)};
      }, ss);
    else
      strategy_sums(ch, v, k, [](float pl, float pb) {
        return LightBsdfWeights{balance_heuristic(1, pl, 1, pb), balance_heuristic(1, pb, 1, pl)};
      }, ss);
  }
}

/// Each light distribution alone (f^2 / p and f where p > 0) and the exact product (f^2 / f_blind).
void chunk_limits(const Chunk& ch, const DirectionValues* v, Sums& s) {
  for (std::size_t k = 0; k < kMaxDistributions; ++k) {
    Lanes sq = lanes(s.light_sq[k]), mean = lanes(s.light_mean[k]);
    for (std::size_t j = 0; j < ch.m; ++j) {
      add_scaled(sq, ch.w_over_pl[j][k], ch.f2[j]);
      add_scaled(mean, v[j].p_light[k] > 0 ? ch.w[j] : 0.0, ch.f[j]);
    }
    store(sq, s.light_sq[k]);
    store(mean, s.light_mean[k]);
  }
  Lanes product = lanes(s.product_sq);
  for (std::size_t j = 0; j < ch.m; ++j)
    if (v[j].f_blind > 0) add_scaled(product, ch.w[j] / double(v[j].f_blind), ch.f2[j]);
  store(product, s.product_sq);
}

/// The cell an exact level last added to, kept in a register until another cell is met: the adds
/// to each cell are the same in the same order, without a store and reload per point.
struct CellCursor {
  std::array<double, 4>* cell = nullptr;
  Lanes sum{};
  void add(std::array<double, 4>* c, double share, const Lanes& x) {
    if (c != cell) {
      flush();
      cell = c;
      sum = Lanes{(*c)[0], (*c)[1], (*c)[2], (*c)[3]};
    }
    add_scaled(sum, share, x);
  }
  void flush() {
    if (cell) *cell = {sum[0], sum[1], sum[2], sum[3]};
    cell = nullptr;
  }
};

/// Per exact level, the cells each point overlaps, by their share of it.
void chunk_exact(const Batch& b, std::size_t j0, const Chunk& ch, const AnalyzerOptions& o, Sums& s) {
  for (std::size_t l = 0; l < o.exact_levels.size(); ++l) {
    if (s.exact_source[l] != l) continue;
    const int t = o.exact_levels[l];
    CellCursor cursor;
    for (std::size_t j = 0; j < ch.m; ++j) {
      const Lanes add = Lanes{ch.w[j] * b.v[j0 + j].f_blind, ch.w_over_pl[j][0] * ch.f2[j][0],
                              ch.w_over_pl[j][0] * ch.f2[j][1], ch.w_over_pl[j][0] * ch.f2[j][2]};
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
          cursor.add(&s.exact[l][static_cast<std::size_t>(cy) * t + cx], share, add);
        }
    }
    cursor.flush();
  }
}

/// The t x t cells of a level summed from the cells of level tf, a multiple of t.
std::vector<std::array<double, 4>> aggregate_cells(const std::vector<std::array<double, 4>>& fine, int tf, int t) {
  std::vector<std::array<double, 4>> out(static_cast<std::size_t>(t) * t, std::array<double, 4>{});
  const int r = tf / t;
  for (int y = 0; y < tf; ++y)
    for (int x = 0; x < tf; ++x) {
      std::array<double, 4>& o = out[static_cast<std::size_t>(y / r) * t + x / r];
      const std::array<double, 4>& f = fine[static_cast<std::size_t>(y) * tf + x];
      for (int c = 0; c < 4; ++c) o[c] += f[c];
    }
  return out;
}

}  // namespace

// A point's share of a coarse cell is the sum of its shares of the fine cells inside it, so only the
// finest levels are summed point by point.
void Sums::init_exact(const std::vector<int>& levels) {
  exact_source.assign(levels.size(), 0);
  exact.assign(levels.size(), {});
  for (std::size_t l = 0; l < levels.size(); ++l) {
    std::size_t& source = exact_source[l];
    source = l;
    for (std::size_t f = 0; f < levels.size(); ++f)
      if (levels[f] % levels[l] == 0 && levels[f] > levels[source]) source = f;
  }
  for (std::size_t l = 0; l < levels.size(); ++l)
    if (exact_source[l] == l) exact[l].assign(static_cast<std::size_t>(levels[l]) * levels[l], std::array<double, 4>{});
}

TexelSplits texel_splits(int n, const std::vector<int>& levels) {
  TexelSplits out;
  for (int t : levels) {
    out.emplace_back();
    for (int x = 0; x < n; ++x) out.back().push_back(split(double(x) / n, 1.0 / n, t));
  }
  return out;
}

// The lanes fill one AVX2 register where the machine has it (no FMA: the same bits either way).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)  // clang 14: no flatten with clones
__attribute__((target_clones("avx2", "default"), flatten))
#endif
void accumulate(const Batch& b, const AnalyzerOptions& o, const std::vector<int>& distribution, Sums& s) {
  Chunk ch;
  for (std::size_t j0 = 0; j0 < b.count; j0 += kChunk) {
    ch.m = std::min(kChunk, b.count - j0);
    fill(b, j0, ch, s);
    chunk_strategies(ch, b.v + j0, o, distribution, s);
    chunk_limits(ch, b.v + j0, s);
    chunk_exact(b, j0, ch, o, s);
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
  // A variance: below 0 only by round-off (it is 0 for a grey integrand).
  r->v_product = std::max(
      0.0, mean_over_channels([&](int c, double I) { return s.integral_blind * s.product_sq[c] / (I * I) - 1; }));
  std::vector<std::array<double, 4>> aggregated;
  for (std::size_t l = 0; l < options_.exact_levels.size(); ++l) {
    const std::size_t source = s.exact_source[l];
    if (source != l)
      aggregated = aggregate_cells(s.exact[source], options_.exact_levels[source], options_.exact_levels[l]);
    const std::vector<std::array<double, 4>>& cells = source == l ? s.exact[l] : aggregated;
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
