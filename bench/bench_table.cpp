// SPDX-License-Identifier: Apache-2.0
// ImportanceTable construction (importance image, per-cell CDFs, cones) for the 1024x512 blender maps
// and a 4096x2048 map (sunset.exr resampled in setup, not timed), a synthetic sky with a small sun at
// 4096x2048 and 8192x4096 (generated in setup, not timed; issue 21's build targets), with 1 and 2 TBB threads
// (tbb::global_control), with the peak bound off (peak_ratio 0) and at its default (8). Wall-clock
// time (UseRealTime). TableBuildMapTexels_*: the renderer's default table (the map's own texels,
// 4 x 4 sub-cells, FineTexels::Map). Counters report the table's memory against a
// standard single-level 2D CDF over the same texels.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <ctime>

#include "bench_common.h"

namespace envpis_bench {
namespace {

using namespace envpis;

void table_build(benchmark::State& state, const EnvironmentMap& (*map_fn)(), FineTexels fine_texels = FineTexels::EqualArea) {
  const EnvironmentMap& map = map_fn();  // loaded / resampled once, outside the timing
  const int threads = static_cast<int>(state.range(0));
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
  std::size_t bytes = 0, single = 0;
  int fine = 0;
  const std::clock_t cpu0 = std::clock();  // process CPU time: all threads
  ImportanceTableOptions options;
  options.peak_ratio = static_cast<float>(state.range(1));
  options.fine_texels = fine_texels;
  options.subdivision = fine_texels == FineTexels::Map ? 4 : 1;  // the renderer's tables
  for (auto _ : state) {
    ImportanceTable table(map, options);
    bytes = table.bytes_used();
    single = table.single_level_bytes();
    fine = table.fine_resolution();
    benchmark::DoNotOptimize(table);
  }
  const double cpu_ms = 1e3 * double(std::clock() - cpu0) / CLOCKS_PER_SEC;
  // CPU time of all threads per build: on a shared machine, real time / this shows the contention,
  // and this / threads bounds the uncontended wall time from below.
  state.counters["all_threads_cpu_ms"] = cpu_ms / double(state.iterations());
  state.counters["threads"] = threads;
  state.counters["fine_N"] = fine;
  state.counters["bytes_used"] = benchmark::Counter(double(bytes), benchmark::Counter::kDefaults,
                                                    benchmark::Counter::kIs1024);
  state.counters["single_level_bytes"] = benchmark::Counter(double(single), benchmark::Counter::kDefaults,
                                                            benchmark::Counter::kIs1024);
  state.counters["bytes_ratio"] = single ? double(bytes) / double(single) : 0.0;
  state.counters["bytes_over_single"] = double(bytes) - double(single);
  state.SetItemsProcessed(state.iterations() * int64_t(map.width()) * map.height());  // map texels
  state.SetLabel(std::to_string(map.width()) + "x" + std::to_string(map.height()));
}

void BM_TableBuild_Sunset1k(benchmark::State& s) { table_build(s, sunset_map); }
void BM_TableBuild_Studio1k(benchmark::State& s) { table_build(s, studio_map); }
void BM_TableBuild_Sunset4k(benchmark::State& s) { table_build(s, sunset_4k_map); }
void BM_TableBuild_Sky4k(benchmark::State& s) { table_build(s, sky_4k_map); }
void BM_TableBuild_Sky8k(benchmark::State& s) { table_build(s, sky_8k_map); }
// The renderer's default light table: the map's own texels, 4 x 4 sub-cells.
void BM_TableBuildMapTexels_Sunset1k(benchmark::State& s) { table_build(s, sunset_map, FineTexels::Map); }
void BM_TableBuildMapTexels_Sunset4k(benchmark::State& s) { table_build(s, sunset_4k_map, FineTexels::Map); }
void BM_TableBuildMapTexels_Sky8k(benchmark::State& s) { table_build(s, sky_8k_map, FineTexels::Map); }

}  // namespace

BENCHMARK(BM_TableBuild_Sunset1k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {0, 8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuild_Studio1k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {0, 8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuild_Sunset4k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {0, 8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuild_Sky4k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {0, 8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuildMapTexels_Sunset1k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuildMapTexels_Sunset4k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuildMapTexels_Sky8k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {8}})->UseRealTime()->Unit(benchmark::kMillisecond);
BENCHMARK(BM_TableBuild_Sky8k)->ArgNames({"threads", "peak_ratio"})->ArgsProduct({{1, 2}, {8}})->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace envpis_bench
