// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal: OpenEXR files read and written by OpenEXR itself (not through OpenImageIO; see
// oiio_module_abi.h for why).
#include <string>
#include <vector>

#include "envpis/image_file.h"

namespace envpis::detail {

/// Decodes an OpenEXR file's first part as float: channels R, G, B (or Y without them), then A (those
/// present, in that order), then the others in the file's order, at most limits.max_channels of them. The data window is
/// the image. Header claims are bounded before any buffer is allocated. Throws envpis::Error with a
/// one-line reason.
ImageFile read_exr(const std::string& path, const ImageReadLimits& limits);

/// Writes float channels, ZIP-compressed, with the given channel names (default Y, Y A, R G B or R G B A)
/// and attributes (int or string). Throws envpis::Error with a one-line reason.
void write_exr(const std::string& path, int width, int height, int channels, const float* pixels,
               const std::vector<std::string>& channel_names, const std::vector<ImageAttribute>& attributes);

}  // namespace envpis::detail
