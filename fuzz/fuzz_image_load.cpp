// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: EnvironmentMap::load on arbitrary file contents.
//
// Input layout: byte 0 selects the file name extension (low 4 bits), the layout option (bits 4-5) and
// the scale option (bits 6-7); the remaining bytes are the file's contents, written to a temporary
// file that load() then opens: OpenEXR by OpenEXR and PNG by libpng themselves, other formats through
// OpenImageIO (its glue linked in and instrumented in scripts/fuzz.sh's build).
//
// Contract checked: load() either throws envpis::Error or returns a map with positive size whose
// texels are all finite, >= 0 and <= 1e30 (the documented repair policy), and whose eval() is finite
// and >= 0 in every direction. Any other exception, a crash, a sanitizer report, a leak or a hang is a
// finding.
//
// load() picks one reader (by the content for OpenEXR, Radiance HDR, PFM, TIFF and PNG, else by the
// extension) and never uses OpenImageIO's fallback of offering a file to all of its readers. The
// "try_all_readers" attribute is turned off here as well, so that no other path through OpenImageIO
// reaches those third-party readers (DICOM, FFmpeg, WebP, RAW, ...; see fuzz/README.md).
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "envpis/environment_map.h"

namespace {

// Repeats give the two formats environment maps actually come in most of the probability.
const char* const kExtensions[16] = {".exr", ".hdr", ".exr", ".hdr", ".pic", ".rgbe", ".EXR", ".png",
                                     ".tif", ".pfm", ".ppm", ".tga", ".jpg", ".bmp", "",     ".txt"};
const envpis::MapLayout kLayouts[4] = {envpis::MapLayout::Auto, envpis::MapLayout::LatLong,
                                       envpis::MapLayout::EqualArea, envpis::MapLayout::Auto};
const float kScales[4] = {1.0f, 0.0f, 1e30f, 1e-30f};

std::string g_dir;  // private scratch directory of this process

void remove_scratch() {
  if (g_dir.empty()) return;
  for (const char* ext : kExtensions) std::remove((g_dir + "/input" + ext).c_str());
  rmdir(g_dir.c_str());
}

[[noreturn]] void violated(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_image_load: contract violated: %s (%s)\n", what, detail.c_str());
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* tmp = std::getenv("TMPDIR");
  std::string templ = std::string(tmp && *tmp ? tmp : "/tmp") + "/envpis-fuzz-load-XXXXXX";
  if (!mkdtemp(templ.data())) {
    std::perror("fuzz_image_load: mkdtemp");
    std::abort();
  }
  g_dir = templ;
  std::atexit(remove_scratch);
  OIIO::attribute("try_all_readers", 0);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t sel = data[0];
  const std::string path = g_dir + "/input" + kExtensions[sel & 15];
  {
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) {
      std::perror("fuzz_image_load: fopen");
      std::abort();
    }
    if (size > 1 && std::fwrite(data + 1, 1, size - 1, f) != size - 1) std::abort();
    std::fclose(f);
  }

  envpis::EnvironmentMapOptions options;
  options.layout = kLayouts[(sel >> 4) & 3];
  options.scale = kScales[(sel >> 6) & 3];
  try {
    const envpis::EnvironmentMap map = envpis::EnvironmentMap::load(path, options);
    if (map.width() <= 0 || map.height() <= 0) violated("map has no pixels", std::to_string(map.width()));
    if (map.layout() == envpis::MapLayout::EqualArea && map.width() != map.height())
      violated("non-square equal-area map", std::to_string(map.width()) + "x" + std::to_string(map.height()));
    for (int y = 0; y < map.height(); ++y)
      for (int x = 0; x < map.width(); ++x) {
        const envpis::Rgb t = map.texel(x, y);
        for (float v : {t.r, t.g, t.b})
          if (!(v >= 0.0f && v <= 1e30f)) violated("texel outside [0, 1e30] after repair", std::to_string(v));
      }
    // A few directions, including the poles, the seam and degenerate ones.
    const envpis::Vec3 dirs[] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {1, -1e-7f, 0}, {-1, 0, 0},
                                 {0.3f, -0.4f, 0.5f}, {1, 1, 1}, {0, 0, 0}, {NAN, 0, 1}, {INFINITY, 0, 0}};
    for (const envpis::Vec3& d : dirs) {
      const envpis::Rgb L = map.eval(d);
      for (float v : {L.r, L.g, L.b})
        if (!(v >= 0.0f) || !std::isfinite(v)) violated("eval() not finite and >= 0", std::to_string(v));
    }
  } catch (const envpis::Error&) {
    // The documented outcome for a bad file.
  }
  std::remove(path.c_str());
  return 0;
}
