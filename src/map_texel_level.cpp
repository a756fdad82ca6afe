// SPDX-License-Identifier: Apache-2.0
#include "map_texel_level.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "envpis/equal_area.h"
#include "envpis_assert.h"
#include "huge_pages.h"
#include "parallel.h"

namespace envpis::detail {

namespace {
// The matrix of the map's to_map, from the images of the axes (its columns).
Mat3 to_map_matrix(const EnvironmentMap& map) {
  Mat3 m;
  const Vec3 col[3] = {map.to_map({1, 0, 0}), map.to_map({0, 1, 0}), map.to_map({0, 0, 1})};
  for (int j = 0; j < 3; ++j) {
    m.m[0][j] = col[j].x;
    m.m[1][j] = col[j].y;
    m.m[2][j] = col[j].z;
  }
  return m;
}
}  // namespace

MapTexelLevel::MapTexelLevel(const EnvironmentMap& map, int leaves, const MapTexelOptions& options)
    : to_map_(to_map_matrix(map)), to_world_(to_map_.transposed()), w_(map.width()), h_(map.height()),
      leaves_(leaves) {
  ENVPIS_ASSERT(map.layout() == MapLayout::LatLong && leaves >= 1);
  // 1 - cos theta in the northern half, 1 + cos theta in the southern one: both small near their pole,
  // where cos theta itself is within float round-off of +-1 across a whole polar row.
  row_qn_.resize(static_cast<std::size_t>(h_) + 1);
  row_qs_.resize(static_cast<std::size_t>(h_) + 1);
  for (int y = 0; y <= h_; ++y) {  // 2 sin^2(theta / 2) and 2 cos^2(theta / 2): no cancellation
    const double sn = std::sin(0.5 * kPi * double(y) / h_), cs = std::cos(0.5 * kPi * double(y) / h_);
    row_qn_[y] = static_cast<float>(2 * sn * sn);
    row_qs_[y] = static_cast<float>(2 * cs * cs);
  }
  row_sr_.resize(static_cast<std::size_t>(h_));
  for (int y = 0; y < h_; ++y) {  // (2 pi / w)(cos theta0 - cos theta1), in double for the thin polar rows
    const double c0 = std::cos(kPi * double(y) / h_), c1 = std::cos(kPi * double(y + 1) / h_);
    row_sr_[y] = static_cast<float>(2.0 * kPi / w_ * (c0 - c1));
  }
  assign_fresh(imp_, static_cast<std::size_t>(w_) * h_, 0.0f);  // huge_pages.h
  parallel_for(0, h_, [&](int begin, int end) {
    for (int y = begin; y < end; ++y)
      for (int x = 0; x < w_; ++x) imp_[static_cast<std::size_t>(y) * w_ + x] = map.texel(x, y).average();
  });
  compute_importance(options);
  assign_leaves(leaves);
  build_leaf_cdfs();
  build_guides();
}

namespace {
// The largest channel average among texel (x, y) and its eight neighbours (wrapping in x, clamped in
// y): every texel a bilinear look-up inside texel (x, y) interpolates between.
float neighbourhood_max(const std::vector<float>& lum, int w, int h, int x, int y) {
  float m = 0;
  for (int j = std::max(0, y - 1); j <= std::min(h - 1, y + 1); ++j)
    for (int i = -1; i <= 1; ++i) {
      const int xi = (x + i + w) % w;
      m = std::max(m, lum[static_cast<std::size_t>(j) * w + xi]);
    }
  return m;
}

// The map-frame directions of a w x h lat-long map's texel centres (latlong_to_direction of each
// centre, rounded once from double), from one sine and cosine per column and per row: the build visits
// all texels twice, and a sine and cosine per visit was a tenth of its time.
class TexelCentres {
 public:
  TexelCentres(int w, int h)
      : cos_phi_(std::size_t(w)), sin_phi_(std::size_t(w)), sin_theta_(std::size_t(h)), cos_theta_(std::size_t(h)) {
    for (int x = 0; x < w; ++x) {
      const double phi = 2.0 * kPi * (x + 0.5) / w;
      cos_phi_[std::size_t(x)] = static_cast<float>(std::cos(phi));
      sin_phi_[std::size_t(x)] = static_cast<float>(std::sin(phi));
    }
    for (int y = 0; y < h; ++y) {
      const double theta = kPi * (y + 0.5) / h;
      sin_theta_[std::size_t(y)] = static_cast<float>(std::sin(theta));
      cos_theta_[std::size_t(y)] = static_cast<float>(std::cos(theta));
    }
  }
  Vec3 operator()(int x, int y) const {
    const float s = sin_theta_[std::size_t(y)];
    return {s * cos_phi_[std::size_t(x)], s * sin_phi_[std::size_t(x)], cos_theta_[std::size_t(y)]};
  }

