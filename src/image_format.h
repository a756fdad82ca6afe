// SPDX-License-Identifier: Apache-2.0
// Internal: names of the image formats environment maps come in, shared by EnvironmentMap's warnings
// (core) and its loader (envpis::io).
#pragma once

#include <string>

namespace envpis::detail {

/// ASCII lower case (file extensions).
std::string lower(std::string s);
/// "OpenEXR", "Radiance HDR", "PFM", "PNG", "TIFF" for OpenImageIO's reader names, else nullptr.
const char* format_display_name(const std::string& format);

}  // namespace envpis::detail
