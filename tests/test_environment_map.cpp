// SPDX-License-Identifier: Apache-2.0
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>

#include <filesystem>
#include <fstream>
#include <random>

#include "test_util.h"

using namespace envpis;
using namespace envpis::test;
namespace fs = std::filesystem;

namespace {

void write_image(const std::string& path, int w, int h, int channels, const std::vector<float>& px) {
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::FLOAT);
  ASSERT_TRUE(out->open(path, spec));
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data()));
  out->close();
}

std::string load_error(const std::string& path, const EnvironmentMapOptions& o = {}) {
  try {
    EnvironmentMap::load(path, o);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(EnvironmentMap, LoadsEveryBlenderMap) {
  if (!have_blender_maps()) GTEST_SKIP() << "blender-data not installed";
  for (const auto& name : blender_map_names()) {
    const EnvironmentMap m = EnvironmentMap::load(blender_map(name));
    EXPECT_EQ(m.width(), 1024) << name;
    EXPECT_EQ(m.height(), 512) << name;
    EXPECT_EQ(m.layout(), MapLayout::LatLong);
    const Rgb up = m.eval({0, 0, 1});
    EXPECT_TRUE(std::isfinite(up.r) && up.r >= 0) << name;
  }
}

TEST(EnvironmentMap, WritesAndReadsExrAndHdr) {
  const TempDir tmp;
  const fs::path& dir = tmp.path;
  const int w = 8, h = 4;
  std::vector<float> px(w * h * 3);
  for (int i = 0; i < w * h * 3; ++i) px[i] = 0.25f * (i % 7) + 0.5f;
  for (const char* ext : {".exr", ".hdr"}) {
    const std::string path = (dir / (std::string("map") + ext)).string();
    write_image(path, w, h, 3, px);
    const EnvironmentMap m = EnvironmentMap::load(path);
    EXPECT_EQ(m.width(), w);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Rgb t = m.texel(x, y);
        const float* e = &px[(y * w + x) * 3];
        const float tol = std::string(ext) == ".hdr" ? 0.02f * e[0] : 1e-6f;  // RGBE quantizes
        EXPECT_NEAR(t.r, e[0], tol);
        EXPECT_NEAR(t.b, e[2], std::string(ext) == ".hdr" ? 0.02f * e[2] : 1e-6f);
      }
  }
  // A single-channel image is grey.
  const std::string grey = (dir / "grey.exr").string();
  write_image(grey, 4, 2, 1, std::vector<float>(8, 3.0f));
  const Rgb g = EnvironmentMap::load(grey).texel(1, 1);
  EXPECT_FLOAT_EQ(g.r, 3.0f);
  EXPECT_FLOAT_EQ(g.g, 3.0f);
}

TEST(EnvironmentMap, BadFilesGiveClearErrors) {
  const TempDir tmp;
  const fs::path& dir = tmp.path;
  // missing
  std::string e = load_error((dir / "nope.exr").string());
  EXPECT_NE(e.find("nope.exr"), std::string::npos) << e;
  EXPECT_NE(e.find("no such file"), std::string::npos) << e;
  // a directory
  e = load_error(dir.string());
  EXPECT_NE(e.find("directory"), std::string::npos) << e;
  // zero bytes
  const std::string empty = (dir / "empty.exr").string();
  std::ofstream(empty).close();
  e = load_error(empty);
  EXPECT_NE(e.find("empty"), std::string::npos) << e;
  // text with an image extension
  for (const char* name : {"text.exr", "text.hdr", "text.png"}) {
    const std::string p = (dir / name).string();
    std::ofstream(p) << "this is not an image\n";
    e = load_error(p);
    EXPECT_NE(e.find(name), std::string::npos) << e;
  }
  // truncated EXR and HDR
  for (const char* ext : {".exr", ".hdr"}) {
    const std::string full = (dir / (std::string("full") + ext)).string();
    std::vector<float> px(64 * 32 * 3);
    for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(i % 13) + 0.1f * float(i % 5);
    write_image(full, 64, 32, 3, px);
    const std::string cut = (dir / (std::string("cut") + ext)).string();
    {
      std::ifstream in(full, std::ios::binary);
      std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() / 3));
    }
    e = load_error(cut);
    EXPECT_NE(e.find("cut"), std::string::npos) << ext << ": " << (e.empty() ? "loaded without error" : e);
  }
}

