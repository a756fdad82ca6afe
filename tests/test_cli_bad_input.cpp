// SPDX-License-Identifier: Apache-2.0
// Every bad environment file through all three commands that read one (`envpis table`, `render` and
// `compare`), run as a user would: zero-byte, truncated and corrupt EXR and HDR, wrong extensions,
// a directory, a FIFO, a missing or unreadable path, a header claiming 8M-texel scanlines,
// NaN/Inf/negative texels, an all-black map, 1x1, 3x1 and 1x1000 maps, texels of 1e30, top-level sizes
// 0, 1 and 1000, and unwritable outputs.
//
// Policy checked (docs/cli.md, "Bad input"): a file that cannot be used gives exit code 1 and a single
// line "envpis CMD: error: cannot load environment map 'PATH': REASON" and nothing else; a file that
// can be used after a documented repair (invalid texels set to 0, a wrong extension read by content,
// a lat-long map that is not 2:1) gives a warning line naming the file, exit 0 and finite outputs; an
// all-black map is an error for `table` and `compare` (nothing to sample or compare) and, for `render`,
// a warning and a black image (every strategy falls back to BSDF sampling). Never a crash, a hang
// (each run is under `timeout`) or a NaN/Inf in an image or in metrics.json.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_util.h"
#include "test_util.h"

namespace {

namespace fs = std::filesystem;
using envpis::test::CmdResult;
using envpis::test::expect_one_line_error;
using envpis::test::expect_one_line_errors;
using envpis::test::line_starting;
using envpis::test::run_envpis_all;
using envpis::test::shell_quote;

// ------------------------------------------------------------------------------------------ files

void write_float_image(const std::string& path, int w, int h, const std::function<float(int, int, int)>& f) {
  std::vector<float> px(static_cast<std::size_t>(w) * h * 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) px[(static_cast<std::size_t>(y) * w + x) * 3 + c] = f(x, y, c);
  auto out = OIIO::ImageOutput::create(path);
  ASSERT_TRUE(out) << path << ": " << OIIO::geterror();
  OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::FLOAT);
  ASSERT_TRUE(out->open(path, spec)) << path << ": " << out->geterror();
  ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, px.data())) << path << ": " << out->geterror();
  ASSERT_TRUE(out->close());
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A small sky: a gradient, a bright sun, a band; every texel positive.
float sky(int x, int y, int c, int w, int h) {
  float v = 0.2f + 0.8f * float(h - y) / float(h) + 0.1f * float(c);
  if (std::abs(x - w / 3) <= 1 && std::abs(y - h / 4) <= 1) v = 2000.0f;
  return v;
}

// fuzz/make_corpus.py's regress_png_bad_offs_chunk without its first byte (the harness's extension choice).
const std::string kPngBadOffsChunk(
    "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x04\x00\x00\x00\x04"
    "\x08\x02\x00\x00\x00\x26\x93\x09\x29\x08\x00\x00\x09\x6f\x46\x46\x73\x00\x00\x00\x00\x00\x00\x00"
    "\x00\x00\xda\x2a\xb6\xce\x00\x00\x00\x12\x49\x44\x41\x54\x08\x99\x24\xfc\xdf\xc0\x00\x07\x4c\x0c"
    "\x0c\xc4\x70\x00\x4c\xd1\x01\x87\xfc\x27\x03\x25\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
    96);

