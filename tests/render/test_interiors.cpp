// SPDX-License-Identifier: Apache-2.0
// The interior rooms of issue 24, item 3 (scripts/make-interiors.py, scenes/interior-*.json; docs/portals.md,
// "Interior rooms"): written by the script into a temporary asset directory and loaded through their scene
// files, each room is closed except through its windows, and its portals fill the windows exactly: from
// points inside, a ray escapes to the environment exactly when it passes through a portal.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "test_util.h"
#include "cli_util.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;

struct Room {
  const char* scene;
  int portals;
  std::vector<Vec3> inside;  // points in the room, clear of its objects
};

TEST(Interiors, RoomsAreClosedExceptThroughTheirPortals) {
  test::TempDir dir;
  const std::string script = (fs::path(ENVPIS_SOURCE_DIR) / "scripts" / "make-interiors.py").string();
  ASSERT_EQ(std::system(("python3 " + test::shell_quote(script) + " " +
                         test::shell_quote((dir.path / "interiors").string()) + " > /dev/null").c_str()), 0);
  ASSERT_EQ(setenv("ENVPIS_ASSETS", dir.path.c_str(), 1), 0);
  const std::vector<Room> rooms = {
      {"interior-room.json", 1, {{0, -1.5f, 1.4f}, {-1.5f, 1.5f, 2.0f}, {1.5f, 0, 0.3f}, {1.9f, 0.5f, 1.9f}}},
      {"interior-glossy-room.json", 1, {{0, -1.5f, 1.4f}, {-1.5f, 1.5f, 2.0f}, {1.5f, 0, 0.3f}}},
      {"interior-two-windows.json", 2, {{2, -1, 1.5f}, {-2, 0, 1.0f}, {0, 1.5f, 2.5f}, {1.2f, -1.8f, 1.6f}}}};
  std::mt19937 rng(24);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  for (const Room& room : rooms) {
    const Scene s = load_scene_file((fs::path(ENVPIS_SOURCE_DIR) / "scenes" / room.scene).string());
    ASSERT_EQ(s.portals().size(), room.portals) << room.scene;
    for (int i = 0; i < s.portals().size(); ++i)  // windows in walls: horizontal normals
      EXPECT_LT(std::abs(s.portals().normal(i).z), 1e-6f) << room.scene;
    for (const Vec3& p : room.inside) {
      int escaped = 0, disagree = 0;
      const int n = 20000;
      for (int k = 0; k < n; ++k) {
        const float z = 1 - 2 * uni(rng), phi = 2 * kPi * uni(rng), r = std::sqrt(std::max(0.0f, 1 - z * z));
        const Vec3 d{r * std::cos(phi), r * std::sin(phi), z};
        SurfaceHit hit;
        const bool escapes = !s.intersect(Ray{p, d}, &hit);
        escaped += escapes;
        disagree += escapes != s.portals().passes(p, d);
      }
      // Rays along an opening's edge may go either way by round-off: a few in 20,000 at most.
      EXPECT_LE(disagree, 4) << room.scene << " from (" << p.x << ", " << p.y << ", " << p.z << ")";
      EXPECT_GT(escaped, n / 200) << room.scene;  // every point sees a window
      EXPECT_LT(escaped, n / 2) << room.scene;    // and mostly walls
    }
  }
  unsetenv("ENVPIS_ASSETS");
}

}  // namespace
}  // namespace envpis::render
