// SPDX-License-Identifier: Apache-2.0
// Equal-area mapping (Clarberg 2008), both directions: the public scalar overloads called in a loop
// vs the batched structure-of-arrays versions, through the public dispatch and through each internal
// kernel set (scalar / SSE2 / AVX2). One iteration maps kBatch points; items = points.
#include <benchmark/benchmark.h>

#include <vector>

#include "bench_common.h"

namespace envpis_bench {
namespace {

using namespace envpis;

constexpr std::size_t kBatch = kRing;  // 1024 points: 20 KiB of SoA data, stays in L1

struct SquareSoA {
  std::vector<float> u, v, x, y, z;
  SquareSoA() : u(kBatch), v(kBatch), x(kBatch), y(kBatch), z(kBatch) {
    const auto& p = uniform_points();
    for (std::size_t i = 0; i < kBatch; ++i) {
      u[i] = p[i].x;
      v[i] = p[i].y;
    }
  }
};

struct SphereSoA {
  std::vector<float> x, y, z, u, v;
  SphereSoA() : x(kBatch), y(kBatch), z(kBatch), u(kBatch), v(kBatch) {
    const auto& d = uniform_directions();
    for (std::size_t i = 0; i < kBatch; ++i) {
      x[i] = d[i].x;
      y[i] = d[i].y;
      z[i] = d[i].z;
    }
  }
};

void finish(benchmark::State& state) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(kBatch));
}

// ---- square -> sphere ----

void BM_SquareToSphere_ScalarLoop(benchmark::State& state) {
  SquareSoA d;
  for (auto _ : state) {
    for (std::size_t i = 0; i < kBatch; ++i) {
      const Vec3 w = equal_area_square_to_sphere(Point2{d.u[i], d.v[i]});
      d.x[i] = w.x;
      d.y[i] = w.y;
      d.z[i] = w.z;
    }
    benchmark::ClobberMemory();
  }
  finish(state);
}

void BM_SquareToSphere_Batched(benchmark::State& state) {
  SquareSoA d;
  for (auto _ : state) {
    equal_area_square_to_sphere(kBatch, d.u.data(), d.v.data(), d.x.data(), d.y.data(), d.z.data(), bench_simd());
    benchmark::ClobberMemory();
  }
  state.SetLabel(to_string(bench_simd()));
  finish(state);
}

void square_to_sphere_kernel(benchmark::State& state, const detail::Kernels* k) {
  if (!k) {
    state.SkipWithError("kernel set not available on this CPU");
    return;
  }
  SquareSoA d;
  for (auto _ : state) {
    k->square_to_sphere(kBatch, d.u.data(), d.v.data(), d.x.data(), d.y.data(), d.z.data());
    benchmark::ClobberMemory();
  }
  finish(state);
}
void BM_SquareToSphere_KernelScalar(benchmark::State& s) { square_to_sphere_kernel(s, &detail::kernels_scalar()); }
void BM_SquareToSphere_KernelSSE2(benchmark::State& s) { square_to_sphere_kernel(s, &detail::kernels_sse2()); }
void BM_SquareToSphere_KernelAVX2(benchmark::State& s) { square_to_sphere_kernel(s, detail::kernels_named("avx2")); }
void BM_SquareToSphere_KernelAVX512(benchmark::State& s) { square_to_sphere_kernel(s, detail::kernels_named("avx512")); }

// ---- sphere -> square ----

void BM_SphereToSquare_ScalarLoop(benchmark::State& state) {
  SphereSoA d;
  for (auto _ : state) {
    for (std::size_t i = 0; i < kBatch; ++i) {
      const Point2 p = equal_area_sphere_to_square(Vec3{d.x[i], d.y[i], d.z[i]});
      d.u[i] = p.x;
      d.v[i] = p.y;
    }
    benchmark::ClobberMemory();
  }
  finish(state);
}

void BM_SphereToSquare_Batched(benchmark::State& state) {
  SphereSoA d;
  for (auto _ : state) {
    equal_area_sphere_to_square(kBatch, d.x.data(), d.y.data(), d.z.data(), d.u.data(), d.v.data(), bench_simd());
    benchmark::ClobberMemory();
  }
  state.SetLabel(to_string(bench_simd()));
  finish(state);
}

void sphere_to_square_kernel(benchmark::State& state, const detail::Kernels* k) {
  if (!k) {
    state.SkipWithError("kernel set not available on this CPU");
    return;
  }
  SphereSoA d;
  for (auto _ : state) {
    k->sphere_to_square(kBatch, d.x.data(), d.y.data(), d.z.data(), d.u.data(), d.v.data());
    benchmark::ClobberMemory();
  }
  finish(state);
}
void BM_SphereToSquare_KernelScalar(benchmark::State& s) { sphere_to_square_kernel(s, &detail::kernels_scalar()); }
void BM_SphereToSquare_KernelSSE2(benchmark::State& s) { sphere_to_square_kernel(s, &detail::kernels_sse2()); }
void BM_SphereToSquare_KernelAVX2(benchmark::State& s) { sphere_to_square_kernel(s, detail::kernels_named("avx2")); }
void BM_SphereToSquare_KernelAVX512(benchmark::State& s) { sphere_to_square_kernel(s, detail::kernels_named("avx512")); }

}  // namespace

BENCHMARK(BM_SquareToSphere_ScalarLoop);
BENCHMARK(BM_SquareToSphere_Batched);
BENCHMARK(BM_SquareToSphere_KernelScalar);
BENCHMARK(BM_SquareToSphere_KernelSSE2);
BENCHMARK(BM_SquareToSphere_KernelAVX2);
BENCHMARK(BM_SquareToSphere_KernelAVX512);
BENCHMARK(BM_SphereToSquare_ScalarLoop);
BENCHMARK(BM_SphereToSquare_Batched);
BENCHMARK(BM_SphereToSquare_KernelScalar);
BENCHMARK(BM_SphereToSquare_KernelSSE2);
BENCHMARK(BM_SphereToSquare_KernelAVX2);
BENCHMARK(BM_SphereToSquare_KernelAVX512);

}  // namespace envpis_bench