class BadInput : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("envpis_bad_input_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const int W = 64, H = 32;
    const auto sky64 = [](int x, int y, int c) { return sky(x, y, c, 64, 32); };
    write_float_image(path("good.exr"), W, H, sky64);
    write_float_image(path("good.hdr"), W, H, sky64);
    write_bytes(path("empty.exr"), "");
    write_bytes(path("empty.hdr"), "");
    write_float_image(path("good.png"), W, H, [](int x, int y, int c) { return float((x + y + c) % 7) / 6.0f; });
    // Truncated: the first third of a valid file.
    for (const char* ext : {"exr", "hdr", "png"}) {
      const std::string full = read_bytes(path(std::string("good.") + ext));
      write_bytes(path(std::string("truncated.") + ext), full.substr(0, full.size() / 3));
    }
    // Corrupt OpenEXR: a valid magic number and version, then a header of 0xff bytes.
    {
      std::string b = read_bytes(path("good.exr"));
      for (std::size_t i = 8; i < 200 && i < b.size(); ++i) b[i] = '\xff';
      write_bytes(path("corrupt-header.exr"), b);
    }
    // Corrupt OpenEXR pixel data: every chunk's bytes after the offset table replaced.
    {
      std::string b = read_bytes(path("good.exr"));
      for (std::size_t i = b.size() / 2; i < b.size(); ++i) b[i] = static_cast<char>(i * 131 + 7);
      write_bytes(path("corrupt-data.exr"), b);
    }
    // Corrupt Radiance HDR: a resolution line that is not one.
    write_bytes(path("corrupt-header.hdr"), "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X sixty-four\n" +
                                                std::string(64 * 32 * 4, '\x40'));
    // Corrupt Radiance HDR pixel data: run-length scanlines that announce the wrong width.
    {
      std::string b = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 32 +X 64\n";
      for (int y = 0; y < 32; ++y) b += std::string("\x02\x02\x00\x10", 4) + std::string(64 * 4, '\x01');
      write_bytes(path("corrupt-data.hdr"), b);
    }
    // A header claiming 8M x 2 texels over 64x32 texels of data (CI's fuzz find: a reader sized a 12 GB
    // buffer from such a claim before noticing the data was missing).
    {
      const std::string b = envpis::test::exr_claiming(read_bytes(path("good.exr")), 8000000, 2);
      ASSERT_FALSE(b.empty());
      write_bytes(path("claims-8M-wide.exr"), b);
    }
    // A 4x4 PNG whose oFFs chunk has a bad length (fuzz_image_load's find, seed regress_png_bad_offs_chunk):
    // OpenImageIO's PNG reader leaked its error string on it.
    write_bytes(path("bad-offs-chunk.png"), kPngBadOffsChunk);
    write_bytes(path("text.exr"), "this is not an image\n");
    write_bytes(path("text.png"), "this is not an image either\n");
    fs::copy_file(path("good.exr"), path("exr-named.hdr"));
    fs::copy_file(path("good.hdr"), path("hdr-named.png"));
    fs::create_directories(path("directory.exr"));
    ASSERT_EQ(::mkfifo(path("fifo.exr").c_str(), 0600), 0);
    fs::copy_file(path("good.exr"), path("locked.exr"));
    fs::permissions(path("locked.exr"), fs::perms::none);
    // Texel values: NaN, +-Inf and negative channels among valid ones.
    write_float_image(path("nan-inf-negative.exr"), W, H, [&](int x, int y, int c) {
      switch ((x + 3 * y + c) % 5) {
        case 0: return std::nanf("");
        case 1: return INFINITY;
        case 2: return -INFINITY;
        case 3: return -2.0f;
        default: return sky64(x, y, c);
      }
    });
    write_float_image(path("black.exr"), W, H, [](int, int, int) { return 0.0f; });
    write_float_image(path("1x1.exr"), 1, 1, [](int, int, int c) { return 1.0f + float(c); });
    write_float_image(path("3x1.exr"), 3, 1, [](int x, int, int c) { return 0.5f + float(x) + float(c); });
    write_float_image(path("1x1000.exr"), 1, 1000, [](int, int y, int) { return y < 100 ? 50.0f : 0.5f; });
    write_float_image(path("all-1e30.exr"), W, H, [](int, int, int) { return 1e30f; });
    write_float_image(path("sun-1e30.exr"), W, H, [&](int x, int y, int c) {
      return (x == 20 && y == 8) ? 1e30f : sky64(x, y, c);
    });
    fs::create_directories(path("out"));
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::permissions(path("locked.exr"), fs::perms::owner_all, ec);
    fs::remove_all(dir_, ec);
  }
  void SetUp() override {
    ASSERT_TRUE(fs::exists(envpis::test::envpis_binary())) << "envpis not built: " << envpis::test::envpis_binary();
  }

 public:
  static std::string path(const std::string& name) { return (dir_ / name).string(); }

 protected:
  static fs::path dir_;
};
fs::path BadInput::dir_;

