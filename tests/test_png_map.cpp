// SPDX-License-Identifier: Apache-2.0
// PNG environment maps: decoded by libpng directly (src/io/png_decode.h), with the values OpenImageIO's
// reader gave before (code value / max code), and one clean error line for a corrupt file.
#include <gtest/gtest.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "envpis/environment_map.h"

namespace fs = std::filesystem;
using namespace envpis;

namespace {

fs::path temp_dir() { return fs::temp_directory_path() / ("envpis_png_" + std::to_string(::getpid())); }

// A w x h image of `channels` channels with values v(i), written by OpenImageIO's writer.
std::vector<float> write_png(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type) {
  std::vector<float> v(static_cast<std::size_t>(w) * h * channels);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = float((i * 7) % 11) / 10.0f;
  if (channels == 4)
    for (std::size_t i = 3; i < v.size(); i += 4) v[i] = (i / 4) % 3 == 0 ? 0.0f : 0.6f;  // alpha 0 or 0.6
  auto out = OIIO::ImageOutput::create(path);
  EXPECT_TRUE(out);
  OIIO::ImageSpec spec(w, h, channels, type);
  if (channels == 4) {
    spec.alpha_channel = 3;
    spec.attribute("oiio:UnassociatedAlpha", 1);  // store the colour as given, not divided by alpha
  }
  EXPECT_TRUE(out->open(path, spec)) << out->geterror();
  EXPECT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, v.data())) << out->geterror();
  out->close();
  return v;
}

std::string load_error(const std::string& path) {
  try {
    EnvironmentMap::load(path);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

// 8 and 16 bits, grey, RGB and RGBA: texel = stored colour / max code, alpha ignored.
TEST(PngMap, ValuesAreCodeValuesOverMaxCode) {
  fs::create_directories(temp_dir());
  struct Case {
    const char* name;
    int channels;
    OIIO::TypeDesc type;
  };
  for (const Case& c : {Case{"rgb8.png", 3, OIIO::TypeDesc::UINT8}, Case{"rgb16.png", 3, OIIO::TypeDesc::UINT16},
                        Case{"grey8.png", 1, OIIO::TypeDesc::UINT8}, Case{"rgba8.png", 4, OIIO::TypeDesc::UINT8},
                        Case{"rgba16.png", 4, OIIO::TypeDesc::UINT16}}) {
    const std::string p = (temp_dir() / c.name).string();
    const int w = 6, h = 3;
    const std::vector<float> v = write_png(p, w, h, c.channels, c.type);
    const EnvironmentMap m = EnvironmentMap::load(p);
    ASSERT_EQ(m.width(), w);
    ASSERT_EQ(m.height(), h);
    EXPECT_EQ(m.load_report().format, "png");
    const float tol = c.type == OIIO::TypeDesc::UINT8 ? 0.51f / 255 : 0.51f / 65535;  // written rounded
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y * w + x) * c.channels;
        const float alpha = c.channels == 4 ? v[i + 3] : 1.0f;
        const Rgb t = m.texel(x, y);
        const float e[3] = {v[i], c.channels >= 3 ? v[i + 1] : v[i], c.channels >= 3 ? v[i + 2] : v[i]};
        // 16-bit colour comes back from libpng premultiplied: undone, except where alpha is 0.
        const bool lost = c.channels == 4 && c.type == OIIO::TypeDesc::UINT16 && alpha == 0.0f;
        const float got[3] = {t.r, t.g, t.b};
        for (int k = 0; k < 3; ++k)
          EXPECT_NEAR(got[k], lost ? 0.0f : e[k], c.type == OIIO::TypeDesc::UINT16 && c.channels == 4 ? 2e-4f : tol)
              << c.name << " texel " << x << "," << y << " channel " << k;
      }
  }
  fs::remove_all(temp_dir());
}

// Corrupt PNGs fail with one line naming the file and libpng's reason, and nothing on stderr (libpng
// prints nothing through the simplified API).
TEST(PngMap, CorruptFilesGiveOneLineErrors) {
  fs::create_directories(temp_dir());
  const std::string good = (temp_dir() / "good.png").string();
  write_png(good, 16, 8, 3, OIIO::TypeDesc::UINT8);
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::pair<std::string, std::string>> files = {
      {"truncated.png", bytes.substr(0, bytes.size() / 2)},
      {"signature-only.png", bytes.substr(0, 8)},
      {"bad-crc.png", bytes.substr(0, 30) + char(bytes[30] ^ 0x55) + bytes.substr(31)},
      {"not-png.png", "this is not an image\n"},
  };
  for (const auto& [name, content] : files) {
    const std::string p = (temp_dir() / name).string();
    std::ofstream(p, std::ios::binary) << content;
    ::testing::internal::CaptureStderr();
    const std::string e = load_error(p);
    const std::string err = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(e.rfind("cannot load environment map '" + p + "': PNG reader: ", 0), 0u) << name << ": " << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    EXPECT_EQ(err, "") << name;
  }
  fs::remove_all(temp_dir());
}
