// SPDX-License-Identifier: Apache-2.0
#include "image_format.h"

#include <cctype>

namespace envpis::detail {

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const char* format_display_name(const std::string& format) {
  if (format == "openexr") return "OpenEXR";
  if (format == "hdr") return "Radiance HDR";
  if (format == "pnm") return "PFM";
  if (format == "png") return "PNG";
  if (format == "tiff") return "TIFF";
  return nullptr;
}

}  // namespace envpis::detail