// The reader follows the content for the usual HDR formats (a wrong extension is harmless and
// reported), the extension otherwise; non-regular files, unknown formats and unreadable paths fail
// cleanly, without blocking (a FIFO) and without OpenImageIO's try-every-reader fallback.
TEST(EnvironmentMap, ReaderChoiceAndNonRegularFiles) {
  const TempDir tmp;
  const fs::path dir = tmp.path / "reader";
  fs::create_directories(dir);
  std::vector<float> px(8 * 4 * 3, 1.0f);
  px[5] = 7.0f;
  const std::string exr = (dir / "map.exr").string(), hdr = (dir / "map.hdr").string();
  write_image(exr, 8, 4, 3, px);
  write_image(hdr, 8, 4, 3, px);
  {
    const EnvironmentMap m = EnvironmentMap::load(exr);
    EXPECT_EQ(m.load_report().format, "openexr");
    EXPECT_EQ(m.load_report().extension_format, "openexr");
    EXPECT_TRUE(m.warnings().empty());
    EXPECT_FALSE(m.is_black());
    EXPECT_FLOAT_EQ(m.max_radiance(), 7.0f);
  }
  // OpenEXR and Radiance content under the wrong (or no) extension: read by content, with a warning.
  const std::vector<std::pair<std::string, std::string>> renamed{
      {exr, "exr-named.png"}, {exr, "exr-named.hdr"}, {hdr, "hdr-named.exr"}, {hdr, "hdr-no-extension"}};
  for (const auto& [src, name] : renamed) {
    const std::string p = (dir / name).string();
    fs::copy_file(src, p, fs::copy_options::overwrite_existing);
    const EnvironmentMap m = EnvironmentMap::load(p);
    EXPECT_EQ(m.width(), 8) << name;
    EXPECT_NEAR(m.texel(1, 0).b, 7.0f, 0.1f) << name;
    EXPECT_EQ(m.load_report().format, src == exr ? "openexr" : "hdr") << name;
    const std::vector<std::string> w = m.warnings();
    if (name == "hdr-no-extension") {
      EXPECT_TRUE(w.empty()) << name;
    } else {
      ASSERT_EQ(w.size(), 1u) << name;
      EXPECT_NE(w[0].find(p), std::string::npos) << w[0];
      EXPECT_NE(w[0].find("despite its '"), std::string::npos) << w[0];
    }
  }
  // Unknown content: the extension decides; with no reader for it, a clear error.
  const std::string bin = (dir / "random.bin").string(), noext = (dir / "random").string();
  for (const std::string& p : {bin, noext}) {
    std::ofstream f(p, std::ios::binary);
    for (int i = 0; i < 4096; ++i) f.put(static_cast<char>((i * 7919 + 13) & 0xff));
  }
  std::string e = load_error(bin);
  EXPECT_NE(e.find("unknown image format (no reader for the extension '.bin'"), std::string::npos) << e;
  e = load_error(noext);
  EXPECT_NE(e.find("unknown image format (no file extension"), std::string::npos) << e;
  // A FIFO would block a reader forever: refused before it is opened.
  const std::string fifo = (dir / "fifo.exr").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  e = load_error(fifo);
  EXPECT_NE(e.find("'" + fifo + "': is not a regular file"), std::string::npos) << e;
  // A path through a regular file, and (unless root, who reads anything) a file without read permission.
  e = load_error(exr + "/sub.exr");
  EXPECT_NE(e.find("cannot load environment map '" + exr + "/sub.exr'"), std::string::npos) << e;
  if (::geteuid() != 0) {
    const std::string locked = (dir / "locked.exr").string();
    fs::copy_file(exr, locked, fs::copy_options::overwrite_existing);
    fs::permissions(locked, fs::perms::none);
    e = load_error(locked);
    EXPECT_NE(e.find("cannot open: Permission denied"), std::string::npos) << e;
    fs::permissions(locked, fs::perms::owner_all);
  }
  // A 1x1 all-black map loads (the table and sampler handle it); the caller can tell it is black.
  const std::string black = (dir / "black.exr").string();
  write_image(black, 1, 1, 3, {0.0f, 0.0f, 0.0f});
  const EnvironmentMap b = EnvironmentMap::load(black);
  EXPECT_TRUE(b.is_black());
  EXPECT_EQ(b.max_radiance(), 0.0f);
}

