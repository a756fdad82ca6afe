// SPDX-License-Identifier: Apache-2.0
// Portals in glTF files (docs/scene-format.md, "Portals in glTF"): a node named "portal..." is read
// as a portal quad (node and object transforms applied, mirrored ones too), not as geometry, in a
// glTF object of a scene file and in a glTF file rendered on its own; bad portal geometry is a
// one-line error naming the file and the node, from the library and from the command line.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "cli_util.h"
#include "test_util.h"
#include "render/gltf.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

using test::TempDir;

std::string base64(const std::vector<unsigned char>& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < in.size(); i += 3) {
    const unsigned v = unsigned(in[i]) << 16 | (i + 1 < in.size() ? unsigned(in[i + 1]) << 8 : 0u) |
                       (i + 2 < in.size() ? unsigned(in[i + 2]) : 0u);
    out += k[(v >> 18) & 63];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? k[v & 63] : '=';
  }
  return out;
}

struct MeshSpec {
  std::string node;
  std::vector<float> xyz;  // glTF coordinates (+Y up)
  std::vector<unsigned short> indices;
  std::string translation = "[0, 0, 0]";
};

/// A glTF 2.0 file with one node per mesh, all in one base64 buffer.
std::string gltf_text(const std::vector<MeshSpec>& meshes) {
  std::vector<unsigned char> buf;
  std::string views, accessors, ms, nodes, scene;
  auto append = [&](const void* p, std::size_t n) {
    const std::size_t at = buf.size();
    buf.insert(buf.end(), static_cast<const unsigned char*>(p), static_cast<const unsigned char*>(p) + n);
    while (buf.size() % 4) buf.push_back(0);
    return at;
  };
  for (std::size_t m = 0; m < meshes.size(); ++m) {
    const MeshSpec& s = meshes[m];
    const std::size_t pa = append(s.xyz.data(), s.xyz.size() * 4), ia = append(s.indices.data(), s.indices.size() * 2);
    const std::string sep = m ? "," : "";
    views += sep + "{\"buffer\":0,\"byteOffset\":" + std::to_string(pa) + ",\"byteLength\":" + std::to_string(s.xyz.size() * 4) +
             "},{\"buffer\":0,\"byteOffset\":" + std::to_string(ia) + ",\"byteLength\":" + std::to_string(s.indices.size() * 2) + "}";
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (std::size_t i = 0; i < s.xyz.size(); ++i) {  // NaN compares false: min/max stay finite
      lo[i % 3] = s.xyz[i] < lo[i % 3] ? s.xyz[i] : lo[i % 3];
      hi[i % 3] = s.xyz[i] > hi[i % 3] ? s.xyz[i] : hi[i % 3];
    }
    auto v3 = [](const float* a) { return "[" + std::to_string(a[0]) + "," + std::to_string(a[1]) + "," + std::to_string(a[2]) + "]"; };
    accessors += sep + "{\"bufferView\":" + std::to_string(2 * m) + ",\"componentType\":5126,\"count\":" +
                 std::to_string(s.xyz.size() / 3) + ",\"type\":\"VEC3\",\"min\":" + v3(lo) + ",\"max\":" + v3(hi) +
                 "},{\"bufferView\":" + std::to_string(2 * m + 1) + ",\"componentType\":5123,\"count\":" +
                 std::to_string(s.indices.size()) + ",\"type\":\"SCALAR\"}";
    ms += sep + "{\"primitives\":[{\"attributes\":{\"POSITION\":" + std::to_string(2 * m) + "},\"indices\":" +
          std::to_string(2 * m + 1) + ",\"material\":0}]}";
    nodes += sep + "{\"name\":\"" + s.node + "\",\"mesh\":" + std::to_string(m) + ",\"translation\":" + s.translation + "}";
    scene += sep + std::to_string(m);
  }
  return "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[" + scene + "]}],\"nodes\":[" + nodes +
         "],\"meshes\":[" + ms + "],\"materials\":[{\"name\":\"grey\"}],\"accessors\":[" + accessors +
         "],\"bufferViews\":[" + views + "],\"buffers\":[{\"byteLength\":" + std::to_string(buf.size()) +
         ",\"uri\":\"data:application/octet-stream;base64," + base64(buf) + "\"}]}";
}

