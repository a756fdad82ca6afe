// SPDX-License-Identifier: Apache-2.0
// Per-shading-point product sampling on a realistic table (blender's sunset.exr, T = 12 -> 144 cells).
// Every timed loop cycles through kRing precomputed shading points (random normal, wo and proxy of a
// mixed material) so branch predictors and caches see realistic variety. One iteration = one
// shading point (or one sample / pdf evaluation).
#include <benchmark/benchmark.h>

#include <vector>

#include "bench_common.h"
#include "proxy_internal.h"

namespace envpis_bench {
namespace {

using namespace envpis;

constexpr std::size_t kMask = kRing - 1;

void table_counters(benchmark::State& state, const ImportanceTable& t) {
  state.counters["cells"] = t.cell_count();
}

// ---- product CDF build: ProductSampler::prepare (proxy preparation + weights + normalized CDF) ----

void product_prepare(benchmark::State& state, bool simd) {
  const ImportanceTable& table = sunset_table();
  const auto& pts = shading_points();
  ProductSamplerOptions opt;
  opt.simd = simd ? bench_simd() : Simd::Scalar;
  ProductSampler ps(table, opt);
  std::size_t i = 0;
  for (auto _ : state) {
    const ShadingPoint& s = pts[i++ & kMask];
    benchmark::DoNotOptimize(ps.prepare(s.n, s.wo, s.proxy));
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(simd ? to_string(bench_simd()) : "scalar reference");
  table_counters(state, table);
}
void BM_ProductPrepare_Scalar(benchmark::State& s) { product_prepare(s, false); }
void BM_ProductPrepare_SIMD(benchmark::State& s) { product_prepare(s, true); }

// ---- the product-weights kernel alone (T^2 cone evaluations x E[c]), per instruction set ----

void product_weights_kernel(benchmark::State& state, const detail::Kernels* k) {
  if (!k) {
    state.SkipWithError("kernel set not available on this CPU");
    return;
  }
  const ImportanceTable& table = sunset_table();
  const auto& pts = shading_points();
  std::vector<detail::LobeParams> lobes(kRing);
  for (std::size_t j = 0; j < kRing; ++j)
    lobes[j] = detail::to_lobe_params(prepare_proxy(pts[j].proxy, pts[j].n, pts[j].wo));
  const detail::CellArrays cells = detail::cell_arrays(table);
  std::vector<float> out(cells.padded_count);
  std::size_t i = 0;
  for (auto _ : state) {
    k->product_weights(cells, lobes[i++ & kMask], out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
  table_counters(state, table);
}
void BM_ProductWeights_KernelScalar(benchmark::State& s) { product_weights_kernel(s, &detail::kernels_scalar()); }
void BM_ProductWeights_KernelSSE2(benchmark::State& s) { product_weights_kernel(s, &detail::kernels_sse2()); }
void BM_ProductWeights_KernelAVX2(benchmark::State& s) { product_weights_kernel(s, detail::kernels_named("avx2")); }
void BM_ProductWeights_KernelAVX512(benchmark::State& s) { product_weights_kernel(s, detail::kernels_named("avx512")); }

// ---- the proxy preparation alone (axes, roughness transform): part of prepare() ----

void BM_PrepareProxy(benchmark::State& state) {
  const auto& pts = shading_points();
  std::size_t i = 0;
  for (auto _ : state) {
    const ShadingPoint& s = pts[i++ & kMask];
    PreparedProxy p = prepare_proxy(s.proxy, s.n, s.wo);
    benchmark::DoNotOptimize(p);
  }
  state.SetItemsProcessed(state.iterations());
}

// ---- the paper's per-shading-point cost: build the product CDF, draw one sample with its pdf ----

void product_prepare_and_sample(benchmark::State& state, const ImportanceTable& table,
                                const ProductSamplerOptions& opt, const char* label) {
  const auto& pts = shading_points();
  const auto& us = uniform_points();
  ProductSampler ps(table, opt);
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t j = i++ & kMask;
    const ShadingPoint& s = pts[j];
    ps.prepare(s.n, s.wo, s.proxy);
    const DirectionSample d = ps.sample(us[j]);  // d.pdf is pdf(d.direction)
    benchmark::DoNotOptimize(d);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(label);
  table_counters(state, table);
}
void product_prepare_and_sample(benchmark::State& state, bool simd) {
  ProductSamplerOptions opt;
  opt.simd = simd ? bench_simd() : Simd::Scalar;
  product_prepare_and_sample(state, sunset_table(), opt, simd ? to_string(bench_simd()) : "scalar reference");
}

// The refined product (4 x 4 sub-cells); the argument is ProductSamplerOptions::refine_cells.
void BM_ProductPrepareAndSample_Refined(benchmark::State& state) {
  ProductSamplerOptions opt;
  opt.simd = bench_simd();
  opt.refine = true;
  opt.refine_cells = static_cast<int>(state.range(0));
  product_prepare_and_sample(state, sunset_table_subcells(), opt, to_string(bench_simd()));
}

void BM_ProductPrepareAndSample_Scalar(benchmark::State& s) { product_prepare_and_sample(s, false); }
void BM_ProductPrepareAndSample_SIMD(benchmark::State& s) { product_prepare_and_sample(s, true); }

// The cells estimated from their moments (CellEstimate::Moments) instead of their cones: the paper's
// one-level product, and the refined one with refine_cells 0.
void BM_ProductPrepareAndSample_SIMD_Moments(benchmark::State& state) {
  ProductSamplerOptions opt;
  opt.simd = bench_simd();
  opt.cell_estimate = CellEstimate::Moments;
  product_prepare_and_sample(state, sunset_table(), opt, to_string(bench_simd()));
}
void BM_ProductPrepareAndSample_Refined_Moments(benchmark::State& state) {
  ProductSamplerOptions opt;
  opt.simd = bench_simd();
  opt.refine = true;
  opt.cell_estimate = CellEstimate::Moments;
  product_prepare_and_sample(state, sunset_table_subcells(), opt, to_string(bench_simd()));
}

// The renderer's configuration (refined, moments, floor 0.2) with each reflection lobe: the argument is
// ReflectionLobe (0 mirror, 1 half-vector).
void BM_ProductPrepareAndSample_ReflectionLobe(benchmark::State& state) {
  ProductSamplerOptions opt;
  opt.simd = bench_simd();
  opt.refine = true;
  opt.cell_estimate = CellEstimate::Moments;
  opt.proxy.min_alpha = 0.2f;
  opt.proxy.reflection_lobe = static_cast<ReflectionLobe>(state.range(0));
  product_prepare_and_sample(state, sunset_table_subcells(), opt, to_string(opt.proxy.reflection_lobe));
}

// The weights kernel alone with the moments estimate (the widest set).
void BM_ProductWeights_KernelBest_Moments(benchmark::State& state) {
  const ImportanceTable& table = sunset_table();
  const auto& pts = shading_points();
  std::vector<detail::LobeParams> lobes(kRing);
  for (std::size_t j = 0; j < kRing; ++j) {
    lobes[j] = detail::to_lobe_params(prepare_proxy(pts[j].proxy, pts[j].n, pts[j].wo));
    lobes[j].moments = 1;
  }
  const detail::Kernels& k = detail::kernels_for(bench_simd());
  const detail::CellArrays cells = detail::cell_arrays(table);
  std::vector<float> out(cells.padded_count);
  std::size_t i = 0;
  for (auto _ : state) {
    k.product_weights(cells, lobes[i++ & kMask], out.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(k.name);
  table_counters(state, table);
}

// ---- sampling from prepared distributions (64 different shading points, cycled) ----

constexpr std::size_t kSamplers = 64;

std::vector<ProductSampler> prepared_samplers() {
  const ImportanceTable& table = sunset_table();
  const auto& pts = shading_points();
  std::vector<ProductSampler> v;
  v.reserve(kSamplers);
  for (std::size_t j = 0; j < kSamplers; ++j) {
    v.emplace_back(table);
    v.back().prepare(pts[j].n, pts[j].wo, pts[j].proxy);
  }
  return v;
}

void BM_ProductSample(benchmark::State& state) {  // sample() = choose cell + fine sample + pdf
  const auto samplers = prepared_samplers();
  const auto& us = uniform_points();
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t j = i++;
    const DirectionSample d = samplers[j % kSamplers].sample(us[j & kMask]);
    benchmark::DoNotOptimize(d);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_ProductPdf(benchmark::State& state) {  // pdf of an arbitrary direction (MIS of a BSDF sample)
  const auto samplers = prepared_samplers();
  const auto& ds = uniform_directions();
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t j = i++;
    benchmark::DoNotOptimize(samplers[j % kSamplers].pdf(ds[j & kMask]));
  }
  state.SetItemsProcessed(state.iterations());
}

// ---- environment-only sampling from the two-level table ----

// A light sample from the table `table` returns.
template <const ImportanceTable& (*table_of)()>
void env_sample(benchmark::State& state) {
  const ImportanceTable& table = table_of();
  const auto& us = uniform_points();
  std::size_t i = 0;
  for (auto _ : state) {
    const DirectionSample d = table.sample(us[i++ & kMask]);
    benchmark::DoNotOptimize(d);
  }
  state.SetItemsProcessed(state.iterations());
}

void BM_EnvSample(benchmark::State& state) { env_sample<sunset_table>(state); }

void BM_EnvPdf(benchmark::State& state) {
  const ImportanceTable& table = sunset_table();
  const auto& ds = uniform_directions();
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(table.pdf(ds[i++ & kMask]));
  state.SetItemsProcessed(state.iterations());
}

// The same on the table of the map's own texels (the renderer's default): a light sample, and the pdf
// and radiance of a direction (what the renderer asks of a BSDF sample's direction that escapes).
void BM_EnvSampleMapTexels(benchmark::State& state) { env_sample<sunset_table_map_texels>(state); }

void BM_EnvPdfAndEvalMapTexels(benchmark::State& state) {
  const ImportanceTable& table = sunset_table_map_texels();
  const EnvironmentMap& map = sunset_map();
  const auto& ds = uniform_directions();
  std::size_t i = 0;
  for (auto _ : state) {
    const Vec3 d = ds[i++ & kMask];
    benchmark::DoNotOptimize(table.pdf(d));
    benchmark::DoNotOptimize(map.eval(d));
  }
  state.SetItemsProcessed(state.iterations());
}

}  // namespace

BENCHMARK(BM_ProductPrepare_Scalar);
BENCHMARK(BM_ProductPrepare_SIMD);
BENCHMARK(BM_ProductWeights_KernelScalar);
BENCHMARK(BM_ProductWeights_KernelSSE2);
BENCHMARK(BM_ProductWeights_KernelAVX2);
BENCHMARK(BM_ProductWeights_KernelAVX512);
BENCHMARK(BM_PrepareProxy);
BENCHMARK(BM_ProductPrepareAndSample_Scalar);
BENCHMARK(BM_ProductPrepareAndSample_SIMD);
BENCHMARK(BM_ProductPrepareAndSample_Refined)->ArgName("refine_cells")->Arg(0)->Arg(8);
BENCHMARK(BM_ProductPrepareAndSample_SIMD_Moments);
BENCHMARK(BM_ProductPrepareAndSample_Refined_Moments);
BENCHMARK(BM_ProductPrepareAndSample_ReflectionLobe)->ArgName("half_vector")->Arg(0)->Arg(1);
BENCHMARK(BM_ProductWeights_KernelBest_Moments);
BENCHMARK(BM_ProductSample);
BENCHMARK(BM_ProductPdf);
BENCHMARK(BM_EnvSample);
BENCHMARK(BM_EnvPdf);
BENCHMARK(BM_EnvSampleMapTexels);
BENCHMARK(BM_EnvPdfAndEvalMapTexels);

}  // namespace envpis_bench
