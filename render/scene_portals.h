// SPDX-License-Identifier: Apache-2.0
// The scene file's "portals" field (docs/scene-format.md): an array of quads, each
// {"vertices": [[x, y, z], [x, y, z], [x, y, z], [x, y, z]]}, counter-clockwise seen from outside the
// room, as envpis::Portals requires. Kept out of scene_file.cpp, which is long enough.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "envpis/portals.h"

namespace envpis::render {

/// Parses and validates the portals; throws Error with one line naming the file and the portal
/// ("scene.json: portals[1]: not planar (...)") for a malformed entry or a quad Portals rejects.
Portals parse_portals(const nlohmann::json& portals, const std::string& file);

}  // namespace envpis::render