// What a header claims is checked before any pixel is read: a 600-byte EXR whose data window claims
// 8M x 2 texels made OpenImageIO's converting read_image() allocate a 12 GB band buffer (the fuzzer's
// find; OpenEXR files are now read by OpenEXR itself, which refuses the claim when it reads the header). Pixels are read in the stored formats, per channel, in bands: mixed per-channel formats, tiles
// that overhang the image, a data window away from (0, 0) and 8/16-bit integer files all convert to the
// right floats.
TEST(EnvironmentMap, HeaderClaimsAreBoundedAndStoredFormatsConvert) {
  const TempDir tmp;
  const fs::path dir = tmp.path / "claims";
  fs::create_directories(dir);
  const std::string small = (dir / "small.exr").string();
  write_image(small, 8, 4, 3, std::vector<float>(8 * 4 * 3, 0.5f));
  std::string bytes;
  {
    std::ifstream in(small, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  bytes = exr_claiming(bytes, 8000000, 2);
  ASSERT_FALSE(bytes.empty()) << "no data/display window attributes in " << small;
  const std::string wide = (dir / "wide.exr").string();
  std::ofstream(wide, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  std::string e = load_error(wide);
  // Refused by OpenEXR's own header check (envpis sets its limit to 65536 texels a side), before
  // OpenEXR sizes its decoding buffers from the header.
  EXPECT_NE(e.find("'" + wide + "': OpenEXR reader: "), std::string::npos) << (e.empty() ? "loaded without error" : e);
  EXPECT_NE(e.find("exceeds the maximum width of 65536"), std::string::npos) << e;

  // Tiled, 10x7 in 4x4 tiles, R half, G float, B half, A uint8: values must survive the native read.
  const int w = 10, h = 7;
  std::vector<float> px(static_cast<std::size_t>(w) * h * 4);
  for (int i = 0; i < w * h; ++i) {
    px[i * 4 + 0] = 0.25f * float(i % 9);
    px[i * 4 + 1] = 1000.0f + float(i);
    px[i * 4 + 2] = 0.5f * float(i % 5);
    px[i * 4 + 3] = 1.0f;
  }
  const std::string tiled = (dir / "tiled.exr").string();
  {
    auto out = OIIO::ImageOutput::create(tiled);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 4, OIIO::TypeDesc::HALF);
    spec.channelformats = {OIIO::TypeDesc::HALF, OIIO::TypeDesc::FLOAT, OIIO::TypeDesc::HALF, OIIO::TypeDesc::HALF};
    spec.tile_width = spec.tile_height = 4;
    ASSERT_TRUE(out->open(tiled, spec)) << out->geterror();
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << out->geterror();
    out->close();
  }
  {
    auto in = OIIO::ImageInput::open(tiled);
    ASSERT_TRUE(in);
    ASSERT_EQ(in->spec().tile_width, 4);
    ASSERT_EQ(in->spec().channelformat(1), OIIO::TypeDesc::FLOAT) << "the writer did not keep the mixed formats";
  }
  const EnvironmentMap m = EnvironmentMap::load(tiled);
  ASSERT_EQ(m.width(), w);
  ASSERT_EQ(m.height(), h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const int i = y * w + x;
      const Rgb t = m.texel(x, y);
      EXPECT_FLOAT_EQ(t.r, px[i * 4 + 0]) << x << "," << y;
      EXPECT_FLOAT_EQ(t.g, px[i * 4 + 1]) << x << "," << y;  // float: exact even above half's precision
      EXPECT_FLOAT_EQ(t.b, px[i * 4 + 2]) << x << "," << y;
    }

  // A data window that does not start at (0, 0), scanlines and tiles: texel (0, 0) is its first pixel.
  for (const int tile : {0, 4}) {
    const std::string p = (dir / ("origin" + std::to_string(tile) + ".exr")).string();
    auto out = OIIO::ImageOutput::create(p);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::HALF);
    spec.x = 5;
    spec.y = 3;
    spec.tile_width = spec.tile_height = tile;
    ASSERT_TRUE(out->open(p, spec)) << out->geterror();
    std::vector<float> v(static_cast<std::size_t>(w) * h * 3);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = 0.125f * float(i % 17);
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data())) << out->geterror();
    out->close();
    const EnvironmentMap o = EnvironmentMap::load(p);
    ASSERT_EQ(o.width(), w);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float* e = &v[static_cast<std::size_t>(y * w + x) * 3];
        const Rgb t = o.texel(x, y);
        EXPECT_EQ(t.r, e[0]) << tile << ": " << x << "," << y;
        EXPECT_EQ(t.b, e[2]) << tile << ": " << x << "," << y;
      }
  }

  // 8-bit PNG and 16-bit TIFF: integers normalized to [0, 1].
  for (const auto& [name, type] : {std::pair{"u8.png", OIIO::TypeDesc::UINT8}, std::pair{"u16.tif", OIIO::TypeDesc::UINT16}}) {
    const std::string p = (dir / name).string();
    auto out = OIIO::ImageOutput::create(p);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(4, 2, 3, type);
    ASSERT_TRUE(out->open(p, spec));
    std::vector<float> v(4 * 2 * 3);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = float(i % 3) * 0.5f;  // 0, 0.5, 1
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data()));
    out->close();
    const Rgb t = EnvironmentMap::load(p).texel(3, 1);
    EXPECT_FLOAT_EQ(t.r, 0.0f) << name;
    EXPECT_NEAR(t.g, 0.5f, type == OIIO::TypeDesc::UINT8 ? 1.0f / 255 : 1.0f / 65535) << name;
    EXPECT_FLOAT_EQ(t.b, 1.0f) << name;
  }
}