// A floor (glTF y = 0) and the window of scenes/interior-window.json: renderer x = 2, y in
// [-0.75, 0.75], z in [1, 2], facing +X. glTF (x, y, z) = renderer (x, z, -y); front face towards +X.
MeshSpec floor_mesh() { return {"floor", {-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2}, {0, 2, 1, 0, 3, 2}}; }
MeshSpec window(std::string name = "portal-window") {
  return {std::move(name), {2, 1, 0.75f, 2, 1, -0.75f, 2, 2, -0.75f, 2, 2, 0.75f}, {0, 1, 2, 0, 2, 3}, "[0, 0.5, 0]"};
}

bool near(Vec3 a, Vec3 b) { return length(a - b) < 1e-5f; }

TEST(GltfPortals, PortalNodeIsAQuadNotGeometry) {
  TempDir dir;
  const std::string file = dir.write("room.gltf", gltf_text({floor_mesh(), window()}));
  const GltfModel m = load_gltf(file);
  ASSERT_EQ(m.parts.size(), 1u);
  EXPECT_EQ(m.parts[0].mesh.positions.size(), 4u);  // the floor only
  ASSERT_EQ(m.portals.size(), 1u);
  EXPECT_EQ(m.portals[0].node, "portal-window");
  const Quad& q = m.portals[0].quad;  // the node's translation (glTF +0.5 up) applied, in the file's winding
  EXPECT_TRUE(near(q.v[0], {2, -0.75f, 1.5f})) << q.v[0].x << " " << q.v[0].y << " " << q.v[0].z;
  EXPECT_TRUE(near(q.v[1], {2, 0.75f, 1.5f}));
  EXPECT_TRUE(near(q.v[2], {2, 0.75f, 2.5f}));
  const Portals p({q});
  EXPECT_GT(p.normal(0).x, 0.999f);  // front face out of the room: counter-clockwise from outside
  EXPECT_TRUE(p.passes({0, 0, 1.5f}, normalize(Vec3{2, 0, 0.5f})));

  // On its own, as a scene.
  const Scene s = load_scene_file(file);
  ASSERT_EQ(s.portals().size(), 1);
  EXPECT_GT(s.portals().normal(0).x, 0.999f);
  for (const auto& o : s.objects()) EXPECT_EQ(o.name.find("portal"), std::string::npos) << o.name;
}

TEST(GltfPortals, SceneFileTransformsPortalsAndKeepsItsOwn) {
  TempDir dir;
  dir.write("room.gltf", gltf_text({floor_mesh(), window()}));
  const std::string head = R"({"camera": {"from": [0, -3, 1], "to": [0, 0, 1]},
    "environment": {"sky": {"width": 32, "height": 16}}, "objects": [)";
  const std::string json_portal = R"(], "portals": [{"vertices": [[-1, -1, 3], [1, -1, 3], [1, 1, 3], [-1, 1, 3]]}]})";
  const Scene moved = load_scene_file(dir.write("a.json",
      head + R"({"type": "gltf", "name": "room", "file": "room.gltf", "translate": [1, 0, 0]})" + json_portal));
  ASSERT_EQ(moved.portals().size(), 2);  // the glTF's first, then the file's
  EXPECT_TRUE(near(moved.portals().quad(0).v[0], {3, -0.75f, 1.5f}));
  EXPECT_GT(moved.portals().normal(0).x, 0.999f);
  EXPECT_GT(moved.portals().normal(1).z, 0.999f);
  // A mirroring transform keeps the portal facing out of the (mirrored) room.
  const Scene mirrored = load_scene_file(dir.write("b.json",
      head + R"({"type": "gltf", "name": "room", "file": "room.gltf", "scale": [-1, 1, 1]}]})"));
  ASSERT_EQ(mirrored.portals().size(), 1);
  EXPECT_LT(mirrored.portals().normal(0).x, -0.999f);
  EXPECT_TRUE(mirrored.portals().passes({0, 0, 1.5f}, normalize(Vec3{-2, 0, 0.5f})));
}

