// SPDX-License-Identifier: Apache-2.0
#include "png_decode.h"

#include <png.h>

#include <cstdint>
#include <new>

#include "envpis/common.h"

namespace envpis::detail {

namespace {

// Frees the png_image on every exit, including the throws below.
struct PngImage {
  png_image img{};
  PngImage() { img.version = PNG_IMAGE_VERSION; }
  ~PngImage() { png_image_free(&img); }
  PngImage(const PngImage&) = delete;
  PngImage& operator=(const PngImage&) = delete;
};

// Integer samples to RGB floats in [0, 1], as OpenImageIO normalized them before (code value / max),
// dropping alpha. libpng premultiplies 16-bit (linear) colour by alpha: that is undone, so colour is
// what the file stores whatever its alpha (0 where alpha is 0), as for every other format.
template <class T>
std::vector<float> to_rgb(const std::vector<T>& codes, int channels, float max_code, bool premultiplied) {
  const std::size_t texels = codes.size() / channels;
  std::vector<float> out(texels * 3);
  const float scale = 1.0f / max_code;
  for (std::size_t i = 0; i < texels; ++i) {
    const T* c = &codes[i * channels];
    float k = scale;
    if (channels == 4 && premultiplied) k = c[3] > 0 ? 1.0f / static_cast<float>(c[3]) : 0.0f;
    for (int j = 0; j < 3; ++j) out[i * 3 + j] = static_cast<float>(c[j]) * k;
  }
  return out;
}

template <class T>
std::vector<float> finish(png_image& img, std::size_t texels, int channels, float max_code) {
  std::vector<T> codes(texels * channels);
  if (!png_image_finish_read(&img, nullptr, codes.data(), 0, nullptr))
    throw Error("PNG reader: " + std::string(img.message));
  return to_rgb(codes, channels, max_code, sizeof(T) == 2);
}

}  // namespace

DecodedPng decode_png(const std::string& path, std::size_t max_texels) {
  PngImage png;
  if (!png_image_begin_read_from_file(&png.img, path.c_str()))
    throw Error("PNG reader: " + std::string(png.img.message));
  const std::size_t texels = std::size_t(png.img.width) * std::size_t(png.img.height);
  if (png.img.width == 0 || png.img.height == 0) throw Error("the image has no pixels");
  if (texels > max_texels)
    throw Error("the image is too large (" + std::to_string(png.img.width) + "x" + std::to_string(png.img.height) + ")");
  // 16-bit files keep their 16 bits (libpng takes them as linear unless a gAMA chunk says otherwise);
  // 8-bit files are read as their sRGB-encoded code values, like every 8-bit texture format here.
  // With an alpha channel, alpha is read too (no compositing onto a background) and then dropped.
  const bool sixteen = (png.img.format & PNG_FORMAT_FLAG_LINEAR) != 0;
  const bool alpha = (png.img.format & PNG_FORMAT_FLAG_ALPHA) != 0;
  png.img.format = (sixteen ? PNG_FORMAT_LINEAR_RGB : PNG_FORMAT_RGB) | (alpha ? PNG_FORMAT_FLAG_ALPHA : 0);
  DecodedPng out;
  out.width = static_cast<int>(png.img.width);
  out.height = static_cast<int>(png.img.height);
  const int channels = alpha ? 4 : 3;
  try {
    out.rgb = sixteen ? finish<std::uint16_t>(png.img, texels, channels, 65535.0f)
                      : finish<std::uint8_t>(png.img, texels, channels, 255.0f);
  } catch (const std::bad_alloc&) {
    throw Error("not enough memory for " + std::to_string(out.width) + "x" + std::to_string(out.height) + " texels");
  }
  return out;
}

}  // namespace envpis::detail