TEST(EnvironmentMap, RepairsNanInfAndNegativeTexels) {
  std::vector<float> px = {1, 2, 3, std::nanf(""), 1, 1, INFINITY, -INFINITY, 1, -5, 0.5f, 1};
  const EnvironmentMap m = EnvironmentMap::from_pixels(2, 2, px, {});
  EXPECT_EQ(m.load_report().nan_texels, 1u);
  EXPECT_EQ(m.load_report().inf_texels, 2u);
  EXPECT_EQ(m.load_report().negative_texels, 1u);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      const Rgb t = m.texel(x, y);
      EXPECT_TRUE(std::isfinite(t.r) && std::isfinite(t.g) && std::isfinite(t.b) && t.r >= 0 && t.g >= 0 && t.b >= 0);
    }
  std::mt19937_64 rng(2);
  for (int i = 0; i < 1000; ++i) {
    const Rgb L = m.eval(random_direction(rng));
    ASSERT_TRUE(std::isfinite(L.r) && L.r >= 0);
  }
  EXPECT_EQ(m.eval({0, 0, 0}).r, 0.0f);
  EXPECT_EQ(m.eval({std::nanf(""), 0, 1}).r, 0.0f);
}

// The world direction at azimuth phi (from +X towards +Y) and polar angle theta (from +Z), written
// here independently of the library's lat-long formula.
Vec3 spherical(double phi, double theta) {
  return {float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta))};
}

