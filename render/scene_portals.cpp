// SPDX-License-Identifier: Apache-2.0
#include "render/scene_portals.h"

#include <cmath>
#include <map>
#include <tuple>

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

void add_portal(Portals& out, const Quad& q, const std::string& context) {
  try {
    out.add(q);  // the library's checks: degenerate, non-planar, non-convex, too many
  } catch (const Error& e) {
    std::string m = e.what();  // "portal i: cause": the caller's own name for it replaces the prefix
    const std::size_t k = m.find(": ");
    if (m.rfind("portal ", 0) == 0 && k != std::string::npos) m = m.substr(k + 2);
    throw Error(context + ": " + m);
  }
}

Portals parse_portals(const nlohmann::json& portals, const std::string& file, Portals out) {
  if (!portals.is_array()) fail(file, "portals", "expected an array of quads");
  for (std::size_t i = 0; i < portals.size(); ++i) {
    const std::string where = "portals[" + std::to_string(i) + "]";
    add_portal(out, parse_quad(portals[i], file, where), file + ": " + where);
  }
  return out;
}

Quad quad_from_triangles(const std::vector<Vec3>& positions, const std::vector<std::uint32_t>& indices) {
  // Vertices are merged by exact position: a quad exported as two triangles often repeats its shared
  // corners (split normals or UVs), and the same source corner transforms to the same floats.
  std::map<std::tuple<float, float, float>, int> id_of;
  std::vector<Vec3> corners;
  std::vector<int> id(positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Vec3 p = positions[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) throw Error("a non-finite vertex position");
    auto [it, fresh] = id_of.emplace(std::make_tuple(p.x, p.y, p.z), int(corners.size()));
    if (fresh) corners.push_back(p);
    id[i] = it->second;
  }
  if (corners.size() != 4)
    throw Error("not a quad (" + std::to_string(corners.size()) + " distinct vertices, expected 4)");
  // Directed edges of the triangles; the boundary is the edges whose reverse no triangle has.
  std::map<std::pair<int, int>, int> edges;
  for (std::size_t t = 0; t + 2 < indices.size(); t += 3)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = indices[t + std::size_t(e)], b = indices[t + std::size_t((e + 1) % 3)];
      if (a >= id.size() || b >= id.size()) throw Error("not a quad (a vertex index out of range)");
      if (id[a] != id[b]) ++edges[{id[a], id[b]}];
    }
  int next[4] = {-1, -1, -1, -1};
  for (const auto& [e, count] : edges)
    if (count > 1) throw Error("not a quad (its triangles overlap or are wound inconsistently)");
  for (const auto& [e, count] : edges) {
    if (edges.count({e.second, e.first})) continue;
    if (next[e.first] >= 0) throw Error("not a quad (its triangles do not form one loop of 4 edges)");
    next[e.first] = e.second;
  }
  Quad q;
  int v = 0;
  for (int k = 0; k < 4; ++k) {
    if (next[v] < 0 || (k < 3 && next[v] == 0)) throw Error("not a quad (its triangles do not form one loop of 4 edges)");
    q.v[k] = corners[std::size_t(v)];
    v = next[v];
  }
  if (v != 0) throw Error("not a quad (its triangles do not form one loop of 4 edges)");
  return q;
}

}  // namespace envpis::render
