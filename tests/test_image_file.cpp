// SPDX-License-Identifier: Apache-2.0
// envpis/image_file.h: OpenEXR and PNG read and written without OpenImageIO, other formats through its
// module, and the envpis command not linked against OpenImageIO (its start-up cost).
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>  // an independent reader of what write_image_file wrote

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_util.h"
#include "envpis/environment_map.h"
#include "envpis/image_file.h"

namespace fs = std::filesystem;
using namespace envpis;

namespace {

fs::path temp_dir() {
  const fs::path d = fs::temp_directory_path() / ("envpis_test_image_file_" + std::to_string(::getpid()));
  fs::create_directories(d);
  return d;
}

std::vector<float> ramp(int w, int h, int nc) {
  std::vector<float> px(std::size_t(w) * h * nc);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = 0.001f * float(i * i % 9973) + (i % 7 == 0 ? 1e4f : 0.0f);
  return px;
}

}  // namespace

// Float EXR: every value back bit for bit, channels in R, G, B, then the others; the names and header
// attributes as another reader (OpenImageIO) sees them.
TEST(ImageFile, OpenExrRoundTripIsExactWithNamesAndAttributes) {
  const fs::path dir = temp_dir();
  const std::string path = (dir / "four.exr").string();
  const int w = 7, h = 5;
  const std::vector<float> px = ramp(w, h, 4);
  write_image_file(path, w, h, 4, px.data(), {"R", "G", "B", "variance"},
                   {{"envpis:spp", 64}, {"envpis:strategy", std::string("product")}});
  const ImageFile img = read_image_file(path);
  EXPECT_EQ(img.format, "openexr");
  EXPECT_FALSE(img.integer_coded);
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.height, h);
  ASSERT_EQ(img.channels, 4);
  EXPECT_EQ(img.pixels, px);

  auto in = OIIO::ImageInput::open(path);
  ASSERT_TRUE(in) << OIIO::geterror();
  EXPECT_EQ(in->spec().channelnames, (std::vector<std::string>{"R", "G", "B", "variance"}));
  EXPECT_EQ(in->spec().get_int_attribute("envpis:spp"), 64);
  EXPECT_EQ(in->spec().get_string_attribute("envpis:strategy"), "product");

  // Grey with alpha: named Y and A, read back in that order (not A first, as the names sort).
  const std::string grey = (dir / "grey.exr").string();
  const std::vector<float> ya = ramp(w, h, 2);
  write_image_file(grey, w, h, 2, ya.data());
  EXPECT_EQ(read_image_file(grey).pixels, ya);
  auto grey_in = OIIO::ImageInput::open(grey);
  ASSERT_TRUE(grey_in) << OIIO::geterror();
  EXPECT_EQ(grey_in->spec().channelnames, (std::vector<std::string>{"Y", "A"}));

  ImageReadLimits three;
  three.max_channels = 3;
  EXPECT_EQ(read_image_file(path, three).channels, 3);
  ImageReadLimits small;
  small.max_side = 6;
  try {
    read_image_file(path, small);
    ADD_FAILURE() << "a 7-texel side passed a limit of 6";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("the image is too large (7x5)"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// 8-bit PNG: values clamped to [0, 1] and rounded to codes; read back as code / 255.
TEST(ImageFile, PngRoundTripRoundsToEightBitCodes) {
  const fs::path dir = temp_dir();
  const std::string path = (dir / "rgb.png").string();
  const int w = 4, h = 3;
  std::vector<float> px(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = float(i) / 36.0f * 1.2f - 0.1f;  // some outside [0, 1]
  px[5] = std::nanf("");
  write_image_file(path, w, h, 3, px.data());
  const ImageFile img = read_image_file(path);
  EXPECT_EQ(img.format, "png");
  EXPECT_TRUE(img.integer_coded);
  ASSERT_EQ(img.channels, 3);
  for (std::size_t i = 0; i < px.size(); ++i) {
    const float v = std::isnan(px[i]) ? 0.0f : std::fmin(std::fmax(px[i], 0.0f), 1.0f);
    EXPECT_FLOAT_EQ(img.pixels[i], std::round(v * 255.0f) / 255.0f) << i;
  }
  fs::remove_all(dir);
}

// A format only OpenImageIO has (Radiance HDR) goes through the module both ways.
TEST(ImageFile, OtherFormatsGoThroughTheOpenImageIOModule) {
  const fs::path dir = temp_dir();
  const std::string path = (dir / "sky.hdr").string();
  const int w = 8, h = 4;
  std::vector<float> px(std::size_t(w) * h * 3);
  for (std::size_t i = 0; i < px.size(); ++i) px[i] = 0.5f + float(i % 11);
  write_image_file(path, w, h, 3, px.data());
  EXPECT_EQ(image_format_for_extension("HDR"), "hdr");
  EXPECT_EQ(image_format_for_extension("dpx"), "dpx");  // asks OpenImageIO
  EXPECT_EQ(image_format_for_extension("nosuchformat"), "");
  const ImageFile img = read_image_file(path);
  EXPECT_EQ(img.format, "hdr");
  ASSERT_EQ(img.width, w);
  ASSERT_EQ(img.channels, 3);
  for (std::size_t i = 0; i < px.size(); ++i) EXPECT_NEAR(img.pixels[i], px[i], 0.01f * px[i]) << i;  // RGBE
  fs::remove_all(dir);
}

// The command does not link OpenImageIO; without its module, OpenEXR maps still load and other formats
// fail with one line that says what is missing.
TEST(ImageFile, TheCommandNeedsTheModuleOnlyForOtherFormats) {
#ifndef ENVPIS_OIIO_AS_MODULE
  GTEST_SKIP() << "built with ENVPIS_OIIO_AS_MODULE=OFF: OpenImageIO is linked in";
#endif
  FILE* p = popen(("readelf -d " + test::shell_quote(test::envpis_binary()) + " 2>&1").c_str(), "r");
  ASSERT_TRUE(p);
  std::string dynamic;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) dynamic.append(buf, n);
  ASSERT_EQ(pclose(p), 0) << dynamic;
  EXPECT_NE(dynamic.find("(NEEDED)"), std::string::npos) << dynamic;
  EXPECT_EQ(dynamic.find("OpenImageIO"), std::string::npos) << dynamic;

  const fs::path dir = temp_dir();
  const std::string exr = (dir / "map.exr").string(), hdr = (dir / "map.hdr").string();
  const std::vector<float> px(16 * 8 * 3, 1.0f);
  write_image_file(exr, 16, 8, 3, px.data());
  write_image_file(hdr, 16, 8, 3, px.data());
  ASSERT_EQ(setenv("ENVPIS_OIIO_MODULE", (dir / "missing.so").c_str(), 1), 0);
  const auto r = test::run_envpis_all({"table --env " + test::shell_quote(exr) + " --samples 100 --out " +
                                           test::shell_quote((dir / "out").string()),
                                       "table --env " + test::shell_quote(hdr) + " --samples 100 --out " +
                                           test::shell_quote((dir / "out2").string())});
  unsetenv("ENVPIS_OIIO_MODULE");
  EXPECT_EQ(r[0].code, 0) << r[0].output;
  test::expect_one_line_error("table", "--env " + hdr, r[1],
                              "cannot load environment map '" + hdr +
                                  "': reading or writing this format needs OpenImageIO, but its OpenImageIO "
                                  "module was not found: tried " + (dir / "missing.so").string() + " (not found)");
  fs::remove_all(dir);
}