TEST(EnvironmentMap, LatLongBilinearFilteringAndMapSpace) {
  const int w = 16, h = 8;
  const auto m = synthetic_latlong(w, h, [](int x, int y) { return float(x + 100 * y); });
  // Texel centres return the texel (to_world(latlong_to_direction(uv)) is the direction of (u, v)).
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Vec3 d = m.to_world(latlong_to_direction({(x + 0.5f) / w, (y + 0.5f) / h}));
      EXPECT_NEAR(m.eval(d).r, float(x + 100 * y), 1e-3f) << x << "," << y;
    }
  // Half-way between two texel centres: the average. The u seam wraps.
  EXPECT_NEAR(m.eval(m.to_world(latlong_to_direction({3.0f / w, 2.5f / h}))).r, 202.5f, 1e-3f);
  EXPECT_NEAR(m.eval(m.to_world(latlong_to_direction({0.0f, 2.5f / h}))).r, 0.5f * (200 + 215), 1e-2f);
  EXPECT_NEAR(m.eval_texture({0.0f, 2.5f / h}).r, 0.5f * (200 + 215), 1e-2f);
  // Map space: +Z is up (the top row), azimuth 0 is +X, u grows towards +Y.
  EXPECT_EQ(direction_to_latlong({0, 0, 1}).y, 0.0f);
  EXPECT_NEAR(direction_to_latlong({1, 0, 0}).x, 0.0f, 1e-6f);
  EXPECT_NEAR(direction_to_latlong({0, 1, 0}).x, 0.25f, 1e-6f);
  // Rotation about Z and scale: the rotated map shows in direction R d what the plain one shows in d.
  EnvironmentMapOptions o;
  o.rotation = Mat3::rotate_z(90);
  o.scale = 2;
  const auto r = synthetic_latlong(w, h, [](int x, int y) { return float(x + 100 * y); }, o);
  const Vec3 d = m.to_world(latlong_to_direction({4.5f / w, 3.5f / h}));
  EXPECT_NEAR(r.eval(o.rotation * d).r, 2 * m.eval(d).r, 1e-2f);
}

// direction_to_latlong uses polynomial angles (src/environment_map.cpp). Against the exact angles (in
// double) over the sphere, near the poles and across the seam: the errors stay within the documented
// bounds, a 4096 x 2048 map's nearest look-up picks the exact texel except within a band of 1e-3 of a
// texel at its edges, and bilinear values move by no more than that band allows.
TEST(EnvironmentMap, LatLongLookUpIsAccurate) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  std::uniform_real_distribution<float> tiny(-1e-6f, 1e-6f);
  std::vector<Vec3> dirs;
  for (int i = 0; i < 400000; ++i) dirs.push_back({g(rng), g(rng), g(rng)});
  for (int i = 0; i < 20000; ++i) {
    dirs.push_back({tiny(rng), tiny(rng), 1.0f});                     // at the poles
    dirs.push_back({tiny(rng), tiny(rng), -1.0f});
    dirs.push_back({g(rng), tiny(rng) * std::fabs(g(rng)), g(rng)});  // at the seam (phi = 0) and phi = pi
    dirs.push_back({1.0f, 1.0f + tiny(rng), g(rng)});                   // where atan2's branches meet
  }
  const int w = 4096, h = 2048;
  const double band = 1e-3;
  double max_phi = 0, max_theta = 0;
  int outside_band = 0, differ = 0;
  const auto m = synthetic_latlong(64, 32, [](int x, int y) { return float((x * 37 + y * 91) % 17) / 16; });
  float max_bilinear = 0;
  for (const Vec3& d : dirs) {
    const Point2 p = direction_to_latlong(d);
    double phi = std::atan2(double(d.y), double(d.x));
    if (phi < 0) phi += 2 * M_PI;
    const double theta = std::atan2(std::hypot(double(d.x), double(d.y)), double(d.z));
    double dphi = std::fabs(2 * M_PI * p.x - phi);
    dphi = std::min(dphi, 2 * M_PI - dphi);  // across the seam
    max_phi = std::max(max_phi, dphi);
    max_theta = std::max(max_theta, std::fabs(M_PI * p.y - theta));
    // Nearest texel: the exact one, unless the exact coordinate is within the band of an edge.
    const double eu = std::fmod(phi / (2 * M_PI), 1.0) * w, ev = theta / M_PI * h;
    const int ex = int(eu) % w, ey = std::min(int(ev), h - 1);
    const int fx = int(p.x * w) % w, fy = std::min(int(p.y * h), h - 1);
    if (ex != fx || ey != fy) {
      ++differ;
      const double du = std::fabs(eu - std::round(eu)), dv = std::fabs(ev - std::round(ev));
      outside_band += (ex != fx && du > band) || (ey != fy && dv > band);
    }
    const Point2 exact{float(eu / w), float(ev / h)};
    max_bilinear = std::max(max_bilinear, std::fabs(m.eval(m.to_world(d)).r - m.eval_texture(exact).r));
  }
  EXPECT_LT(max_phi, 6.5e-7) << "the bound in direction_to_latlong's comment";
  EXPECT_LT(max_theta, 3.5e-7);
  EXPECT_EQ(outside_band, 0) << differ << " directions chose another texel";
  EXPECT_LT(differ, int(dirs.size() / 100));  // all within the band, most of them at the seam and poles
  // A 64 x 32 map whose neighbours differ by up to 1: an angle error of 6.5e-7 rad moves a bilinear
  // look-up by at most 64 / (2 pi) * 6.5e-7 + 32 / pi * 3.5e-7 of that, about 1e-5 (with float rounding).
  EXPECT_LT(max_bilinear, 2e-5f);
}

