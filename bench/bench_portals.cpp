// SPDX-License-Identifier: Apache-2.0
// Portals (issue 24): the per-shading-point cost of the product through portals against the product
// without, on blender's sunset.exr (T = 12). One iteration = one shading point: PortalView::prepare(p)
// (with portals), ProductSampler::prepare, one sample() (which returns its pdf) and one pdf() of
// another direction (a BSDF sample's, for MIS). The shading points are the product benchmarks' ring
// (normal, wo, proxy), turned to face up, at kRing positions inside the room of tests/test_portals.cpp
// (the box [-2, 2]^2 x [0, 3]); the portals are its east window, then skylight, north window and a
// corner window.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "bench_common.h"

namespace envpis_bench {
namespace {

using namespace envpis;

constexpr std::size_t kMask = kRing - 1;

Quad quad(Vec3 c, Vec3 u, Vec3 v) { return {{c - u - v, c + u - v, c + u + v, c - u + v}}; }

Portals room_portals(int count) {
  const Vec3 n = normalize(Vec3{-1, -1, 1}), u = normalize(Vec3{1, -1, 0}) * 0.4f;
  const std::vector<Quad> all = {quad({2, 0, 1.5f}, {0, 0.8f, 0}, {0, 0, 0.5f}),
                                 quad({0, 0, 3}, {0.5f, 0, 0}, {0, 0.5f, 0}),
                                 quad({0, 2, 1.2f}, {0, 0, 0.5f}, {0.6f, 0, 0}),
                                 quad({-1.7f, -1.7f, 2.6f}, u, cross(n, u) * (0.3f / length(cross(n, u))))};
  return Portals(std::vector<Quad>(all.begin(), all.begin() + count));
}

struct RoomPoint {
  Vec3 p;
  ShadingPoint s;
};

const std::vector<RoomPoint>& room_points() {
  static const std::vector<RoomPoint> pts = [] {
    std::vector<RoomPoint> out;
    std::mt19937_64 rng(24);
    std::uniform_real_distribution<float> U(0, 1);
    for (const ShadingPoint& s : shading_points()) {
      RoomPoint r{{-1.8f + 3.6f * U(rng), -1.8f + 3.6f * U(rng), 0.1f + 2.7f * U(rng)}, s};
      if (r.s.n.z < 0) r.s.n = -r.s.n, r.s.wo = -r.s.wo;
      out.push_back(r);
    }
    return out;
  }();
  return pts;
}

// portals < 0: no portals (the baseline); else that many, with the estimate.
// sample_too false: prepare() alone (the view's and the product's), to tell the weights' cost from the
// samples' (whose fine-level reads land in other cells through portals: other cache lines).
void product_through_portals(benchmark::State& state, int portals, PortalEstimate estimate, bool sample_too = true) {
  const ImportanceTable& table = sunset_table();
  const auto& pts = room_points();
  const auto& us = uniform_points();
  const auto& ds = uniform_directions();
  ProductSamplerOptions opt;
  opt.simd = bench_simd();
  ProductSampler ps(table, opt);
  PortalView view(table, room_portals(std::max(portals, 0)), {estimate, 4});
  std::size_t i = 0, valid = 0;
  for (auto _ : state) {
    const std::size_t j = i++ & kMask;
    const RoomPoint& r = pts[j];
    const PortalView* v = nullptr;
    if (portals > 0) {
      view.prepare(r.p);
      v = &view;
    }
    valid += ps.prepare(r.s.n, r.s.wo, r.s.proxy, v);
    if (!sample_too) continue;
    const DirectionSample d = ps.sample(us[j]);
    benchmark::DoNotOptimize(d);
    benchmark::DoNotOptimize(ps.pdf(ds[j]));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["valid"] = double(valid) / double(std::max<std::size_t>(i, 1));
  state.SetLabel(portals > 0 ? to_string(estimate) : "no portals");
}

void BM_PortalProduct_None(benchmark::State& s) { product_through_portals(s, -1, PortalEstimate::Cone); }
void BM_PortalProduct_Cone(benchmark::State& s) {
  product_through_portals(s, static_cast<int>(s.range(0)), PortalEstimate::Cone);
}
void BM_PortalPrepare_None(benchmark::State& s) { product_through_portals(s, -1, PortalEstimate::Cone, false); }
void BM_PortalPrepare_Cone(benchmark::State& s) {
  product_through_portals(s, static_cast<int>(s.range(0)), PortalEstimate::Cone, false);
}
void BM_PortalProduct_Grid(benchmark::State& s) {
  product_through_portals(s, static_cast<int>(s.range(0)), PortalEstimate::Grid);
}

// The view alone (PortalView::prepare), per estimate and portal count.
void BM_PortalView(benchmark::State& state) {
  const ImportanceTable& table = sunset_table();
  const auto& pts = room_points();
  const PortalEstimate est = state.range(1) ? PortalEstimate::Grid : PortalEstimate::Cone;
  PortalView view(table, room_portals(static_cast<int>(state.range(0))), {est, 4});
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(view.prepare(pts[i++ & kMask].p));
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(to_string(est));
}

// The environment-only baseline through one portal: PortalView::prepare + PortalEnvironmentSampler.
void BM_PortalEnvironment(benchmark::State& state) {
  const ImportanceTable& table = sunset_table();
  const auto& pts = room_points();
  const auto& us = uniform_points();
  const auto& ds = uniform_directions();
  PortalView view(table, room_portals(static_cast<int>(state.range(0))));
  PortalEnvironmentSampler env(table);
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t j = i++ & kMask;
    view.prepare(pts[j].p);
    env.prepare(view);
    benchmark::DoNotOptimize(env.sample(us[j]));
    benchmark::DoNotOptimize(env.pdf(ds[j]));
  }
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(BM_PortalProduct_None);
BENCHMARK(BM_PortalProduct_Cone)->ArgName("portals")->Arg(1)->Arg(4);
BENCHMARK(BM_PortalPrepare_None);
BENCHMARK(BM_PortalPrepare_Cone)->ArgName("portals")->Arg(1)->Arg(4);
BENCHMARK(BM_PortalProduct_Grid)->ArgName("portals")->Arg(1)->Arg(4);
BENCHMARK(BM_PortalView)->ArgNames({"portals", "grid"})->Args({1, 0})->Args({4, 0})->Args({1, 1})->Args({4, 1});
BENCHMARK(BM_PortalEnvironment)->ArgName("portals")->Arg(1)->Arg(4);

}  // namespace envpis_bench
