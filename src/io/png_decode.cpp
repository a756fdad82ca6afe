// SPDX-License-Identifier: Apache-2.0
#include "png_decode.h"

#include <png.h>

#include <algorithm>
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

// Integer samples to floats in [0, 1] (code value / max, as OpenImageIO normalizes them), keeping `out`
// of the `stored` channels. libpng premultiplies 16-bit (linear) colour by alpha: that is undone, so
// colour is what the file stores whatever its alpha (0 where alpha is 0), as for every other format.
template <class T>
std::vector<float> to_float(const std::vector<T>& codes, int stored, int out, float max_code, bool premultiplied) {
  const std::size_t texels = codes.size() / stored;
  std::vector<float> px(texels * out);
  const float scale = 1.0f / max_code;
  for (std::size_t i = 0; i < texels; ++i) {
    const T* c = &codes[i * stored];
    float k = scale;
    if (stored == 4 && premultiplied) k = c[3] > 0 ? 1.0f / static_cast<float>(c[3]) : 0.0f;
    for (int j = 0; j < 3; ++j) px[i * out + j] = static_cast<float>(c[j]) * k;
    if (out == 4) px[i * out + 3] = static_cast<float>(c[3]) * scale;
  }
  return px;
}

template <class T>
std::vector<float> finish(png_image& img, std::size_t texels, int stored, int out, float max_code) {
  std::vector<T> codes(texels * stored);
  if (!png_image_finish_read(&img, nullptr, codes.data(), 0, nullptr))
    throw Error("PNG reader: " + std::string(img.message));
  return to_float(codes, stored, out, max_code, sizeof(T) == 2);
}

// begin: png_image_begin_read_from_file or _from_memory.
template <class Begin>
ImageFile decode(Begin begin, const ImageReadLimits& limits) {
  PngImage png;
  if (!begin(&png.img)) throw Error("PNG reader: " + std::string(png.img.message));
  const std::size_t texels = std::size_t(png.img.width) * std::size_t(png.img.height);
  if (png.img.width == 0 || png.img.height == 0) throw Error("the image has no pixels");
  if (texels > limits.max_texels ||
      (limits.max_side > 0 && std::max(png.img.width, png.img.height) > std::uint32_t(limits.max_side)))
    throw Error("the image is too large (" + std::to_string(png.img.width) + "x" + std::to_string(png.img.height) + ")");
  // 16-bit files keep their 16 bits (libpng takes them as linear unless a gAMA chunk says otherwise);
  // 8-bit files are read as their sRGB-encoded code values, like every 8-bit texture format here.
  // With an alpha channel, alpha is read too (no compositing onto a background).
  const bool sixteen = (png.img.format & PNG_FORMAT_FLAG_LINEAR) != 0;
  const bool alpha = (png.img.format & PNG_FORMAT_FLAG_ALPHA) != 0;
  png.img.format = (sixteen ? PNG_FORMAT_LINEAR_RGB : PNG_FORMAT_RGB) | (alpha ? PNG_FORMAT_FLAG_ALPHA : 0);
  ImageFile out;
  out.width = static_cast<int>(png.img.width);
  out.height = static_cast<int>(png.img.height);
  out.channels = alpha && limits.max_channels >= 4 ? 4 : 3;
  out.integer_coded = true;
  out.format = "png";
  const int stored = alpha ? 4 : 3;
  try {
    out.pixels = sixteen ? finish<std::uint16_t>(png.img, texels, stored, out.channels, 65535.0f)
                         : finish<std::uint8_t>(png.img, texels, stored, out.channels, 255.0f);
  } catch (const std::bad_alloc&) {
    throw Error("not enough memory for " + std::to_string(out.width) + "x" + std::to_string(out.height) + " texels");
  }
  return out;
}

}  // namespace

ImageFile decode_png(const std::string& path, const ImageReadLimits& limits) {
  return decode([&](png_image* img) { return png_image_begin_read_from_file(img, path.c_str()); }, limits);
}

ImageFile decode_png(const std::uint8_t* bytes, std::size_t size, const ImageReadLimits& limits) {
  return decode([&](png_image* img) { return png_image_begin_read_from_memory(img, bytes, size); }, limits);
}

}  // namespace envpis::detail