 private:
  std::vector<float> cos_phi_, sin_phi_, sin_theta_, cos_theta_;
};

// f(y) of every row y in [0, h), computed in parallel.
template <class Fn>
auto per_row(int h, const Fn& f) {
  std::vector<decltype(f(0))> out(static_cast<std::size_t>(h));
  parallel_for(0, h, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) out[static_cast<std::size_t>(y)] = f(y);
  });
  return out;
}

// The rows' sums added in row order: the same bits whatever the number of threads.
double sum_rows(const std::vector<double>& rows) {
  double sum = 0;
  for (double r : rows) sum += r;
  return sum;
}
}  // namespace

// importance = the texel's channel average (what a nearest look-up returns), raised by the peak bound
// where look-ups are bilinear, then floored or MIS-compensated against the mean per steradian.
void MapTexelLevel::compute_importance(const MapTexelOptions& options) {
  const std::size_t n = imp_.size();
  if (options.peak_ratio > 0 && options.bilinear) {
    std::vector<float> lum;
    assign_fresh(lum, n, 0.0f);
    parallel_for(0, h_, [&](int begin, int end) {
      std::copy(imp_.begin() + std::ptrdiff_t(begin) * w_, imp_.begin() + std::ptrdiff_t(end) * w_,
                lum.begin() + std::ptrdiff_t(begin) * w_);
    });
    const float inv_k = 1.0f / options.peak_ratio;
    parallel_for(0, h_, [&](int begin, int end) {
      for (int y = begin; y < end; ++y)
        for (int x = 0; x < w_; ++x) {
          float& v = imp_[static_cast<std::size_t>(y) * w_ + x];
          v = std::max(v, neighbourhood_max(lum, w_, h_, x, y) * inv_k);
        }
    });
  }
  // The rows' sums of f(importance) x solid angle; with `write`, every texel is replaced by f of it
  // (the plain sum reads only: writing 4 bytes per texel back unchanged costs a pass over the array).
  const auto map_rows = [&](const auto& f, bool write = true) {
    return sum_rows(per_row(h_, [&](int y) {
      double row = 0;
      float* v = imp_.data() + static_cast<std::size_t>(y) * w_;
      for (int x = 0; x < w_; ++x) {
        const float t = f(v[x]);
        if (write) v[x] = t;
        row += double(t);
      }
      return row * row_sr_[static_cast<std::size_t>(y)];
    }));
  };
  double sum = map_rows([](float v) { return v; }, false);
  if (!(sum > 0) || !std::isfinite(sum)) {
    parallel_fill(imp_.data(), n, 0.0f);
    integral_ = 0;
    return;
  }
  const float mean = static_cast<float>(sum / (4.0 * kPi));
  // A constant map's compensated table is the plain one (it would be empty).
  const auto varies = [&] {
    const auto range = per_row(h_, [&](int y) {
      const float* v = imp_.data() + static_cast<std::size_t>(y) * w_;
      const auto mm = std::minmax_element(v, v + w_);
      return std::pair<float, float>(*mm.first, *mm.second);
    });
    float lo = range[0].first, hi = range[0].second;
    for (const auto& r : range) lo = std::min(lo, r.first), hi = std::max(hi, r.second);
    return hi - lo > 1e-6f * hi;
  };
  if (options.compensated && varies()) {
    integral_ = map_rows([mean](float v) { return std::max(0.0f, v - mean); });
    return;
  }
  const float min_value = options.floor * mean;
  if (min_value > 0) sum = map_rows([min_value](float v) { return std::max(v, min_value); });
  integral_ = sum;
}

