// SPDX-License-Identifier: Apache-2.0
// The smallest complete use of envpis: load a map, build its importance table, describe a material
// with a BSDF proxy, prepare the product sampler at a shading point, draw product samples.
#include <envpis/envpis.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <random>

int main(int argc, char** argv) {
  const char* path = argc > 1 ? argv[1] : "/usr/share/blender/datafiles/studiolights/world/sunset.exr";
  // The library's version (envpis::version(), compiled into it) and the headers' (envpis::kVersion).
  std::printf("envpis %s (headers %s)\n", envpis::version(), envpis::kVersion);
  try {
    // Once per map: the environment and its two-level importance table (immutable, shareable).
    const envpis::EnvironmentMap map = envpis::EnvironmentMap::load(path);
    const envpis::ImportanceTable table(map);
    if (table.empty()) {
      std::printf("%s is black: nothing to sample, use BSDF sampling only\n", path);
      return 0;
    }
    std::printf("%s: %dx%d, table T=%d N=%d, built in %.3f s, %zu bytes\n", path, map.width(), map.height(),
                table.top_resolution(), table.fine_resolution(), table.build_seconds(), table.bytes_used());

    // Per shading point: a proxy of the material's lobes (a rough plastic: diffuse + glossy coat).
    envpis::BsdfProxy proxy;
    proxy.add_diffuse(0.6f);
    proxy.add_reflection(0.4f, /*alpha=*/0.15f);
    const envpis::Vec3 normal{0, 0, 1};
    const envpis::Vec3 wo = envpis::normalize({1, 0, 1});  // towards the viewer

    envpis::ProductSampler sampler(table);  // one per thread
    if (!sampler.prepare(normal, wo, proxy)) {
      std::fprintf(stderr, "invalid shading point\n");
      return 1;
    }

    std::mt19937 rng(1);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    int bad = 0;
    for (int i = 0; i < 8; ++i) {
      const envpis::DirectionSample s = sampler.sample({uniform(rng), uniform(rng)});
      const float check = sampler.pdf(s.direction);  // what MIS needs for BSDF-sampled directions
      const bool ok = s.pdf > 0 && std::fabs(check - s.pdf) <= 1e-4f * s.pdf;
      bad += !ok;
      std::printf("direction (%+.4f, %+.4f, %+.4f)  pdf %.5g  pdf(direction) %.5g  cell %3d  %s\n",
                  s.direction.x, s.direction.y, s.direction.z, s.pdf, check, s.cell, ok ? "ok" : "MISMATCH");
    }
    return bad == 0 ? 0 : 1;
  } catch (const std::exception& e) {  // envpis::Error names the file and the reason
    std::fprintf(stderr, "envpis_minimal: %s\n", e.what());
    return 1;
  }
}
