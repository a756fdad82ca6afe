// SPDX-License-Identifier: Apache-2.0
#pragma once
// PNG images decoded by libpng's simplified API, never by OpenImageIO's PNG reader.
//
// Why not OpenImageIO: its PNG reader (2.4) leaks the error string it builds in its read callback
// whenever libpng longjmps out of a corrupt file, and lets libpng print "libpng error: ..." on stderr
// before returning its own error. libpng's simplified API keeps both inside a png_image: no leak,
// one message, and every PNG colour type converted to RGB(A) by libpng itself.
#include <cstddef>
#include <cstdint>
#include <string>

#include "envpis/image_file.h"

namespace envpis::detail {

/// Decodes the PNG at `path` (already known to start with the PNG signature) as RGB, or RGBA when the
/// file has alpha and limits.max_channels >= 4; values are code / max code. Throws envpis::Error with a
/// one-line reason (libpng's) on a corrupt or truncated file, or beyond the limits.
ImageFile decode_png(const std::string& path, const ImageReadLimits& limits);
/// The same for a PNG held in memory.
ImageFile decode_png(const std::uint8_t* bytes, std::size_t size, const ImageReadLimits& limits);

}  // namespace envpis::detail