// Each texel to the leaf holding its centre's world direction; entries grouped by leaf (a counting
// sort that keeps row-major order inside each leaf, so neighbouring u pick neighbouring texels).
void MapTexelLevel::assign_leaves(int leaves) {
  const std::size_t n = static_cast<std::size_t>(w_) * h_;
  assign_fresh(at_, n, TexelLeaf{0.0f, 0});
  const TexelCentres centre(w_, h_);
  parallel_for(0, h_, [&](int begin, int end) {
    for (int y = begin; y < end; ++y)
      for (int x = 0; x < w_; ++x) {
        const Point2 p = equal_area_sphere_to_square(to_world_ * centre(x, y));
        const int lx = std::clamp(static_cast<int>(p.x * float(leaves)), 0, leaves - 1);
        const int ly = std::clamp(static_cast<int>(p.y * float(leaves)), 0, leaves - 1);
        at_[static_cast<std::size_t>(y) * w_ + x] = {0.0f, static_cast<std::uint32_t>(ly * leaves + lx)};
      }
  });
  // A counting sort over bands of rows: each band counts its texels per leaf, then writes them after
  // the earlier bands' texels of the same leaf, so a leaf's entries are in row-major order whatever
  // the number of bands.
  const std::size_t L = static_cast<std::size_t>(leaves) * leaves;
  const int bands = std::min(h_, 2 * parallel_threads());
  const auto rows_of = [&](int b) { return std::pair<int, int>(h_ * b / bands, h_ * (b + 1) / bands); };
  std::vector<std::vector<std::uint32_t>> next(static_cast<std::size_t>(bands), std::vector<std::uint32_t>(L, 0));
  const auto for_bands = [&](const auto& f) {  // f(band, first texel, end texel)
    parallel_for(0, bands, [&](int begin, int end) {
      for (int b = begin; b < end; ++b)
        f(next[static_cast<std::size_t>(b)], std::size_t(rows_of(b).first) * w_, std::size_t(rows_of(b).second) * w_);
    });
  };
  for_bands([&](std::vector<std::uint32_t>& count, std::size_t t0, std::size_t t1) {
    for (std::size_t t = t0; t < t1; ++t) ++count[at_[t].leaf];
  });
  start_.assign(L + 1, 0);
  for (std::size_t l = 0; l < L; ++l) {
    std::uint32_t run = start_[l];
    for (auto& band : next) run += std::exchange(band[l], run);  // the band's count becomes its offset
    start_[l + 1] = run;
  }
  assign_fresh(entry_, n, Entry{0.0f, 0});
  for_bands([&](std::vector<std::uint32_t>& offset, std::size_t t0, std::size_t t1) {
    for (std::size_t t = t0; t < t1; ++t) entry_[offset[at_[t].leaf]++] = {0.0f, static_cast<std::uint32_t>(t)};
  });
}

void MapTexelLevel::build_leaf_cdfs() {
  const int L = leaves_ * leaves_;
  leaf_sum_.assign(static_cast<std::size_t>(L), 0.0);
  inv_leaf_sum_.assign(static_cast<std::size_t>(L), 0.0f);
  parallel_for(0, L, [&](int begin, int end) {
    for (int l = begin; l < end; ++l) {
      double run = 0;
      for (std::uint32_t e = start_[l]; e < start_[l + 1]; ++e) {
        const std::uint32_t t = entry_[e].texel;
        run += double(imp_[t]) * row_sr_[t / static_cast<std::uint32_t>(w_)];
      }
      leaf_sum_[l] = run;
      if (!(run > 0)) continue;  // never chosen: every level above weighs a leaf by its sum
      inv_leaf_sum_[l] = static_cast<float>(1.0 / run);
      double acc = 0;
      for (std::uint32_t e = start_[l]; e < start_[l + 1]; ++e) {
        const std::uint32_t t = entry_[e].texel;
        acc += double(imp_[t]) * row_sr_[t / static_cast<std::uint32_t>(w_)];
        entry_[e].cdf = static_cast<float>(acc / run);
        at_[t].density = imp_[t] * inv_leaf_sum_[l];
      }
      entry_[start_[l + 1] - 1].cdf = 1.0f;
    }
  });
}

