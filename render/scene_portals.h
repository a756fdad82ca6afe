// SPDX-License-Identifier: Apache-2.0
// Portals from the scene inputs (docs/scene-format.md, "portals"): the scene file's "portals" field,
// an array of quads, each {"vertices": [[x, y, z], [x, y, z], [x, y, z], [x, y, z]]}, counter-clockwise
// seen from outside the room, as envpis::Portals requires; and a glTF portal node's triangles turned
// into such a quad. Every quad goes through add_portal, so the JSON and the glTF portals share the
// library's checks and the same one-line messages. Kept out of scene_file.cpp, which is long enough.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "envpis/portals.h"

namespace envpis::render {

/// Adds q to out (Portals::add: degenerate, non-planar, non-convex, too many); a rejection becomes
/// Error "<context>: <cause>", context naming the file and the portal ("scene.json: portals[1]").
void add_portal(Portals& out, const Quad& q, const std::string& context);

/// Parses and validates the portals, appending them to `out`; throws Error with one line naming the
/// file and the portal ("scene.json: portals[1]: not planar (...)") for a malformed entry or a quad
/// Portals rejects.
Portals parse_portals(const nlohmann::json& portals, const std::string& file, Portals out = {});

/// The quad that a triangle mesh covers: exactly 4 distinct positions whose triangles (any number,
/// consistently wound) leave one boundary loop through all four, returned in the triangles' winding
/// order (so a mesh whose front face looks out of the room gives the quad Portals expects). Throws
/// Error ("not a quad: ...") otherwise, or for a non-finite position. Whether the quad is planar,
/// convex and not degenerate is add_portal's to check.
Quad quad_from_triangles(const std::vector<Vec3>& positions, const std::vector<std::uint32_t>& indices);

}  // namespace envpis::render