TEST(EnvironmentMap, LatLongOrientation) {
  const int w = 16, h = 8;
  auto f = [](int x, int y) { return float(x * x + 1000 * y); };  // no mirror symmetry in u
  EnvironmentMapOptions legacy;
  legacy.orientation = LatLongOrientation::Legacy;
  const auto pano = synthetic_latlong(w, h, f);
  const auto old = synthetic_latlong(w, h, f, legacy);
  EXPECT_EQ(pano.orientation(), LatLongOrientation::Panorama);  // the default
  EXPECT_EQ(old.orientation(), LatLongOrientation::Legacy);
  // Every texel centre, from the convention's own formula: Panorama u = 0.5 - phi / 2pi, Legacy u = phi / 2pi.
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = (x + 0.5) / w, theta = M_PI * (y + 0.5) / h;
      EXPECT_NEAR(pano.eval(spherical(2 * M_PI * (0.5 - u), theta)).r, f(x, y), 1e-2f) << x << "," << y;
      EXPECT_NEAR(old.eval(spherical(2 * M_PI * u, theta)).r, f(x, y), 1e-2f) << x << "," << y;
    }
  // On the equator (half-way between rows 3 and 4): +X reads u = 0.5 (columns 7 and 8), +Y u = 0.25
  // (columns 3 and 4), -Y u = 0.75; under Legacy +X reads u = 0 (columns 15 and 0).
  auto equator = [&](int x0, int x1) { return 0.25f * (f(x0, 3) + f(x1, 3) + f(x0, 4) + f(x1, 4)); };
  EXPECT_NEAR(pano.eval({1, 0, 0}).r, equator(7, 8), 1e-2f);
  EXPECT_NEAR(pano.eval({0, 1, 0}).r, equator(3, 4), 1e-2f);
  EXPECT_NEAR(pano.eval({0, -1, 0}).r, equator(11, 12), 1e-2f);
  EXPECT_NEAR(pano.eval({-1, 0, 0}).r, equator(15, 0), 1e-2f);
  EXPECT_NEAR(old.eval({1, 0, 0}).r, equator(15, 0), 1e-2f);
  EXPECT_NEAR(old.eval({0, 1, 0}).r, equator(3, 4), 1e-2f);
  EXPECT_NEAR(old.eval({-1, 0, 0}).r, equator(7, 8), 1e-2f);
  // The same through map space.
  EXPECT_NEAR(direction_to_latlong(pano.to_map({1, 0, 0})).x, 0.5f, 1e-6f);
  EXPECT_NEAR(direction_to_latlong(pano.to_map({0, 1, 0})).x, 0.25f, 1e-6f);
  EXPECT_NEAR(direction_to_latlong(old.to_map({1, 0, 0})).x, 0.0f, 1e-6f);
  // A rotation turns the panorama about +Z: rotated by 90 degrees, +Y reads what +X did.
  EnvironmentMapOptions rot;
  rot.rotation = Mat3::rotate_z(90);
  const auto turned = synthetic_latlong(w, h, f, rot);
  EXPECT_NEAR(turned.eval({0, 1, 0}).r, equator(7, 8), 1e-2f);
  EXPECT_NEAR(turned.eval(spherical(M_PI / 2 + 0.3, 1.0)).r, pano.eval(spherical(0.3, 1.0)).r, 1e-2f);
  // Equal-area maps have no orientation: the option changes nothing.
  auto g = [](int x, int y) { return float(x * x + 7 * y); };
  const auto ea = synthetic_latlong(8, 8, g), ea_old = synthetic_latlong(8, 8, g, legacy);
  std::mt19937_64 rng(3);
  for (int i = 0; i < 200; ++i) {
    const Vec3 d = random_direction(rng);
    ASSERT_EQ(ea.eval(d).r, ea_old.eval(d).r);
    ASSERT_NEAR(length(ea.to_map(d) - d), 0.0f, 1e-6f);
  }
  EXPECT_EQ(parse_latlong_orientation("panorama"), LatLongOrientation::Panorama);
  EXPECT_EQ(parse_latlong_orientation("legacy"), LatLongOrientation::Legacy);
  EXPECT_THROW(parse_latlong_orientation("mirrored"), Error);
  EXPECT_STREQ(to_string(LatLongOrientation::Legacy), "legacy");
}

