// SPDX-License-Identifier: Apache-2.0
// Writes the sun stress family (tests/stress_maps.h) as lat-long OpenEXR files:
//   envpis_stress_maps OUT_DIR [WIDTH]
// one NAME.exr per map (the family and the quadrant-boundary suns), for scripts/stress-bench.sh. The
// maps are generated, never shipped.
#include <OpenImageIO/imageio.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "stress_maps.h"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: envpis_stress_maps OUT_DIR [WIDTH]\n");
    return 2;
  }
  const std::string dir = argv[1];
  const int w = argc == 3 ? std::atoi(argv[2]) : 1024;
  if (w < 8 || w > 8192 || w % 2) {
    std::fprintf(stderr, "envpis_stress_maps: WIDTH must be even and in 8..8192\n");
    return 2;
  }
  std::filesystem::create_directories(dir);
  std::vector<envpis::test::StressMap> maps = envpis::test::stress_family();
  for (auto& sm : envpis::test::quadrant_boundary_family()) maps.push_back(std::move(sm));
  for (const auto& sm : maps) {
    const envpis::EnvironmentMap m = envpis::test::make_stress_map(sm, w, w / 2);
    std::vector<float> rgb(static_cast<std::size_t>(w) * (w / 2) * 3);
    for (int y = 0; y < w / 2; ++y)
      for (int x = 0; x < w; ++x) {
        const envpis::Rgb c = m.texel(x, y);
        float* p = &rgb[(static_cast<std::size_t>(y) * w + x) * 3];
        p[0] = c.r, p[1] = c.g, p[2] = c.b;
      }
    const std::string path = dir + "/" + sm.name + ".exr";
    auto out = OIIO::ImageOutput::create(path);
    OIIO::ImageSpec spec(w, w / 2, 3, OIIO::TypeDesc::FLOAT);
    if (!out || !out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, rgb.data()) || !out->close()) {
      std::fprintf(stderr, "envpis_stress_maps: cannot write %s\n", path.c_str());
      return 1;
    }
    std::printf("%s\n", path.c_str());
  }
  return 0;
}
