// SPDX-License-Identifier: Apache-2.0
// Portals in the renderer and the scene format (issue 24, item 2; docs/portals.md, "In the renderer"):
//   - in scenes/interior-window.json (a closed room lit through one window, its portal in the opening)
//     every strategy converges to the same per-object means as a high-sample reference, with portals
//     off (mis, mis-comp, product), on (the -portal variants) and with a portal covering only half of
//     the window (the MIS variants: BSDF samples carry the uncovered half);
//   - the portal variants' light samplers: sample() and pdf() agree inside the room, no sample outside;
//   - portals change nothing for the strategies without them (bit-identical images);
//   - bad portals in a scene file are a one-line error naming the file and the portal, also from the
//     command line; a portal strategy on a scene without portals is a clear error.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_util.h"
#include "test_util.h"
#include "render/render.h"
#include "render/scenes.h"

namespace envpis::render {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

const std::string& interior_file() {
  static const std::string path = (fs::path(ENVPIS_SOURCE_DIR) / "scenes" / "interior-window.json").string();
  return path;
}

// The east window's opening is y in [-0.75, 0.75], z in [1, 2] on x = 2; the half portal covers y < 0.
Portals half_window() { return Portals({Quad{{{2, -0.75f, 1}, {2, 0, 1}, {2, 0, 2}, {2, -0.75f, 2}}}}); }

RenderOptions interior_options(Strategy s, int spp, std::uint64_t seed) {
  RenderOptions o;
  o.strategy = s;
  o.integrator = IntegratorKind::Direct;
  o.spp = spp;
  o.seed = seed;
  o.width = 64;
  o.height = 48;
  return o;
}

double bonferroni_z(int tests) {  // two-sided, family-wise 1e-3
  const double alpha = 1e-3 / tests;
  double lo = 0, hi = 10;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > alpha ? lo : hi) = mid;
  }
  return lo;
}

TEST(PortalRender, InteriorSceneLoadsItsPortal) {
  const Scene s = load_scene_file(interior_file());
  ASSERT_EQ(s.portals().size(), 1);
  EXPECT_GT(s.portals().normal(0).x, 0.99f);  // counter-clockwise seen from outside: points out (+X)
}

// The test of issue 24: every strategy, portals on and off and half a window, against one reference.
TEST(PortalRender, EveryStrategyConvergesWithPortalsOnOffAndHalf) {
  const Scene full = load_scene_file(interior_file());
  Scene half = load_scene_file(interior_file());
  half.set_portals(half_window());
  const int objects = static_cast<int>(full.objects().size());
  // The reference's noise dominates the z-tests of the portal strategies (mis is about 10x noisier
  // here): 8192 spp, and the portal strategies at 256, so that a pdf off by 2x fails clearly.
  const RenderResult ref_mis = render(full, interior_options(Strategy::Mis, 8192, 1000));
  const RenderResult ref_product = render(full, interior_options(Strategy::Product, 1024, 2000));
  const auto m_mis = object_means(ref_mis, objects), m_product = object_means(ref_product, objects);

  struct Case {
    const Scene* scene;
    Strategy strategy;
    const char* portals;
  };
  // env-portal is left out of the half-window case: it has no BSDF hits, so it cannot see through
  // the uncovered half (documented: unbiased only when portals cover every opening).
  const std::vector<Case> cases{
      {&full, Strategy::Mis, "off"},          {&full, Strategy::MisComp, "off"},
      {&full, Strategy::Product, "off"},      {&full, Strategy::EnvPortal, "on"},
      {&full, Strategy::MisPortal, "on"},     {&full, Strategy::MisCompPortal, "on"},
      {&full, Strategy::ProductPortal, "on"}, {&half, Strategy::MisPortal, "half"},
      {&half, Strategy::MisCompPortal, "half"}, {&half, Strategy::ProductPortal, "half"},
  };
  const double z_max = bonferroni_z(static_cast<int>(cases.size() + 1) * objects);
  std::printf("Bonferroni threshold |z| < %.2f\n", z_max);
  for (const Case& c : cases) {
    const RenderResult r = render(*c.scene, interior_options(c.strategy, uses_portals(c.strategy) ? 256 : 64, 42));
    ASSERT_EQ(r.nonfinite_pixels, 0u) << to_string(c.strategy);
    const auto m = object_means(r, objects);
    const auto& ref = c.strategy == Strategy::Mis ? m_product : m_mis;
    std::printf("%-16s %-4s", to_string(c.strategy), c.portals);
    for (int i = 0; i < objects; ++i) {
      if (m[i].pixels < 20) continue;  // not in view at this size
      const double se = std::sqrt(m[i].variance + ref[i].variance);
      ASSERT_GT(se, 0.0) << full.objects()[i].name;
      const double z = (m[i].mean - ref[i].mean) / se;
      std::printf(" %s %.4f(%+.2f)", full.objects()[i].name.c_str(), m[i].mean, z);
      EXPECT_LT(std::fabs(z), z_max) << to_string(c.strategy) << " portals " << c.portals << " on "
                                     << full.objects()[i].name << ": " << m[i].mean << " vs " << ref[i].mean;
    }
    std::printf("\n");
  }
  for (int i = 0; i < objects; ++i) {
    if (m_mis[i].pixels < 20) continue;
    const double z = (m_mis[i].mean - m_product[i].mean) / std::sqrt(m_mis[i].variance + m_product[i].variance);
    EXPECT_LT(std::fabs(z), z_max) << "references disagree on " << full.objects()[i].name;
  }
}