namespace {
constexpr std::uint32_t kGuideStride = 4;  // entries per guide index, on average over a leaf
// The guide bucket of cdf value x among g: monotone in x, so guides bracket every search.
inline std::uint32_t guide_key(float x, std::uint32_t g) {
  return std::min(g - 1, static_cast<std::uint32_t>(x * float(g)));
}
}  // namespace

void MapTexelLevel::build_guides() {
  const int L = leaves_ * leaves_;
  guide_start_.assign(static_cast<std::size_t>(L) + 1, 0);
  for (int l = 0; l < L; ++l) guide_start_[l + 1] = guide_start_[l] + (start_[l + 1] - start_[l]) / kGuideStride + 2;
  guide_.assign(guide_start_[L], 0);
  parallel_for(0, L, [&](int begin, int end) {
    for (int l = begin; l < end; ++l) {
      const Entry* first = entry_.data() + start_[l];
      const std::uint32_t n = start_[l + 1] - start_[l], g = guide_start_[l + 1] - guide_start_[l] - 1;
      std::uint32_t* guide = guide_.data() + guide_start_[l];
      std::uint32_t e = 0;
      for (std::uint32_t k = 0; k < g; ++k) {
        while (e < n && guide_key(first[e].cdf, g) < k) ++e;
        guide[k] = e;
      }
      guide[g] = n;
    }
  });
}

// The first entry of the leaf with cdf > u (the last one if none), as std::upper_bound over the whole
// leaf finds it: entries before guide k have key < k = key(u), hence cdf < u; the entry at guide k + 1
// has key > key(u), hence cdf > u.
const MapTexelLevel::Entry* MapTexelLevel::find(int leaf, float u) const {
  const Entry* first = entry_.data() + start_[leaf];
  const std::uint32_t n = start_[leaf + 1] - start_[leaf];
  const std::uint32_t* guide = guide_.data() + guide_start_[leaf];
  const std::uint32_t k = guide_key(u, guide_start_[leaf + 1] - guide_start_[leaf] - 1);
  // The guide and the leaf's first kPrefetchEntries entries (8 cache lines) are
  // fetched together rather than one after the other: on a large map both are rarely in cache.
  __builtin_prefetch(guide + k);
  constexpr std::uint32_t kPrefetchEntries = 64;
  const char* line = reinterpret_cast<const char*>(first);
  const char* end = reinterpret_cast<const char*>(first + std::min(n, kPrefetchEntries));
  for (; line < end; line += 64) __builtin_prefetch(line);
  // Bisection without a data-dependent branch: the entry stays among lo[0 .. len - 1] (the last entry,
  // of cdf 1, is above every u < 1), the comparison only selects the half.
  const Entry* lo = first + guide[k];
  std::uint32_t len = std::min(guide[k + 1] + 1, n) - guide[k];
  while (len > 1) {
    const std::uint32_t half = len / 2;
    lo = lo[half - 1].cdf <= u ? lo + half : lo;
    len -= half;
  }
  return std::min(lo, first + n - 1);
}

int MapTexelLevel::texel_at(Point2 uv) const {
  const TexelCoord t = latlong_texel(uv, w_, h_);
  return t.y * w_ + t.x;
}

MapTexelLevel::Sample MapTexelLevel::sample(int leaf, Point2 u) const {
  ENVPIS_ASSERT(leaf >= 0 && leaf < leaves_ * leaves_ && leaf_sum_[leaf] > 0);
  const float uy = clamp_unit(u.y);
  const Entry* it = find(leaf, uy);
  const float c0 = it > entry_.data() + start_[leaf] ? it[-1].cdf : 0.0f, c1 = it->cdf;
  const float r = c1 > c0 ? clamp_unit((uy - c0) / (c1 - c0)) : 0.5f;
  const std::uint32_t t = it->texel;
  __builtin_prefetch(&at_[t]);  // read after the direction's arithmetic
  const int x = static_cast<int>(t % static_cast<std::uint32_t>(w_)), y = static_cast<int>(t / static_cast<std::uint32_t>(w_));
  // Uniform in solid angle inside the texel: azimuth linear in u.x, cos theta linear in r (through
  // q = 1 -+ cos theta, see row_qn_). Both kept a thousandth of the texel from its edges, so that the
  // direction looks this texel up again despite round-off.
  constexpr float kMargin = 1e-3f;
  const float a = std::clamp(clamp_unit(u.x), kMargin, 1 - kMargin), b = std::clamp(r, kMargin, 1 - kMargin);
  const float phi = 2.0f * kPi * (float(x) + a) / float(w_);
  const bool north = 2 * y + 1 <= h_;  // the row's centre is not south of the equator
  const std::vector<float>& rq = north ? row_qn_ : row_qs_;
  const float q = rq[y] + b * (rq[y + 1] - rq[y]);  // theta increases with b in both halves
  const float z = north ? 1.0f - q : q - 1.0f;
  const float s = std::sqrt(std::max(0.0f, q * (2.0f - q)));
  Sample out;
  out.direction = normalize(to_world_ * Vec3{s * std::cos(phi), s * std::sin(phi), z});
  out.density = at_[t].density;
  out.texture = texture_of(out.direction);
  out.exact = texel_at(out.texture) == static_cast<int>(t);
  return out;
}

