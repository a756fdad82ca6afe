// SPDX-License-Identifier: Apache-2.0
#pragma once
// PNG environment maps, decoded by libpng's simplified API instead of OpenImageIO's PNG reader.
//
// Why not OpenImageIO: its PNG reader (2.4) leaks the error string it builds in its read callback
// whenever libpng longjmps out of a corrupt file, and lets libpng print "libpng error: ..." on stderr
// before returning its own error. libpng's simplified API keeps both inside a png_image: no leak,
// one message, and every PNG colour type converted to RGB by libpng itself.
#include <string>
#include <vector>

namespace envpis::detail {

struct DecodedPng {
  int width = 0;
  int height = 0;
  std::vector<float> rgb;  // width * height * 3, row after row, code values / max code (0..1)
};

/// Decodes the PNG at `path` (already known to start with the PNG signature). Throws envpis::Error
/// with a one-line reason (libpng's) on a corrupt or truncated file, or on more than max_texels texels.
DecodedPng decode_png(const std::string& path, std::size_t max_texels);

}  // namespace envpis::detail