TEST(PortalRender, PathIntegratorIsFiniteWithEveryPortalStrategy) {
  const Scene s = load_scene_file(interior_file());
  for (Strategy st : portal_strategies()) {
    RenderOptions o = interior_options(st, 4, 7);
    o.integrator = IntegratorKind::Path;
    const RenderResult r = render(s, o);
    EXPECT_EQ(r.nonfinite_pixels, 0u) << to_string(st);
  }
}

// Per shading point the light sampler's pdf is the density its samples come from; outside the room
// (on the portal's outer side) there is no sample and pdf 0 (so MIS gives the BSDF sample weight 1).
TEST(PortalRender, LightSamplerSampleAndPdfAgreeInsideNoSampleOutside) {
  const Scene s = load_scene_file(interior_file());
  Material diffuse;
  diffuse.add(make_lambert({0.5f, 0.5f, 0.5f}));
  for (Strategy st : portal_strategies()) {
    const StrategyTables t = StrategyTables::build(s.environment(), st);
    LightSampler ls(t, &s.portals());
    ShadingContext sc;
    sc.n = {0, 0, 1};
    sc.wo = normalize(Vec3{-1, 0, 1});
    const Frame frame(sc.n);
    sc.frame = &frame;
    sc.wo_local = frame.to_local(sc.wo);
    sc.bsdf = &diffuse;
    sc.opaque = true;
    sc.p = {0.5f, -0.5f, 0.01f};  // on the floor, in the window's light
    ls.prepare(sc);
    int through = 0;
    for (int i = 0; i < 256; ++i) {
      const Point2 u{(i % 16 + 0.5f) / 16, (i / 16 + 0.5f) / 16};
      const DirectionSample d = ls.sample(u);
      ASSERT_GT(d.pdf, 0.0f) << to_string(st);
      EXPECT_NEAR(ls.pdf(d.direction), d.pdf, 1e-4f * d.pdf) << to_string(st);
      through += s.portals().passes(sc.p, d.direction);
    }
    EXPECT_GT(through, 64) << to_string(st) << ": most light samples should leave through the window";
    sc.p = {3, 0, 1.5f};  // outside, beyond the window: the one-sided portal shows nothing
    ls.prepare(sc);
    EXPECT_EQ(ls.sample({0.3f, 0.6f}).pdf, 0.0f) << to_string(st);
    EXPECT_EQ(ls.pdf(normalize(Vec3{1, 0, 0.2f})), 0.0f) << to_string(st);
  }
}

// product-portal with the product cache: a shading point's distribution is its key's (the point
// rounded), never the first point's that filled the slot, so the image does not depend on the order
// the pixels are visited in (tile size, threads) or on the cache's size, bit for bit.
TEST(PortalRender, ProductCacheImageIsIndependentOfSampleOrder) {
  const Scene s = load_scene_file(interior_file());
  RenderOptions a = interior_options(Strategy::ProductPortal, 16, 5);
  a.integrator = IntegratorKind::Path;
  a.product_cache.entries = 16;
  a.threads = 1;
  a.tile_size = 8;
  RenderOptions b = a;
  b.threads = 2;
  b.tile_size = 16;
  b.product_cache.entries = 1;
  const RenderResult ra = render(s, a), rb = render(s, b);
  std::printf("product cache: %llu hits, %llu misses\n", static_cast<unsigned long long>(ra.product_cache_hits),
              static_cast<unsigned long long>(ra.product_cache_misses));
  EXPECT_GT(2 * ra.product_cache_hits, ra.product_cache_misses);  // the camera rays' hits share keys
  EXPECT_EQ(ra.rgb, rb.rgb);
}

// The strategies without portals ignore them: the same image bit for bit with and without.
TEST(PortalRender, PortalsChangeNothingForTheOtherStrategies) {
  const Scene with = load_scene_file(interior_file());
  Scene without = load_scene_file(interior_file());
  without.set_portals(Portals());
  for (Strategy st : {Strategy::Mis, Strategy::Product}) {
    const RenderResult a = render(with, interior_options(st, 4, 3)), b = render(without, interior_options(st, 4, 3));
    EXPECT_EQ(a.rgb, b.rgb) << to_string(st);
  }
}

