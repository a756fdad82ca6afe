// SPDX-License-Identifier: Apache-2.0
#include "render/scene_portals.h"

#include <cmath>

namespace envpis::render {

namespace {

[[noreturn]] void fail(const std::string& file, const std::string& where, const std::string& what) {
  throw Error(file + ": " + where + ": " + what);
}

Vec3 parse_vertex(const nlohmann::json& v, const std::string& file, const std::string& where) {
  if (!v.is_array() || v.size() != 3) fail(file, where, "expected an array of 3 numbers");
  float c[3];
  for (int i = 0; i < 3; ++i) {
    // The JSON parser turns NaN and infinities into null, so a non-number here is also the NaN case.
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail(file, where, "expected 3 finite numbers");
    c[i] = v[i].get<float>();
  }
  return {c[0], c[1], c[2]};
}

Quad parse_quad(const nlohmann::json& p, const std::string& file, const std::string& where) {
  if (!p.is_object()) fail(file, where, "expected an object {\"vertices\": [4 points]}");
  for (auto it = p.begin(); it != p.end(); ++it)
    if (it.key() != "vertices") fail(file, where, "unknown field '" + it.key() + "'");
  if (!p.contains("vertices")) fail(file, where, "missing field 'vertices'");
  const nlohmann::json& vs = p.at("vertices");
  if (!vs.is_array() || vs.size() != 4)
    fail(file, where + ".vertices", "expected 4 vertices (a quad), got " +
                                        (vs.is_array() ? std::to_string(vs.size()) : std::string("no array")));
  Quad q;
  for (int i = 0; i < 4; ++i)
    q.v[i] = parse_vertex(vs[static_cast<std::size_t>(i)], file, where + ".vertices[" + std::to_string(i) + "]");
  return q;
}

}  // namespace

Portals parse_portals(const nlohmann::json& portals, const std::string& file) {
  if (!portals.is_array()) fail(file, "portals", "expected an array of quads");
  Portals out;
  for (std::size_t i = 0; i < portals.size(); ++i) {
    const std::string where = "portals[" + std::to_string(i) + "]";
    const Quad q = parse_quad(portals[i], file, where);
    try {
      out.add(q);  // the library's checks: degenerate, non-planar, non-convex, too many
    } catch (const Error& e) {
      std::string m = e.what();  // "portal i: cause": the file's own name for it replaces the prefix
      const std::size_t k = m.find(": ");
      if (m.rfind("portal ", 0) == 0 && k != std::string::npos) m = m.substr(k + 2);
      fail(file, where, m);
    }
  }
  return out;
}

}  // namespace envpis::render