MapTexelLevel::Located MapTexelLevel::locate_texture(Point2 uv) const {
  const TexelLeaf& a = at_[static_cast<std::size_t>(texel_at(uv))];
  return {static_cast<int>(a.leaf), a.density};
}

Point2 MapTexelLevel::invert(Vec3 d) const {
  const int t = texel_at(texture_of(d));
  const std::uint32_t leaf = at_[static_cast<std::size_t>(t)].leaf;
  const Entry* first = entry_.data() + start_[leaf];
  const Entry* last = entry_.data() + start_[leaf + 1];
  const std::size_t e = static_cast<std::size_t>(
      std::lower_bound(first, last, static_cast<std::uint32_t>(t), [](const Entry& a, std::uint32_t v) { return a.texel < v; }) -
      entry_.data());
  const float c0 = e > start_[leaf] ? entry_[e - 1].cdf : 0.0f, c1 = entry_[e].cdf;
  const int x = t % w_, y = t / w_;
  const Vec3 m = to_map_ * d;
  // q of the direction as sample() computes it: 1 - z north, 1 + z south, from the polar angle.
  const float theta = direction_to_latlong(m).y * kPi;
  const bool north = 2 * y + 1 <= h_;
  const float half = 0.5f * (north ? theta : kPi - theta);
  const float q = 2.0f * std::sin(half) * std::sin(half);
  const std::vector<float>& rq = north ? row_qn_ : row_qs_;
  const float r = rq[y + 1] != rq[y] ? clamp_unit((q - rq[y]) / (rq[y + 1] - rq[y])) : 0.5f;
  const float ux = direction_to_latlong(m).x * float(w_) - float(x);
  return {clamp_unit(ux), clamp_unit(c0 + r * (c1 - c0))};
}

std::vector<DirectionSums> MapTexelLevel::leaf_directions() const {
  const int L = leaves_ * leaves_;
  std::vector<DirectionSums> out(static_cast<std::size_t>(L));
  const TexelCentres centre(w_, h_);
  parallel_for(0, L, [&](int begin, int end) {  // each leaf from its own texel list: no shared sums
    for (int l = begin; l < end; ++l)
      for (std::uint32_t e = start_[l]; e < start_[l + 1]; ++e) {
        const std::uint32_t t = entry_[e].texel;
        const int x = static_cast<int>(t % static_cast<std::uint32_t>(w_)), y = static_cast<int>(t / static_cast<std::uint32_t>(w_));
        out[static_cast<std::size_t>(l)].add(to_world_ * centre(x, y), double(imp_[t]) * row_sr_[y], row_sr_[y]);
      }
  });
  return out;
}

std::size_t MapTexelLevel::bytes_used() const {
  return sizeof(*this) +
         (row_sr_.capacity() + row_qn_.capacity() + row_qs_.capacity() + imp_.capacity() + inv_leaf_sum_.capacity()) *
             sizeof(float) +
         at_.capacity() * sizeof(TexelLeaf) + entry_.capacity() * sizeof(Entry) +
         (start_.capacity() + guide_.capacity() + guide_start_.capacity()) * sizeof(std::uint32_t) +
         leaf_sum_.capacity() * sizeof(double);
}

}  // namespace envpis::detail
