// SPDX-License-Identifier: Apache-2.0
#pragma once
// Image files as float pixels (envpis::io): what EnvironmentMap::load reads, and what a renderer or a
// tool reads textures from and writes its images to.
//
// OpenEXR and PNG are read and written by OpenEXR and libpng themselves. Every other format goes through
// OpenImageIO, which envpis::io does not link: it loads it on first use from a module
// (libenvpis_oiio.so, installed in <libdir>/envpis; the environment variable ENVPIS_OIIO_MODULE names
// another path). OpenImageIO's ~260 shared libraries would cost every process half a second to start.
#include <cstddef>
#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "envpis/common.h"

namespace envpis {

/// Decoded pixels: `channels` floats per pixel, row after row, top row first.
struct ImageFile {
  int width = 0;
  int height = 0;
  int channels = 0;
  std::vector<float> pixels;
  /// The file stores integers, and the values are code / max code: colour in such a file is usually
  /// sRGB-encoded. False for floating-point files (OpenEXR, Radiance HDR, PFM, float TIFF).
  bool integer_coded = false;
  /// The reader: "openexr", "png", or OpenImageIO's name for it ("hdr", "pnm", "tiff", "jpeg", ...).
  std::string format;
};

/// Refused before any pixel is decoded or buffer allocated, from what the header claims.
struct ImageReadLimits {
  int max_channels = 4;                          ///< read the first max_channels channels only
  std::size_t max_texels = std::size_t(1) << 28;  ///< width * height
  int max_side = 0;                              ///< width and height; 0: no limit
};

/// Reads an image file. The reader is chosen by the file's first bytes for OpenEXR, Radiance HDR, PFM,
/// TIFF, PNG and JPEG, else by its extension; never by offering the file to every reader. Throws Error
/// with a one-line reason (without the path) when the file is missing, not a regular file, empty, of an
/// unknown format, corrupt, truncated, beyond the limits, or needs OpenImageIO and its module is missing.
ImageFile read_image_file(const std::string& path, const ImageReadLimits& limits = {});

/// Decodes a PNG or JPEG image held in memory (a glTF buffer's image). Throws Error as read_image_file.
ImageFile decode_image(const std::uint8_t* bytes, std::size_t size, const ImageReadLimits& limits = {});

/// The reader read_image_file would use for a file extension without the dot ("exr", "HDR"): "openexr",
/// "hdr", ...; empty when no reader takes it. Asks OpenImageIO (loading its module) only for extensions
/// outside OpenEXR, Radiance HDR, PNM/PFM, PNG, TIFF and JPEG.
std::string image_format_for_extension(const std::string& extension);

/// A metadata entry written into an OpenEXR file's header (other formats ignore them).
struct ImageAttribute {
  std::string name;
  std::variant<int, std::string> value;
};

/// Writes float pixels in the format of path's extension: .exr by OpenEXR (32-bit float, ZIP), .png by
/// libpng (8-bit, each value clamped to [0, 1] and rounded; no encoding is applied), any other through
/// OpenImageIO. channel_names: OpenEXR's channel names (default by count: Y; Y, A; R, G, B; R, G, B, A).
/// Throws Error with a one-line reason naming the path.
void write_image_file(const std::string& path, int width, int height, int channels, const float* pixels,
                      const std::vector<std::string>& channel_names = {},
                      const std::vector<ImageAttribute>& attributes = {});

}  // namespace envpis