// ------------------------------------------------------------------------------------ commands

const std::vector<std::string> kCommands = {"table", "render", "compare"};

// `envpis CMD` on map `env`, small and fast, writing under out/CMD-TAG.
std::string command_line(const std::string& cmd, const std::string& env, const std::string& tag,
                         const std::string& extra = "") {
  const std::string out = BadInput::path("out/" + cmd + "-" + tag);
  if (cmd == "table") return "table --env " + shell_quote(env) + " --samples 200 --out " + shell_quote(out) + extra;
  if (cmd == "render")
    return "render --env " + shell_quote(env) + " --width 16 --height 4 --spp 4 --quiet --out " +
           shell_quote(out + ".exr") + extra;
  return "compare --env " + shell_quote(env) +
         " --width 16 --height 4 --spp 2 --ref-spp 4 --strategies mis,product --repeats 1 --no-convergence "
         "--no-plots --no-cache --quiet --out " +
         shell_quote(out) + extra;
}

bool all_finite_nonnegative(const std::vector<float>& v) {
  for (float x : v)
    if (!std::isfinite(x) || x < 0) return false;
  return true;
}

std::vector<float> read_exr(const std::string& p, int* w = nullptr, int* h = nullptr) {
  auto in = OIIO::ImageInput::open(p);
  if (!in) return {};
  const OIIO::ImageSpec& s = in->spec();
  std::vector<float> px(static_cast<std::size_t>(s.width) * s.height * s.nchannels);
  if (!in->read_image(0, 0, 0, s.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  if (w) *w = s.width;
  if (h) *h = s.height;
  return px;
}

// Every number in a JSON document is finite (nlohmann writes NaN/Inf as null: no null where a number
// is expected is checked by the callers; here: no non-finite double slipped through as a number).
void expect_json_finite(const nlohmann::json& j, const std::string& where) {
  if (j.is_number_float()) EXPECT_TRUE(std::isfinite(j.get<double>())) << where;
  if (j.is_structured())
    for (auto it = j.begin(); it != j.end(); ++it)
      expect_json_finite(*it, where + "/" + (j.is_object() ? it.key() : std::string("[]")));
}

// The outputs of a successful run are there and finite.
void expect_good_outputs(const std::string& cmd, const std::string& tag, const std::string& args) {
  const std::string out = BadInput::path("out/" + cmd + "-" + tag);
  if (cmd == "table") {
    std::ifstream f(out + "/summary.json");
    ASSERT_TRUE(f.good()) << args;
    const nlohmann::json j = nlohmann::json::parse(f);
    expect_json_finite(j, args);
    EXPECT_EQ(j["samples"]["zero_pdf"], 0) << args;
    for (double p : j["cells"]["product_probability"].get<std::vector<double>>()) EXPECT_TRUE(std::isfinite(p)) << args;
  } else if (cmd == "render") {
    int w = 0, h = 0;
    const std::vector<float> px = read_exr(out + ".exr", &w, &h);
    ASSERT_EQ(px.size(), 16u * 4u * 3u) << args;
    EXPECT_TRUE(all_finite_nonnegative(px)) << args;
  } else {
    std::ifstream f(out + "/metrics.json");
    ASSERT_TRUE(f.good()) << args;
    const nlohmann::json m = nlohmann::json::parse(f);
    expect_json_finite(m, args);
    for (const auto& s : m["equal_spp"]["strategies"]) {
      ASSERT_TRUE(s["relmse"].is_number()) << args << ": " << s["strategy"];
      EXPECT_EQ(s["nan_count"], 0) << args;
      EXPECT_TRUE(all_finite_nonnegative(read_exr(out + "/" + s["images"]["exr"].get<std::string>()))) << args;
    }
    EXPECT_TRUE(all_finite_nonnegative(read_exr(out + "/images/reference.exr"))) << args;
  }
}

struct FileCase {
  std::string file;    // under the test directory (or an absolute path)
  std::string reason;  // after "cannot load environment map 'PATH': "
};

// ------------------------------------------------------------------------------------ tests

// Files that cannot be used: the same one-line error, naming the file and the problem, from all three.
TEST_F(BadInput, UnusableFilesGiveOneLineErrorsFromEveryCommand) {
  std::vector<FileCase> cases = {
      {"missing.exr", "no such file"},
      {"empty.exr", "the file is empty (0 bytes)"},
      {"empty.hdr", "the file is empty (0 bytes)"},
      {"truncated.exr", "could not read the pixels (corrupt or truncated?): "},
      {"truncated.hdr", "could not read the pixels (corrupt or truncated?): "},
      {"corrupt-header.exr", "OpenEXR reader: "},
      {"corrupt-data.exr", "could not read the pixels (corrupt or truncated?): "},
      {"corrupt-header.hdr", "Radiance HDR reader: "},
      {"corrupt-data.hdr", "could not read the pixels (corrupt or truncated?): "},
      {"claims-8M-wide.exr", "OpenEXR reader: Cannot read image file"},  // OpenEXR refuses the 8M-texel side
      {"text.exr", "OpenEXR reader: "},
      {"text.png", "PNG reader: Not a PNG file"},
      {"truncated.png", "PNG reader: "},
      {"bad-offs-chunk.png", "PNG reader: "},
      {"directory.exr", "is a directory, not an image file"},
      {"fifo.exr", "is not a regular file"},
      {"good.exr/inside-a-file.exr", "Not a directory"},
  };
  if (::geteuid() != 0) cases.push_back({"locked.exr", "cannot open: Permission denied"});  // root reads anything

  std::vector<std::string> args;
  std::vector<std::pair<std::string, const FileCase*>> what;
  for (const FileCase& c : cases)
    for (const std::string& cmd : kCommands) {
      args.push_back(command_line(cmd, path(c.file), "err"));
      what.emplace_back(cmd, &c);
    }
  const std::vector<CmdResult> results = run_envpis_all(args);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto& [cmd, c] = what[i];
    expect_one_line_error(cmd, args[i], results[i],
                          "cannot load environment map '" + path(c->file) + "': " + c->reason);
  }
  // Nothing was written for a failed run.
  EXPECT_FALSE(fs::exists(path("out/table-err/summary.json")));
  EXPECT_FALSE(fs::exists(path("out/render-err.exr")));
  EXPECT_FALSE(fs::exists(path("out/compare-err/metrics.json")));
}

// Files that are usable after a documented repair or fallback: a warning naming the file, exit 0,
// finite outputs; tiny and extreme maps work.
TEST_F(BadInput, RepairableAndExtremeMapsWorkWithWarnings) {
  struct OkCase {
    std::string file, tag;
    std::string warning;  // expected on a warning line ("" : no warning at all)
  };
  const std::vector<OkCase> cases = {
      {"nan-inf-negative.exr", "nan", "texel values were invalid and set to 0 (1229 NaN, 2458 infinite, 1229 negative)"},
      {"exr-named.hdr", "exr-named", "contains OpenEXR data despite its '.hdr' extension: read as OpenEXR"},
      {"hdr-named.png", "hdr-named", "contains Radiance HDR data despite its '.png' extension"},
      {"1x1.exr", "1x1", ""},  // square: read as an equal-area map
      {"3x1.exr", "3x1", "is read as lat-long but is 3x1, not 2:1"},
      {"1x1000.exr", "1x1000", "is read as lat-long but is 1x1000, not 2:1"},
      {"all-1e30.exr", "all-1e30", ""},
      {"sun-1e30.exr", "sun-1e30", ""},
      {"good.hdr", "good-hdr", ""},
  };
  std::vector<std::string> args;
  std::vector<std::pair<std::string, const OkCase*>> what;
  for (const OkCase& c : cases)
    for (const std::string& cmd : kCommands) {
      args.push_back(command_line(cmd, path(c.file), c.tag));
      what.emplace_back(cmd, &c);
    }
  const std::vector<CmdResult> results = run_envpis_all(args);
  for (std::size_t i = 0; i < args.size(); ++i) {
    const auto& [cmd, c] = what[i];
    const CmdResult& r = results[i];
    ASSERT_EQ(r.code, 0) << args[i] << "\n" << r.output;
    const std::string warn = line_starting(r.output, "envpis " + cmd + ": warning: ");
    if (c->warning.empty()) {
      EXPECT_EQ(warn, "") << args[i];
    } else {
      EXPECT_NE(warn.find("'" + path(c->file) + "'"), std::string::npos) << args[i] << "\n" << r.output;
      EXPECT_NE(r.output.find(c->warning), std::string::npos) << args[i] << "\n" << r.output;
    }
    expect_good_outputs(cmd, c->tag, args[i]);
  }
}

// An all-black map: nothing to sample (`table`) or compare (`compare`): a clear error; `render` warns
// and renders the correct black image with every strategy (each falls back to BSDF sampling).
TEST_F(BadInput, AllBlackMap) {
  const std::string black = path("black.exr");
  std::vector<std::string> args = {command_line("table", black, "black"), command_line("compare", black, "black")};
  const std::vector<std::string> strategies = {"bsdf", "env", "mis", "mis-comp", "product", "oracle"};
  for (const std::string& s : strategies)
    args.push_back(command_line("render", black, "black-" + s, " --strategy " + s + " --integrator path"));
  const std::vector<CmdResult> r = run_envpis_all(args);
  expect_one_line_error("table", args[0], r[0], "no positive radiance");
  expect_one_line_error("compare", args[1], r[1], "has no positive radiance: every strategy renders a black image");
  for (std::size_t i = 0; i < strategies.size(); ++i) {
    const CmdResult& ri = r[2 + i];
    ASSERT_EQ(ri.code, 0) << args[2 + i] << "\n" << ri.output;
    EXPECT_NE(line_starting(ri.output, "envpis render: warning: ").find("has no positive radiance"), std::string::npos)
        << ri.output;
    const std::vector<float> px = read_exr(path("out/render-black-" + strategies[i] + ".exr"));
    ASSERT_EQ(px.size(), 16u * 4u * 3u);
    for (float v : px) ASSERT_EQ(v, 0.0f) << strategies[i];
  }
}

// Top-level sizes: 0 and 1000 are refused by every command before any work; 1 works everywhere.
TEST_F(BadInput, TopLevelSizes) {
  const std::string good = path("good.exr");
  std::vector<std::string> args;
  for (const std::string& cmd : kCommands)
    for (const char* top : {"0", "1000", "1"}) args.push_back(command_line(cmd, good, std::string("top") + top, std::string(" --top ") + top));
  const std::vector<CmdResult> r = run_envpis_all(args);
  for (std::size_t c = 0; c < kCommands.size(); ++c) {
    expect_one_line_error(kCommands[c], args[c * 3], r[c * 3], "--top: must be in 1..256, got '0'");
    expect_one_line_error(kCommands[c], args[c * 3 + 1], r[c * 3 + 1], "--top: must be in 1..256, got '1000'");
    ASSERT_EQ(r[c * 3 + 2].code, 0) << args[c * 3 + 2] << "\n" << r[c * 3 + 2].output;
    expect_good_outputs(kCommands[c], "top1", args[c * 3 + 2]);
  }
}

// Outputs that cannot be written: refused before rendering, with the path and the reason.
TEST_F(BadInput, UnwritableOutputs) {
  const std::string good = shell_quote(path("good.exr"));
  const std::string through_file = path("good.exr") + "/sub";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"table --env " + good + " --out " + shell_quote(through_file), "cannot create output directory '" + through_file + "'"},
      {"table --env " + good + " --out /proc/envpis-no", "cannot create output directory '/proc/envpis-no'"},
      {"render --env " + good + " --out " + shell_quote(through_file + ".exr"), "cannot write --out '" + through_file + ".exr'"},
      {"render --env " + good + " --out /proc/envpis-no.exr", "cannot write --out '/proc/envpis-no.exr'"},
      {"render --env " + good + " --out " + shell_quote(path("out")) + "/x.exr --id-out /proc/no.png", "cannot write --id-out"},
      {"render --env " + good + " --out " + shell_quote(path("directory.exr")), "--out: '" + path("directory.exr") + "' is a directory"},
      {"compare --env " + good + " --out " + shell_quote(through_file), "--out '" + through_file + "'"},
      {"compare --env " + good + " --out " + shell_quote(path("good.exr")), "exists and is not a directory"},
      {"compare --env " + good + " --out /proc/envpis-no", "--out '/proc/envpis-no'"},
  };
  expect_one_line_errors(cases);
}