struct BadCase {
  MeshSpec portal;
  std::string expect;
};

std::vector<BadCase> bad_cases() {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  MeshSpec triangle = window("portal-tri"), bent = window("portal-bent"), dart = window("portal-dart"),
           line = window("portal-line"), flipped = window("portal-flipped"), hexa = window("portal-hex"),
           nanq = window("portal-nan");
  triangle.indices = {0, 1, 2};
  bent.xyz[9] = 2.5f;                       // vertex 3 off the plane x = 2 by 0.5 (glTF x is renderer x)
  dart.xyz[7] = 1.2f, dart.xyz[8] = 0;      // vertex 2 pulled inside: a reflex corner at it
  line.xyz = {2, 1, 0.75f, 2, 1, 0.25f, 2, 1, -0.25f, 2, 1, -0.75f};
  flipped.indices = {0, 1, 2, 0, 3, 2};     // the second triangle wound the other way
  hexa.xyz.insert(hexa.xyz.end(), {2, 3, 0, 2, 3, 1});
  hexa.indices.insert(hexa.indices.end(), {3, 2, 4, 3, 4, 5});
  nanq.xyz[4] = nan;
  return {{triangle, "portal node 'portal-tri': not a quad (3 distinct vertices, expected 4)"},
          {bent, "portal node 'portal-bent': not planar"},
          {dart, "portal node 'portal-dart': not convex"},
          {line, "portal node 'portal-line': degenerate"},
          {flipped, "portal node 'portal-flipped': not a quad (its triangles overlap or are wound inconsistently)"},
          {hexa, "portal node 'portal-hex': not a quad (6 distinct vertices, expected 4)"},
          {nanq, "portal node 'portal-nan': "}};
}

TEST(GltfPortals, BadPortalsAreOneLineErrorsNamingFileAndNode) {
  TempDir dir;
  int i = 0;
  for (const BadCase& c : bad_cases()) {
    const std::string file = dir.write("bad-" + std::to_string(i++) + ".gltf", gltf_text({floor_mesh(), c.portal}));
    try {
      (void)load_gltf(file);
      ADD_FAILURE() << "accepted " << c.portal.node;
    } catch (const Error& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(file + ": " + c.expect, 0), 0u) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    }
  }
  // Nine portals: one more than Portals holds, across the glTF and the scene file.
  std::vector<MeshSpec> nine{floor_mesh()};
  for (int k = 0; k < 9; ++k) {
    nine.push_back(window("portal-" + std::to_string(k)));
    nine.back().translation = "[0, " + std::to_string(0.01 * k) + ", 0]";
  }
  const std::string file = dir.write("nine.gltf", gltf_text(nine));
  try {
    (void)load_gltf(file);
    ADD_FAILURE() << "accepted nine portals";
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(file + ": portal node 'portal-", 0), 0u) << m;
    EXPECT_NE(m.find("at most 8 portals"), std::string::npos) << m;
  }
}

TEST(GltfPortals, BadPortalsExitNonZeroWithOneLine) {
  TempDir dir;
  std::vector<std::pair<std::string, std::string>> cases;
  int i = 0;
  for (const BadCase& c : bad_cases()) {
    const std::string file = dir.write("bad-" + std::to_string(i++) + ".gltf", gltf_text({floor_mesh(), c.portal}));
    const std::string scene = dir.write("bad-" + std::to_string(i) + ".json",
        R"({"camera": {"from": [0, -3, 1], "to": [0, 0, 1]}, "objects": [{"type": "gltf", "file": ")" + file + R"("}]})");
    const std::string out = test::shell_quote((dir.path / "out.exr").string());
    cases.push_back({"render --scene " + test::shell_quote(file) + " --spp 1 --width 8 --height 4 --out " + out,
                     file + ": " + c.expect});
    cases.push_back({"render --scene " + test::shell_quote(scene) + " --spp 1 --width 8 --height 4 --out " + out,
                     scene + ": objects[0].file: " + file + ": " + c.expect});
  }
  test::expect_one_line_errors(cases, 2);
  EXPECT_FALSE(std::filesystem::exists(dir.path / "out.exr"));
}

}  // namespace
}  // namespace envpis::render