TEST(PortalRender, PortalStrategyNeedsPortals) {
  Scene s = load_scene_file(interior_file());
  s.set_portals(Portals());
  try {
    render(s, interior_options(Strategy::ProductPortal, 1, 0));
    FAIL() << "rendered product-portal without portals";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("needs a scene with portals"), std::string::npos) << e.what();
  }
  EXPECT_EQ(parse_strategy("mis-portal"), Strategy::MisPortal);
  EXPECT_EQ(base_strategy(Strategy::ProductPortal), Strategy::Product);
  EXPECT_FALSE(uses_portals(Strategy::Product));
}

// A minimal scene file with `portals` as its "portals" field.
std::string scene_with_portals(const std::string& portals) {
  return R"({
  "camera": {"from": [0, -8, 2], "to": [0, 0, 0.5], "fov": 40, "width": 16, "height": 8},
  "environment": {"sky": {"width": 32, "height": 16}},
  "materials": {"white": {"type": "diffuse", "albedo": 0.8}},
  "objects": [{"type": "sphere", "center": [0, 0, 1], "radius": 1, "material": "white"}],
  "portals": )" + portals + "\n}\n";
}

const std::string kGood = R"({"vertices": [[2, -1, 1], [2, 1, 1], [2, 1, 2], [2, -1, 2]]})";

struct BadCase {
  std::string portals, expect;
};

std::vector<BadCase> bad_cases() {
  return {
      {R"({"vertices": [1, 2]})", "portals: expected an array"},
      {"[" + kGood + R"(, {"vertices": [[2, -1, 1], [2, 1, 1], [2, 1, 2]]}])", "portals[1].vertices: expected 4 vertices"},
      {R"([{"vertices": [[2, -1, 1], [2, 1, 1], [2, 1, 2], [2, -1, "nan"]]}])", "portals[0].vertices[3]: expected 3 finite"},
      {R"([{"vertices": [[2, -1, 1], [2, 1, 1], [2, 1, 2], [2, -1, 1e999]]}])", "invalid JSON: "},
      {R"([{"vertices": [[2, 0, 1], [2, 0, 1], [2, 0, 1], [2, 0, 1]]}])", "portals[0]: degenerate"},
      {R"([{"vertices": [[2, 0, 1], [2, 1, 1], [2, 2, 1], [2, 3, 1]]}])", "portals[0]: degenerate"},
      {R"([{"vertices": [[2, -1, 1], [2, 1, 1], [2.5, 1, 2], [2, -1, 2]]}])", "portals[0]: not planar"},
      {R"([{"vertices": [[2, -1, 1], [2, 1, 1], [2, 0, 1.2], [2, -1, 2]]}])", "portals[0]: not convex"},  // a dart
      {R"([{"vertices": [[2, -1, 1], [2, 1, 1], [2, 1, 2], [2, -1, 2]], "two_sided": true}])",
       "portals[0]: unknown field 'two_sided'"},
      {R"([{"points": []}])", "portals[0]: unknown field 'points'"},
      {"[" + kGood + "," + kGood + "," + kGood + "," + kGood + "," + kGood + "," + kGood + "," + kGood + "," + kGood +
           "," + kGood + "]",
       "portals[8]: at most 8 portals"},
  };
}

TEST(PortalSceneFile, BadPortalsAreOneLineErrorsNamingFileAndPortal) {
  TempDir dir;
  for (const BadCase& c : bad_cases()) {
    const std::string path = dir.write("bad.json", scene_with_portals(c.portals));
    std::string err;
    try {
      load_scene_file(path);
    } catch (const Error& e) {
      err = e.what();
    }
    EXPECT_EQ(err.rfind(path + ": ", 0), 0u) << "expected the file first in '" << err << "'";
    EXPECT_NE(err.find(c.expect), std::string::npos) << "expected '" << c.expect << "' in '" << err << "'";
    EXPECT_EQ(err.find('\n'), std::string::npos) << err;
  }
  const Scene ok = load_scene_file(dir.write("good.json", scene_with_portals("[" + kGood + "]")));
  EXPECT_EQ(ok.portals().size(), 1);
}

TEST(PortalCli, BadPortalsExitNonZeroWithOneLine) {
  TempDir dir;
  std::vector<std::pair<std::string, std::string>> cases;
  int i = 0;
  for (const BadCase& c : bad_cases()) {
    const std::string path = dir.write("bad-" + std::to_string(i++) + ".json", scene_with_portals(c.portals));
    cases.push_back({"render --scene " + test::shell_quote(path) + " --spp 1 --out " +
                         test::shell_quote((dir.path / "out.exr").string()),
                     path + ": " + c.expect.substr(0, c.expect.find(':'))});
  }
  // And a portal strategy on a scene without portals.
  cases.push_back({"render --scene fig1 --strategy mis-portal --spp 1 --width 8 --height 4 --out " +
                       test::shell_quote((dir.path / "out.exr").string()),
                   "needs a scene with portals"});
  test::expect_one_line_errors(cases, 2);
  EXPECT_FALSE(fs::exists(dir.path / "out.exr"));
}

}  // namespace
}  // namespace envpis::render