// Commands that fail after checking --out leave no file there, even when several run at once on the
// same path (the check once created and removed a probe file, and two such checks could leave one behind),
// and a file that was there is left as it was.
TEST_F(BadInput, FailedRendersLeaveTheOutputAsItWas) {
  const std::string good = shell_quote(path("good.exr"));
  for (const bool existed : {false, true}) {
    const std::string out = path(existed ? "out/kept.exr" : "out/none.exr");
    if (existed) std::ofstream(out) << "earlier";
    std::vector<std::pair<std::string, std::string>> cases;
    for (int i = 0; i < 24; ++i)
      cases.push_back({"render --env " + good + " --out " + shell_quote(out) + " --scene no-such-scene",
                       "no-such-scene"});
    expect_one_line_errors(cases, 8);
    if (!existed) {
      EXPECT_FALSE(fs::exists(out));
      continue;
    }
    std::ifstream in(out);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(text, "earlier");
  }
}

// Invalid values of the options every map-reading command shares.
TEST_F(BadInput, InvalidMapOptions) {
  const std::string good = shell_quote(path("good.exr"));
  std::vector<std::pair<std::string, std::string>> cases;
  for (const std::string& cmd : {std::string("render"), std::string("compare")}) {
    const std::string base = cmd + " --env " + good + " --out " + shell_quote(path("out/opt-" + cmd + (cmd == "render" ? ".exr" : "")));
    cases.push_back({base + " --env-scale -1", "--env-scale: must be >= 0, got '-1'"});
    cases.push_back({base + " --env-scale nan", "--env-scale: expected a finite number, got 'nan'"});
    cases.push_back({base + " --env-rotation 1e99", "--env-rotation: must be in [-1e6, 1e6] degrees"});
    cases.push_back({base + " --env-rotation inf", "--env-rotation: expected a finite number"});
    cases.push_back({base + " --env-mix 2", "--env-mix: must be in [0, 1], got '2'"});
    cases.push_back({base + " --proxy-min-alpha -0.5", "--proxy-min-alpha: must be in [0, 1]"});
    cases.push_back({base + " --proxy-max-alpha 1.5", "--proxy-max-alpha: must be in [0, 1], got '1.5'"});
    cases.push_back({base + " --proxy-transform wide", "--proxy-transform: unknown roughness transform 'wide'"});
    cases.push_back({base + " --proxy-lobe half", "--proxy-lobe: unknown reflection lobe 'half' (expected mirror or half-vector)"});
    cases.push_back({base + " --oracle-dirs 5", "--oracle-dirs: must be a square number"});
    cases.push_back({base + " --top 12.5", "--top: expected an integer in 1..256, got '12.5'"});
    cases.push_back({base + " --threads -2", "--threads: must be in 0..4096, got '-2'"});
    cases.push_back({base + " --closed-surfaces maybe", "--closed-surfaces: expected on or off, got 'maybe'"});
  }
  cases.push_back({"table --env " + good + " --out " + shell_quote(path("out/opt-table")) + " --scale -1", "--scale: must be >= 0"});
  cases.push_back({"table --env " + good + " --out " + shell_quote(path("out/opt-table")) + " --max-alpha x", "--max-alpha: expected a finite number, got 'x'"});
  expect_one_line_errors(cases);
}

}  // namespace
