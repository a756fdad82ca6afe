// SPDX-License-Identifier: Apache-2.0
// EnvironmentMap::load: the envpis::io component (image files by image_file.h).
#include <filesystem>

#include "envpis/environment_map.h"
#include "envpis/image_file.h"
#include "../image_format.h"

namespace envpis {

namespace {
constexpr std::size_t kMaxTexels = std::size_t(1) << 28;  // 268M texels, 3.2 GB of RGB floats
}  // namespace

EnvironmentMap EnvironmentMap::load(const std::string& path, const EnvironmentMapOptions& options) {
  ImageFile img;
  std::string by_extension;
  try {
    ImageReadLimits limits;
    limits.max_channels = 3;  // only the first three channels are used: read no more
    limits.max_texels = kMaxTexels;
    img = read_image_file(path, limits);
    std::string ext = detail::lower(std::filesystem::path(path).extension().string());
    if (!ext.empty()) ext.erase(0, 1);
    // For the wrong-extension warning only; OpenImageIO is asked only for an unusual extension.
    try {
      by_extension = image_format_for_extension(ext);
    } catch (const Error&) {  // no OpenImageIO module: the map is read, the warning is lost
    }
  } catch (const Error& e) {
    throw Error("cannot load environment map '" + path + "': " + e.what());
  }
  std::vector<float> rgb(std::size_t(img.width) * std::size_t(img.height) * 3);
  for (std::size_t i = 0, n = std::size_t(img.width) * img.height; i < n; ++i) {
    const float* p = &img.pixels[i * img.channels];
    rgb[i * 3 + 0] = p[0];
    rgb[i * 3 + 1] = img.channels >= 3 ? p[1] : p[0];
    rgb[i * 3 + 2] = img.channels >= 3 ? p[2] : p[0];
  }
  img.pixels = {};
  EnvironmentMap map = from_pixels(img.width, img.height, std::move(rgb), options);
  map.path_ = path;
  map.report_.format = img.format;
  map.report_.extension_format = by_extension;
  return map;
}

}  // namespace envpis
