// SPDX-License-Identifier: Apache-2.0
// libFuzzer target: ImportanceTable build, environment-only sampling and ProductSampler
// prepare/sample/pdf from arbitrary bytes.
//
// Input layout (missing bytes read as 0; see fuzz/README.md):
//   bytes  0..15  header
//     0  width - 1 (mod 64)             1  height - 1 (mod 64)
//     2  flags: bits 0-1 layout (auto, latlong, equal-area (forces a square), latlong),
//        bit 2 compensated table, bit 3 scalar kernel, bits 4-5 roughness transform
//        (hybrid, slides, abstract, hybrid), bit 6 rotate the map, bit 7 build the proxy with the
//        add_* calls (else the seven fields are set directly, unvalidated)
//     3  top resolution - 1 (mod 20)    4  importance floor (one of 8 values in [0, 1))
//     5  fine resolution: < 128 automatic, else 1..128
//     6  map scale (one of 8)           7  env_mix (one of 8 in [0, 1])
//     8  proxy min_alpha (one of 8 in [0, 1])
//     9  rotation angle (b * 360 / 256 degrees about +Z)
//     10..15 seed of the sample-point generator
//   bytes 16..39  normal (3 floats), outgoing direction wo (3 floats)
//   bytes 40..67  proxy: diffuse, translucent, reflection, refraction, alpha_reflection,
//                 alpha_refraction, ior (as add_* arguments when bit 7 of the flags is set)
//   bytes 68..    texels, RGB, row-major; repeated cyclically to fill the map (all 1 if absent)
// A "float" is 4 bytes: b0 < 0x30 picks a special value (0, -0, +-1, NaN, +-Inf, +-1e30, FLT_MAX,
// FLT_MIN, a denormal, 1e-30, 0.5, 1e-7, 2) by b1; b0 < 0xa0 gives a moderate value
// int16(b1 b2) / 4096 (about +-8); otherwise the 4 bytes are the IEEE float itself.
//
// Contract checked (aborts with a message when violated):
//   - the table's cell probabilities are finite, >= 0 and sum to 1 (all 0 for an empty table);
//   - every pdf returned by sample() or pdf() is finite and >= 0, exactly 0 for an invalid direction
//     and for an empty table / invalid sampler;
//   - a sample with pdf > 0 has a finite unit direction, and pdf(direction) equals its pdf;
//   - prepare() is valid exactly when the table is not empty and n and wo are valid directions, and
//     then the product's cell probabilities are finite, >= 0 and sum to 1.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "envpis/envpis.h"

namespace {

using namespace envpis;

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t byte(std::size_t i) const { return i < size_ ? data_[i] : 0; }
  float value(std::size_t i) const { return decode(byte(i), byte(i + 1), byte(i + 2), byte(i + 3)); }

  static float decode(std::uint8_t b0, std::uint8_t b1, std::uint8_t b2, std::uint8_t b3) {
    static const float kSpecial[16] = {0.0f,
                                       -0.0f,
                                       1.0f,
                                       -1.0f,
                                       std::numeric_limits<float>::quiet_NaN(),
                                       std::numeric_limits<float>::infinity(),
                                       -std::numeric_limits<float>::infinity(),
                                       1e30f,
                                       -1e30f,
                                       std::numeric_limits<float>::max(),
                                       std::numeric_limits<float>::min(),
                                       std::numeric_limits<float>::denorm_min(),
                                       1e-30f,
                                       0.5f,
                                       1e-7f,
                                       2.0f};
    if (b0 < 0x30) return kSpecial[b1 & 15];
    if (b0 < 0xa0) return static_cast<float>(static_cast<std::int16_t>(b1 | (b2 << 8))) / 4096.0f;
    const std::uint32_t bits = std::uint32_t(b0) | std::uint32_t(b1) << 8 | std::uint32_t(b2) << 16 |
                               std::uint32_t(b3) << 24;
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
};

constexpr std::size_t kHeader = 16, kGeometry = 16, kProxy = 40, kTexels = 68;

std::string describe(const char* what, Vec3 d) {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s (%.9g, %.9g, %.9g)", what, d.x, d.y, d.z);
  return buf;
}

[[noreturn]] void violated(const std::string& what) {
  std::fprintf(stderr, "fuzz_table_product: contract violated: %s\n", what.c_str());
  std::abort();
}

// The message is only built when the check fails (building it every time would halve the speed).
#define CHECK(ok, what)          \
  do {                           \
    if (!(ok)) violated(what);   \
  } while (0)

// ENVPIS_FUZZ_VERBOSE=1: print what each input decodes to (for reading crash reproducers and seeds).
bool verbose() {
  static const bool v = std::getenv("ENVPIS_FUZZ_VERBOSE") != nullptr;
  return v;
}

bool finite_nonneg(float p) { return std::isfinite(p) && p >= 0.0f; }

bool same_pdf(float a, float b) { return std::fabs(a - b) <= 1e-5f * std::max(std::fabs(a), std::fabs(b)); }

// splitmix64: the sample points, reproducible from the input.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  float uniform() { return static_cast<float>(next() >> 40) * 0x1p-24f; }  // [0, 1)
};

