// SPDX-License-Identifier: Apache-2.0
#include "png_encode.h"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "envpis/common.h"

namespace envpis::detail {

void encode_png(const std::string& path, int width, int height, int channels, const float* pixels) {
  static const png_uint_32 kFormats[] = {PNG_FORMAT_GRAY, PNG_FORMAT_GA, PNG_FORMAT_RGB, PNG_FORMAT_RGBA};
  if (width < 1 || height < 1 || channels < 1 || channels > 4)
    throw Error("cannot write '" + path + "': PNG takes 1 to 4 channels, not " + std::to_string(channels) + " of " +
                std::to_string(width) + "x" + std::to_string(height) + " pixels");
  std::vector<std::uint8_t> codes(std::size_t(width) * std::size_t(height) * std::size_t(channels));
  for (std::size_t i = 0; i < codes.size(); ++i) {
    const float v = std::isnan(pixels[i]) ? 0.0f : std::clamp(pixels[i], 0.0f, 1.0f);
    codes[i] = static_cast<std::uint8_t>(std::lround(v * 255.0f));
  }
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  img.width = static_cast<png_uint_32>(width);
  img.height = static_cast<png_uint_32>(height);
  img.format = kFormats[channels - 1];
  const bool ok = png_image_write_to_file(&img, path.c_str(), 0, codes.data(), 0, nullptr) != 0;
  const std::string message = img.message;
  png_image_free(&img);
  if (!ok) throw Error("cannot write '" + path + "': " + message);
}

}  // namespace envpis::detail