TEST(EnvironmentMap, NearestFilterIsPiecewiseConstant) {
  const int w = 16, h = 8;
  auto f = [](int x, int y) { return float(x * x + 1000 * y); };
  EnvironmentMapOptions o;
  o.filter = MapFilter::Nearest;
  const auto bilinear = synthetic_latlong(w, h, f);
  EXPECT_EQ(bilinear.filter(), MapFilter::Bilinear);  // the default
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> U(0.05f, 0.95f);  // inside a texel, off its edges
  for (LatLongOrientation orientation : {LatLongOrientation::Panorama, LatLongOrientation::Legacy}) {
    o.orientation = orientation;
    const auto m = synthetic_latlong(w, h, f, o);
    EXPECT_EQ(m.filter(), MapFilter::Nearest);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int k = 0; k < 8; ++k) {
          const Point2 uv{(x + U(rng)) / w, (y + U(rng)) / h};
          ASSERT_EQ(m.eval_texture(uv).r, f(x, y));
          ASSERT_EQ(m.eval(m.to_world(latlong_to_direction(uv))).r, f(x, y)) << x << "," << y;
        }
    // u wraps, v clamps.
    EXPECT_EQ(m.eval_texture({1.0f, 0.5f}).r, f(0, 4));
    EXPECT_EQ(m.eval_texture({-0.01f, 0.5f}).r, f(w - 1, 4));
    EXPECT_EQ(m.eval_texture({0.01f, 1.0f}).r, f(0, h - 1));
    EXPECT_EQ(m.eval_texture({0.01f, -0.5f}).r, f(0, 0));
  }
  // Bilinear is unchanged: a quarter of the way from texel (5, 2) to (6, 3).
  const Point2 q{(5.75f) / w, (2.75f) / h};
  const float expect = 0.75f * (0.75f * f(5, 2) + 0.25f * f(6, 2)) + 0.25f * (0.75f * f(5, 3) + 0.25f * f(6, 3));
  EXPECT_NEAR(bilinear.eval_texture(q).r, expect, 1e-2f);
  // Equal-area: the texel the square point falls in, across the edges too.
  const int n = 8;
  auto g = [](int x, int y) { return float(x * x + 7 * y); };
  o.orientation = LatLongOrientation::Panorama;
  const auto ea = synthetic_latlong(n, n, g, o);
  ASSERT_EQ(ea.layout(), MapLayout::EqualArea);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Point2 p{(x + U(rng)) / n, (y + U(rng)) / n};
      ASSERT_EQ(ea.eval_texture(p).r, g(x, y));
      ASSERT_EQ(ea.eval(ea.to_world(equal_area_square_to_sphere(p))).r, g(x, y));
    }
  EXPECT_EQ(ea.eval_texture({-0.01f, 0.3f}).r, g(0, n - 1 - 2));  // mirrored across the left edge
  EXPECT_EQ(parse_map_filter("nearest"), MapFilter::Nearest);
  EXPECT_EQ(parse_map_filter("bilinear"), MapFilter::Bilinear);
  EXPECT_THROW(parse_map_filter("closest"), Error);
  EXPECT_STREQ(to_string(MapFilter::Nearest), "nearest");
  // Absurd texture coordinates stay in the image.
  const auto ll = synthetic_latlong(w, h, f, o);
  for (float big : {1e30f, -1e30f, 3e9f, -3e9f}) {
    EXPECT_GE(ll.eval_texture({big, big}).r, 0.0f);
    EXPECT_GE(ea.eval_texture({big, -big}).r, 0.0f);
  }
}