std::vector<Point2> sample_points(Rng& rng) {
  const float one_minus = 0x1.fffffep-1f;
  std::vector<Point2> u = {{0, 0}, {0.5f, 0.5f}, {one_minus, one_minus}, {1, 1}, {0, one_minus}, {one_minus, 0},
                           {1e-30f, 0.25f}};
  while (u.size() < 48) u.push_back({rng.uniform(), rng.uniform()});
  return u;
}

std::vector<Vec3> query_directions(Rng& rng, Vec3 n, Vec3 wo) {
  std::vector<Vec3> d = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {1, -1e-7f, 0},
                         {1e-30f, 1e-30f, 1}, {3e38f, 3e38f, 0}, n, wo, -n, -wo};
  for (int i = 0; i < 16; ++i) d.push_back({rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f});
  return d;
}

const Vec3 kInvalid[] = {{0, 0, 0},         {NAN, 0, 1},       {0, NAN, 0},  {INFINITY, 0, 0},
                         {-INFINITY, 1, 1}, {1e-30f, 0, 0}};

template <class Sampler>
void check_sampling(const Sampler& s, bool valid, const std::vector<Point2>& us, const std::vector<Vec3>& dirs,
                    const char* who) {
  const std::string name(who);
  for (const Point2& u : us) {
    const DirectionSample ds = s.sample(u);
    CHECK(finite_nonneg(ds.pdf), name + ": sample() pdf not finite and >= 0: " + std::to_string(ds.pdf));
    if (!valid) CHECK(ds.pdf == 0.0f, name + ": sample() of an empty/invalid sampler has pdf " + std::to_string(ds.pdf));
    if (ds.pdf > 0) {
      const Vec3 d = ds.direction;
      CHECK(std::isfinite(d.x) && std::isfinite(d.y) && std::isfinite(d.z),
            describe((name + ": sampled direction not finite").c_str(), d));
      CHECK(std::fabs(length(d) - 1.0f) < 1e-4f, describe((name + ": sampled direction not unit").c_str(), d));
      const float p = s.pdf(d);
      CHECK(same_pdf(p, ds.pdf), describe((name + ": pdf(direction) " + std::to_string(p) +
                                           " != sample pdf " + std::to_string(ds.pdf) + " at").c_str(), d));
    }
  }
  for (const Vec3& d : dirs) {
    const float p = s.pdf(d);
    CHECK(finite_nonneg(p), describe((name + ": pdf not finite and >= 0 (" + std::to_string(p) + ") at").c_str(), d));
    if (!valid) CHECK(p == 0.0f, describe((name + ": pdf of an empty/invalid sampler not 0 at").c_str(), d));
  }
  for (const Vec3& d : kInvalid) {
    const float p = s.pdf(d);
    CHECK(p == 0.0f, describe((name + ": pdf of an invalid direction not 0 (" + std::to_string(p) + ") at").c_str(), d));
  }
}

