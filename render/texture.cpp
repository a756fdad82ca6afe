// SPDX-License-Identifier: Apache-2.0
#include "render/texture.h"

#include <algorithm>
#include <cmath>

#include "envpis/image_file.h"

namespace envpis::render {

TextureWrap wrap_from_gltf(int code) {
  switch (code) {
    case 10497: return TextureWrap::Repeat;
    case 33071: return TextureWrap::Clamp;
    case 33648: return TextureWrap::Mirror;
  }
  throw Error("unknown texture wrap mode " + std::to_string(code) + " (expected 10497, 33071 or 33648)");
}

Texture::Texture(int width, int height, std::vector<float> texels)
    : width_(width), height_(height), texels_(std::move(texels)) {
  if (width < 1 || height < 1 || texels_.size() != std::size_t(width) * std::size_t(height) * 4)
    throw Error("texture: " + std::to_string(texels_.size()) + " floats for " + std::to_string(width) + " x " +
                std::to_string(height) + " RGBA texels");
}

namespace {

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

ImageReadLimits texture_limits() {
  ImageReadLimits limits;
  limits.max_channels = 4;
  limits.max_side = 16384;
  return limits;
}

/// RGBA floats from a decoded image (grey -> RGB, missing alpha -> 1).
std::shared_ptr<const Texture> to_texture(const ImageFile& img, bool srgb) {
  const int nc = img.channels;
  // Only 8/16-bit integer images carry an sRGB encoding; float images are linear already.
  const bool encoded = srgb && img.integer_coded;
  std::vector<float> rgba(std::size_t(img.width) * img.height * 4);
  for (std::size_t i = 0, n = std::size_t(img.width) * img.height; i < n; ++i) {
    const float* p = &img.pixels[i * nc];
    float c[4] = {p[0], nc >= 3 ? p[1] : p[0], nc >= 3 ? p[2] : p[0], nc == 2 ? p[1] : (nc >= 4 ? p[3] : 1.0f)};
    for (int k = 0; k < 4; ++k) {
      float v = std::isfinite(c[k]) ? c[k] : 0.0f;
      if (encoded && k < 3) v = srgb_to_linear(std::clamp(v, 0.0f, 1.0f));
      rgba[i * 4 + k] = v;
    }
  }
  return std::make_shared<const Texture>(img.width, img.height, std::move(rgba));
}

}  // namespace

std::shared_ptr<const Texture> Texture::load_file(const std::string& path, bool srgb, const std::string& what) {
  try {
    return to_texture(read_image_file(path, texture_limits()), srgb);
  } catch (const Error& e) {
    throw Error(what + ": cannot read image '" + path + "': " + e.what());
  }
}

std::shared_ptr<const Texture> Texture::load_memory(const std::vector<std::uint8_t>& bytes, bool srgb,
                                                    const std::string& what) {
  if (bytes.size() < 4) throw Error(what + ": empty image data");
  try {
    return to_texture(decode_image(bytes.data(), bytes.size(), texture_limits()), srgb);
  } catch (const Error& e) {
    throw Error(what + ": cannot decode the embedded image: " + e.what());
  }
}

Rgba Texture::texel(int x, int y) const {
  const float* p = &texels_[(std::size_t(y) * width_ + x) * 4];
  return {p[0], p[1], p[2], p[3]};
}

namespace {

/// Integer texel coordinate i wrapped into [0, n).
int wrap_index(int i, int n, TextureWrap w) {
  switch (w) {
    case TextureWrap::Clamp: return std::clamp(i, 0, n - 1);
    case TextureWrap::Repeat: {
      const int m = i % n;
      return m < 0 ? m + n : m;
    }
    case TextureWrap::Mirror: {
      const int period = 2 * n;
      int m = i % period;
      if (m < 0) m += period;
      return m < n ? m : period - 1 - m;
    }
  }
  return 0;
}

}  // namespace

Rgba Texture::bilinear(Point2 uv, TextureWrap ws, TextureWrap wt) const {
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return texel(0, 0);
  // Keep the coordinates in a range where float -> int is exact (repeat/mirror are periodic anyway).
  const float x = std::clamp(uv.x * width_ - 0.5f, -1e6f, 1e6f), y = std::clamp(uv.y * height_ - 0.5f, -1e6f, 1e6f);
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  const int x0 = wrap_index(int(fx), width_, ws), x1 = wrap_index(int(fx) + 1, width_, ws);
  const int y0 = wrap_index(int(fy), height_, wt), y1 = wrap_index(int(fy) + 1, height_, wt);
  const Rgba a = texel(x0, y0), b = texel(x1, y0), c = texel(x0, y1), d = texel(x1, y1);
  auto lerp2 = [&](float pa, float pb, float pc, float pd) {
    return (pa * (1 - tx) + pb * tx) * (1 - ty) + (pc * (1 - tx) + pd * tx) * ty;
  };
  return {lerp2(a.r, b.r, c.r, d.r), lerp2(a.g, b.g, c.g, d.g), lerp2(a.b, b.b, c.b, d.b), lerp2(a.a, b.a, c.a, d.a)};
}

Point2 UvTransform::apply(Point2 uv) const {
  // The extension's matrix product T * R * S with R = [[cos, sin], [-sin, cos]] (its reference code).
  const float c = std::cos(rotation), s = std::sin(rotation);
  const float x = uv.x * scale.x, y = uv.y * scale.y;
  return {c * x + s * y + offset.x, -s * x + c * y + offset.y};
}

}  // namespace envpis::render
