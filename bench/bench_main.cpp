// SPDX-License-Identifier: Apache-2.0
// envpis_bench: Google Benchmark entry point and the shared fixtures.
#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdlib>
#include <random>

#include "bench_common.h"

namespace envpis_bench {

using namespace envpis;

std::string world_dir() {
  const char* env = std::getenv("ENVPIS_BENCH_WORLD_DIR");
  return env && *env ? env : ENVPIS_BENCH_WORLD_DIR;
}

const EnvironmentMap& sunset_map() {
  static const EnvironmentMap m = EnvironmentMap::load(world_dir() + "/sunset.exr");
  return m;
}

const EnvironmentMap& studio_map() {
  static const EnvironmentMap m = EnvironmentMap::load(world_dir() + "/studio.exr");
  return m;
}

const EnvironmentMap& sunset_4k_map() {
  static const EnvironmentMap m = [] {
    const EnvironmentMap& src = sunset_map();
    const int w = 4096, h = 2048;
    std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
    tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 0; x < w; ++x) {
          const Rgb c = src.eval_texture({(x + 0.5f) / w, (y + 0.5f) / h});
          float* p = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
          p[0] = c.r;
          p[1] = c.g;
          p[2] = c.b;
        }
    });
    return EnvironmentMap::from_pixels(w, h, std::move(rgb));
  }();
  return m;
}

namespace {
// A clear sky: a gradient brighter towards the zenith, a dark ground, and a sun of the real sun's
// angular radius (0.27 degrees, a few texels across at 4096 x 2048) at 30 degrees elevation; each
// texel the average over 2 x 2 points so that the sun's rim is partly covered, as in a photograph.
EnvironmentMap make_sky(int w, int h) {
  std::vector<float> rgb(static_cast<std::size_t>(w) * h * 3);
  const float t = (90.0f - 30.0f) * kPi / 180, p = 0.3f;
  const Vec3 sun{std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
  const float cos_r = std::cos(0.27f * kPi / 180);
  tbb::parallel_for(tbb::blocked_range<int>(0, h), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < w; ++x) {
        float acc[3] = {0, 0, 0};
        for (int j = 0; j < 2; ++j)
          for (int i = 0; i < 2; ++i) {
            const Vec3 d = latlong_to_direction({(x + (i + 0.5f) / 2) / w, (y + (j + 0.5f) / 2) / h});
            const float up = std::max(0.0f, d.z);
            float c[3] = {0.4f + 0.6f * up, 0.6f + 0.6f * up, 1.0f + 0.8f * up};
            if (d.z < 0) c[0] = c[1] = c[2] = 0.15f;
            if (dot(d, sun) >= cos_r) c[0] = c[1] = c[2] = 5e4f;
            for (int k = 0; k < 3; ++k) acc[k] += 0.25f * c[k];
          }
        float* px = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
        for (int k = 0; k < 3; ++k) px[k] = acc[k];
      }
  });
  return EnvironmentMap::from_pixels(w, h, std::move(rgb));
}
}  // namespace

const EnvironmentMap& sky_4k_map() {
  static const EnvironmentMap m = make_sky(4096, 2048);
  return m;
}

const EnvironmentMap& sky_8k_map() {
  static const EnvironmentMap m = make_sky(8192, 4096);
  return m;
}

const ImportanceTable& sunset_table() {
  static const ImportanceTable t(sunset_map());
  return t;
}

const ImportanceTable& sunset_table_subcells() {
  static const ImportanceTable t(sunset_map(), [] {
    ImportanceTableOptions o;
    o.subdivision = 4;
    return o;
  }());
  return t;
}

const ImportanceTable& sunset_table_map_texels() {
  static const ImportanceTable t(sunset_map(), [] {
    ImportanceTableOptions o;
    o.subdivision = 4;
    o.fine_texels = FineTexels::Map;
    return o;
  }());
  return t;
}

namespace {
Vec3 uniform_sphere(float u, float v) {
  const float z = 1.0f - 2.0f * u;
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * v;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
}  // namespace

const std::vector<ShadingPoint>& shading_points() {
  static const std::vector<ShadingPoint> pts = [] {
    std::mt19937 rng(20180812u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<ShadingPoint> out(kRing);
    for (std::size_t i = 0; i < kRing; ++i) {
      ShadingPoint& s = out[i];
      s.n = uniform_sphere(U(rng), U(rng));
      s.wo = uniform_sphere(U(rng), U(rng));
      if (dot(s.n, s.wo) < 0 && U(rng) < 0.9f) s.wo = -s.wo;  // mostly seen from above
      const float a = U(rng);
      switch (rng() % 5) {
        case 0:  // diffuse
          s.proxy.add_diffuse(0.2f + 0.7f * U(rng));
          break;
        case 1:  // plastic
          s.proxy.add_diffuse(0.2f + 0.7f * U(rng));
          s.proxy.add_reflection(0.04f + 0.06f * U(rng), 0.05f + 0.55f * a);
          break;
        case 2:  // metal
          s.proxy.add_reflection(0.5f + 0.5f * U(rng), 0.02f + 0.78f * a);
          break;
        case 3:  // glass
          s.proxy.add_reflection(0.05f + 0.05f * U(rng), 0.3f * a);
          s.proxy.add_refraction(0.9f, 0.3f * a, 1.33f + 0.37f * U(rng));
          break;
        default:  // thin translucent
          s.proxy.add_diffuse(0.3f + 0.4f * U(rng));
          s.proxy.add_translucent(0.1f + 0.4f * U(rng));
          break;
      }
    }
    return out;
  }();
  return pts;
}

const std::vector<Point2>& uniform_points() {
  static const std::vector<Point2> pts = [] {
    std::mt19937 rng(7u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<Point2> out(kRing);
    for (auto& p : out) p = {U(rng), U(rng)};
    return out;
  }();
  return pts;
}

const std::vector<Vec3>& uniform_directions() {
  static const std::vector<Vec3> dirs = [] {
    std::mt19937 rng(11u);
    std::uniform_real_distribution<float> U(0.0f, 1.0f);
    std::vector<Vec3> out(kRing);
    for (auto& d : out) d = uniform_sphere(U(rng), U(rng));
    return out;
  }();
  return dirs;
}

envpis::Simd bench_simd() {
  static const envpis::Simd simd = [] {
    const char* name = std::getenv("ENVPIS_SIMD");
    return envpis::simd_resolve(name ? envpis::parse_simd(name) : envpis::Simd::Best);
  }();
  return simd;
}

}  // namespace envpis_bench

int main(int argc, char** argv) {
  benchmark::AddCustomContext("envpis_simd", envpis::to_string(envpis_bench::bench_simd()));
  benchmark::AddCustomContext("envpis_version", envpis::kVersion);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
