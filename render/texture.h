// SPDX-License-Identifier: Apache-2.0
// Image textures of the renderer's materials: RGBA float texels in linear space, bilinear filtering,
// glTF wrap modes and the KHR_texture_transform UV transform.
//
// UV convention: the glTF one. (0, 0) is the image's top-left corner, v grows downwards; texel (x, y)
// covers [x, x+1] x [y, y+1] / size and its centre is sampled exactly at ((x + 0.5) / w, (y + 0.5) / h).
// Meshes keep glTF UVs as the file stores them (render/gltf.cpp reads them that way).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "envpis/common.h"

namespace envpis::render {

struct Rgba {
  float r = 0, g = 0, b = 0, a = 1;
  Rgb rgb() const { return {r, g, b}; }
};

enum class TextureWrap { Repeat, Clamp, Mirror };
/// glTF sampler codes: 10497 repeat, 33071 clamp to edge, 33648 mirrored repeat; throws Error otherwise.
TextureWrap wrap_from_gltf(int code);

class Texture {
 public:
  /// texels: width * height RGBA, rows top to bottom. Throws Error on a size mismatch.
  Texture(int width, int height, std::vector<float> texels);

  /// Decodes an image file (PNG, JPEG or anything OpenImageIO reads). srgb: the 8-bit values are
  /// sRGB-encoded colours (base colour, emissive) and are linearized; otherwise they are data
  /// (roughness, normals) and only scaled to [0, 1]. Throws Error naming `what` on failure.
  static std::shared_ptr<const Texture> load_file(const std::string& path, bool srgb, const std::string& what);
  /// The same from an encoded image in memory (a GLB buffer view, a data: URI).
  static std::shared_ptr<const Texture> load_memory(const std::vector<std::uint8_t>& bytes, bool srgb,
                                                    const std::string& what);

  int width() const { return width_; }
  int height() const { return height_; }
  Rgba texel(int x, int y) const;
  /// Bilinear look-up at glTF UV (u, v) with the given wrap modes.
  Rgba bilinear(Point2 uv, TextureWrap wrap_s, TextureWrap wrap_t) const;

 private:
  int width_, height_;
  std::vector<float> texels_;
};

/// KHR_texture_transform: uv' = T(offset) * R(rotation) * S(scale) * uv, in glTF UV space.
struct UvTransform {
  Point2 offset{0, 0};
  float rotation = 0;  ///< radians, counter-clockwise in UV space (as the extension defines it)
  Point2 scale{1, 1};
  Point2 apply(Point2 uv) const;
  bool identity() const { return offset.x == 0 && offset.y == 0 && rotation == 0 && scale.x == 1 && scale.y == 1; }
};

/// A texture as a material uses it: image, sampler and transform.
struct TextureRef {
  std::shared_ptr<const Texture> texture;  ///< null: no texture
  TextureWrap wrap_s = TextureWrap::Repeat, wrap_t = TextureWrap::Repeat;
  UvTransform transform;
  explicit operator bool() const { return texture != nullptr; }
  Rgba sample(Point2 uv) const { return texture->bilinear(transform.apply(uv), wrap_s, wrap_t); }
};

}  // namespace envpis::render
