// SPDX-License-Identifier: Apache-2.0
#pragma once
// PNG images written by libpng's simplified API.
#include <string>

namespace envpis::detail {

/// Writes 8-bit grey (1 channel), grey + alpha (2), RGB (3) or RGBA (4): each value clamped to [0, 1]
/// and rounded to code value / 255, no encoding applied. Throws envpis::Error with a one-line reason.
void encode_png(const std::string& path, int width, int height, int channels, const float* pixels);

}  // namespace envpis::detail