template <class ProbOf>
void check_distribution(int cells, ProbOf prob, bool nonzero, const char* who) {
  double sum = 0;
  for (int c = 0; c < cells; ++c) {
    const float p = prob(c);
    CHECK(finite_nonneg(p), std::string(who) + ": cell probability not finite and >= 0: " + std::to_string(p));
    sum += p;
  }
  if (nonzero)
    CHECK(std::fabs(sum - 1.0) < 1e-3, std::string(who) + ": cell probabilities sum to " + std::to_string(sum));
  else
    CHECK(sum == 0.0, std::string(who) + ": empty table has cell probabilities summing to " + std::to_string(sum));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const Reader in(data, size);
  const std::uint8_t flags = in.byte(2);

  // ---- the map ----
  const int layout_code = flags & 3;
  const int width = 1 + in.byte(0) % 64;
  const int height = layout_code == 2 ? width : 1 + in.byte(1) % 64;
  const std::size_t count = static_cast<std::size_t>(width) * height * 3;
  std::vector<float> rgb(count, 1.0f);
  if (size > kTexels) {
    const std::size_t n_values = (size - kTexels) / 4;
    if (n_values > 0)
      for (std::size_t i = 0; i < count; ++i) rgb[i] = in.value(kTexels + 4 * (i % n_values));
  }
  EnvironmentMapOptions mo;
  const MapLayout layouts[4] = {MapLayout::Auto, MapLayout::LatLong, MapLayout::EqualArea, MapLayout::LatLong};
  mo.layout = layouts[layout_code];
  const float scales[8] = {1.0f, 0.0f, 1e-30f, 1e30f, 0.5f, 3e38f, 1e-45f, 7.0f};
  mo.scale = scales[in.byte(6) & 7];
  if (flags & 0x40) mo.rotation = Mat3::rotate_z(in.byte(9) * (360.0f / 256.0f));

  ImportanceTableOptions to;
  to.top_resolution = 1 + in.byte(3) % 20;
  const float floors[8] = {1e-4f, 0.0f, 1e-6f, 0.5f, 0x1.fffffep-1f, 1e-30f, 0.1f, 1e-4f};
  to.floor = floors[in.byte(4) & 7];
  to.fine_resolution = in.byte(5) < 128 ? 0 : in.byte(5) - 127;
  to.compensated = (flags & 4) != 0;

  ProductSamplerOptions so;
  const float mixes[8] = {0.0f, 0.0f, 0.1f, 0.5f, 1.0f, 1e-7f, 0.999f, 0.0f};
  so.env_mix = mixes[in.byte(7) & 7];
  so.simd = (flags & 8) == 0 ? Simd::Best : Simd::Scalar;
  const RoughnessTransform transforms[4] = {RoughnessTransform::Hybrid, RoughnessTransform::Slides,
                                            RoughnessTransform::Abstract, RoughnessTransform::Fitted};
  so.proxy.transform = transforms[(flags >> 4) & 3];
  const float min_alphas[8] = {0.35f, 0.0f, 1e-3f, 1.0f, 0.5f, 0.35f, 1e-30f, 0.01f};
  so.proxy.min_alpha = min_alphas[in.byte(8) & 7];

  // ---- the shading point ----
  const Vec3 n{in.value(kGeometry), in.value(kGeometry + 4), in.value(kGeometry + 8)};
  const Vec3 wo{in.value(kGeometry + 12), in.value(kGeometry + 16), in.value(kGeometry + 20)};
  float pv[7];
  for (int i = 0; i < 7; ++i) pv[i] = in.value(kProxy + 4 * i);
  BsdfProxy proxy;
  if (flags & 0x80) {
    proxy.add_diffuse(pv[0]);
    proxy.add_translucent(pv[1]);
    proxy.add_reflection(pv[2], pv[4]);
    proxy.add_refraction(pv[3], pv[5], pv[6]);
  } else {
    proxy.diffuse = pv[0];
    proxy.translucent = pv[1];
    proxy.reflection = pv[2];
    proxy.refraction = pv[3];
    proxy.alpha_reflection = pv[4];
    proxy.alpha_refraction = pv[5];
    proxy.ior = pv[6];
  }

  Rng rng{0};
  for (std::size_t i = 10; i < kHeader; ++i) rng.s = rng.s * 257 + in.byte(i);
  const std::vector<Point2> us = sample_points(rng);
  const std::vector<Vec3> dirs = query_directions(rng, n, wo);

  try {
    const EnvironmentMap map = EnvironmentMap::from_pixels(width, height, std::move(rgb), mo);
    const ImportanceTable table(map, to);
    check_distribution(table.cell_count(), [&](int c) { return table.cell_probability(c); }, !table.empty(),
                       "table");
    CHECK(std::isfinite(table.integral()) && table.integral() >= 0,
          "table integral not finite and >= 0: " + std::to_string(table.integral()));
    check_sampling(table, !table.empty(), us, dirs, "ImportanceTable");

    if (verbose())
      std::fprintf(stderr,
                   "map %dx%d %s scale %g repaired %zu | table T=%d N=%d floor %g%s%s | n (%g %g %g) wo (%g %g %g) "
                   "proxy d %g t %g r %g T %g ar %g at %g ior %g | mix %g simd %d transform %s min_alpha %g\n",
                   map.width(), map.height(), to_string(map.layout()), map.scale(), map.load_report().repaired(),
                   table.top_resolution(), table.fine_resolution(), to.floor, to.compensated ? " compensated" : "",
                   table.empty() ? " EMPTY" : "", n.x, n.y, n.z, wo.x, wo.y, wo.z, proxy.diffuse, proxy.translucent,
                   proxy.reflection, proxy.refraction, proxy.alpha_reflection, proxy.alpha_refraction, proxy.ior,
                   so.env_mix, so.simd == Simd::Scalar ? 0 : 1, to_string(so.proxy.transform), so.proxy.min_alpha);
    ProductSampler sampler(table, so);
    // Two shading points with the same sampler: the scratch is reused between prepare() calls.
    const Vec3 normals[2] = {n, -n};
    for (const Vec3& nn : normals) {
      const bool valid = sampler.prepare(nn, wo, proxy);
      const bool expect = !table.empty() && is_valid_direction(nn) && is_valid_direction(wo);
      CHECK(valid == sampler.valid(), "prepare() result differs from valid()");
      CHECK(valid == expect, describe(valid ? "prepare() valid although table empty or n/wo invalid, n"
                                            : "prepare() invalid for a non-empty table and valid n, wo; n",
                                      nn) +
                                 describe(", wo", wo));
      if (valid)
        check_distribution(table.cell_count(), [&](int c) { return sampler.cell_probability(c); }, true,
                           "product");
      if (verbose())
        std::fprintf(stderr, "  prepare(n%s): valid %d fallback %d\n", &nn == normals ? "" : " flipped", valid ? 1 : 0,
                     sampler.uses_environment_fallback() ? 1 : 0);
      check_sampling(sampler, valid, us, dirs, "ProductSampler");
    }
  } catch (const Error& e) {
    violated(std::string("unexpected envpis::Error for in-range options: ") + e.what());
  }
  return 0;
}