TEST(EnvironmentMap, EqualAreaLayoutIsContinuousAcrossEdges) {
  const int n = 32;
  const auto m = synthetic_latlong(n, n, [](int x, int y) { return std::sin(0.3f * x) + std::cos(0.2f * y) + 3; });
  ASSERT_EQ(m.layout(), MapLayout::EqualArea);
  // Texel centres return the texel.
  EXPECT_NEAR(m.eval(equal_area_square_to_sphere({5.5f / n, 7.5f / n})).r, std::sin(1.5f) + std::cos(1.4f) + 3, 1e-4f);
  // Radiance is continuous across the square's edges (they are seams on the sphere).
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> U(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const float t = U(rng);
    for (Point2 p : {Point2{0.0f, t}, Point2{1.0f, t}, Point2{t, 0.0f}, Point2{t, 1.0f}}) {
      const Vec3 d = equal_area_square_to_sphere(p);
      const Vec3 inside = equal_area_square_to_sphere({std::clamp(p.x, 1e-4f, 1 - 1e-4f), std::clamp(p.y, 1e-4f, 1 - 1e-4f)});
      // a point just across the seam: perturb the direction slightly the other way
      const Vec3 across = normalize(d * 2.0f - inside);
      ASSERT_NEAR(m.eval(inside).r, m.eval(across).r, 0.05f) << p.x << "," << p.y;
    }
  }
  EXPECT_THROW(EnvironmentMap::from_pixels(4, 2, std::vector<float>(24, 1.0f), {MapLayout::EqualArea}), Error);
}

TEST(EnvironmentMap, OptionsAndLayoutParsing) {
  EXPECT_EQ(parse_map_layout("latlong"), MapLayout::LatLong);
  EXPECT_EQ(parse_map_layout("equal-area"), MapLayout::EqualArea);
  EXPECT_THROW(parse_map_layout("cube"), Error);
  EnvironmentMapOptions o;
  o.scale = -1;
  EXPECT_THROW(EnvironmentMap::from_pixels(2, 1, std::vector<float>(6, 1.0f), o), Error);
  o.scale = std::nanf("");
  EXPECT_THROW(EnvironmentMap::from_pixels(2, 1, std::vector<float>(6, 1.0f), o), Error);
  EXPECT_THROW(EnvironmentMap::from_pixels(0, 1, {}, {}), Error);
  EXPECT_THROW(EnvironmentMap::from_pixels(2, 2, std::vector<float>(5, 1.0f), {}), Error);
  // Odd aspect ratios load as lat-long.
  EXPECT_EQ(EnvironmentMap::from_pixels(3, 1, std::vector<float>(9, 1.0f), {}).layout(), MapLayout::LatLong);
  EXPECT_EQ(EnvironmentMap::from_pixels(1, 1000, std::vector<float>(3000, 1.0f), {}).layout(), MapLayout::LatLong);
  // Huge texels times a scale do not overflow to infinity.
  o.scale = 1e10f;
  const auto big = EnvironmentMap::from_pixels(2, 1, std::vector<float>(6, 1e30f), o);
  EXPECT_FLOAT_EQ(big.texel(0, 0).r, 1e30f);
  EXPECT_TRUE(std::isfinite(big.eval({0, 0, 1}).average()));
}
