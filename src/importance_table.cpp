// SPDX-License-Identifier: Apache-2.0
#include "envpis/importance_table.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "cell_cones.h"
#include "envpis_assert.h"
#include "envpis/equal_area.h"
#include "fine_level.h"
#include "map_texel_level.h"
#include "kernels.h"
#include "parallel.h"
#include "texel_importance.h"

#define ENVPIS_KERNEL_NS scalar
#include "equal_area_impl.h"

namespace envpis {

namespace {
constexpr int kMaxTop = 256;
constexpr int kMaxSubdivision = 8;
constexpr int kMaxSubcells = 1024;  // T S
constexpr int kMaxFine = 16384;
constexpr int kAutoFineCap = 2904;  // the automatic N of a 4096 x 2048 map: 67 MB of table
std::vector<detail::DirectionSums> leaf_directions(const detail::FineLevel& fine);
Vec3 square_to_sphere(Point2 p) {
  Vec3 d;
  detail::scalar::square_to_sphere_one<float>(p.x, p.y, d.x, d.y, d.z);
  return d;
}
}  // namespace

FineTexels parse_fine_texels(const std::string& s) {
  if (s == "equal-area") return FineTexels::EqualArea;
  if (s == "map") return FineTexels::Map;
  if (s == "auto") return FineTexels::Auto;
  throw Error("unknown fine texels '" + s + "' (expected equal-area, map or auto)");
}

const char* to_string(FineTexels f) {
  return f == FineTexels::Map ? "map" : f == FineTexels::Auto ? "auto" : "equal-area";
}

void validate(const ImportanceTableOptions& options) {
  if (options.top_resolution < 1 || options.top_resolution > kMaxTop)
    throw Error("top-level resolution must be in 1.." + std::to_string(kMaxTop) + ", got " +
                std::to_string(options.top_resolution));
  if (options.subdivision < 1 || options.subdivision > kMaxSubdivision)
    throw Error("sub-cell subdivision must be in 1.." + std::to_string(kMaxSubdivision) + ", got " +
                std::to_string(options.subdivision));
  if (options.top_resolution * options.subdivision > kMaxSubcells)
    throw Error("top-level resolution times subdivision must be at most " + std::to_string(kMaxSubcells));
  if (options.fine_resolution < 0 || options.fine_resolution > kMaxFine)
    throw Error("fine resolution must be 0 (automatic) or in 1.." + std::to_string(kMaxFine));
  if (!(options.floor >= 0.0f && options.floor < 1.0f))
    throw Error("importance floor must be in [0, 1)");
  if (!(options.peak_ratio == 0.0f || (options.peak_ratio >= 1.0f && options.peak_ratio <= 1e6f)))
    throw Error("peak ratio must be 0 (off) or in [1, 1e6]");
}

FineTexels resolve_fine_texels(FineTexels requested, const EnvironmentMap& map) {
  if (requested != FineTexels::Auto) return requested;
  return map.layout() == MapLayout::LatLong && map.filter() == MapFilter::Nearest ? FineTexels::Map
                                                                                  : FineTexels::EqualArea;
}

namespace {
// The equal-area fine level's grid: TS x TS leaves (sub-cells) of per_leaf x per_leaf texels.
struct FineGrid {
  int leaves, per_leaf;
  bool operator==(const FineGrid& o) const { return leaves == o.leaves && per_leaf == o.per_leaf; }
};
FineGrid fine_grid(const EnvironmentMap& map, const ImportanceTableOptions& options) {
  const int TS = options.top_resolution * options.subdivision;
  int n = options.fine_resolution;
  if (n == 0) {  // twice the map's resolution per side, up to kAutoFineCap (see the header)
    const double texels = double(map.width()) * double(map.height());
    const int n1 = static_cast<int>(std::ceil(std::sqrt(texels) - 1e-9));
    n = std::max(n1, std::min(2 * n1, kAutoFineCap));
  }
  int per_leaf = std::max(1, (n + TS - 1) / TS);  // fine texels per sub-cell along one axis
  if (TS * per_leaf > kMaxFine) per_leaf = kMaxFine / TS;
  return {TS, per_leaf};
}
}  // namespace

std::vector<std::shared_ptr<const ImportanceTable>> ImportanceTable::build_together(
    const EnvironmentMap& map, const std::vector<ImportanceTableOptions>& options) {
  for (const ImportanceTableOptions& o : options) validate(o);
  // Groups of equal-area tables on one grid with one peak ratio: the first member's gather serves all.
  std::vector<int> group(options.size(), -1);
  std::vector<std::size_t> first;  // per group, its first table
  for (std::size_t i = 0; i < options.size(); ++i) {
    if (resolve_fine_texels(options[i].fine_texels, map) != FineTexels::EqualArea) continue;
    for (std::size_t g = 0; g < first.size() && group[i] < 0; ++g) {
      const ImportanceTableOptions& f = options[first[g]];
      if (fine_grid(map, f) == fine_grid(map, options[i]) && f.peak_ratio == options[i].peak_ratio)
        group[i] = static_cast<int>(g);
    }
    if (group[i] < 0) {
      group[i] = static_cast<int>(first.size());
      first.push_back(i);
    }
  }
  std::vector<std::unique_ptr<detail::FineLevel>> gathered(first.size());
  for (std::size_t g = 0; g < first.size(); ++g) {
    if (std::count(group.begin(), group.end(), static_cast<int>(g)) < 2) continue;  // nothing to share
    const FineGrid grid = fine_grid(map, options[first[g]]);
    gathered[g] = std::make_unique<detail::FineLevel>(grid.leaves, grid.per_leaf);
    detail::gather_texel_importance(map, *gathered[g], options[first[g]].peak_ratio);
  }
  // The cones once per grid, before the tables are built side by side (each would compute them).
  std::vector<std::shared_ptr<const detail::CellCones>> cones;
  for (const ImportanceTableOptions& o : options) cones.push_back(detail::cell_cones(o.top_resolution, o.subdivision));
  std::vector<std::shared_ptr<const ImportanceTable>> out(options.size());
  detail::parallel_for(0, static_cast<int>(options.size()), [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const int g = group[static_cast<std::size_t>(i)];
      const detail::FineLevel* shared = g >= 0 ? gathered[static_cast<std::size_t>(g)].get() : nullptr;
      out[static_cast<std::size_t>(i)] =
          std::shared_ptr<const ImportanceTable>(new ImportanceTable(map, options[static_cast<std::size_t>(i)], shared));
    }
  });
  return out;
}

ImportanceTable::ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options)
    : ImportanceTable(map, options, nullptr) {}

ImportanceTable::ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options,
                                 const detail::FineLevel* gathered) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(options);
  T_ = options.top_resolution;
  S_ = options.subdivision;
  const int TS = T_ * S_;
  // Lookups instead of integer divisions where a pdf locates a texel.
  leaf_index_.resize(static_cast<std::size_t>(TS) * TS);
  for (int leaf = 0; leaf < TS * TS; ++leaf) {
    const int lx = leaf % TS, ly = leaf / TS;
    leaf_index_[static_cast<std::size_t>(leaf)] = {(ly / S_) * T_ + lx / S_, (ly % S_) * S_ + lx % S_};
  }
  const FineTexels kind = resolve_fine_texels(options.fine_texels, map);
  if (kind == FineTexels::Map) {
    if (map.layout() != MapLayout::LatLong) throw Error("fine texels 'map' needs a lat-long map");
    F_ = N_ = 0;
    auto level = std::make_shared<detail::MapTexelLevel>(
        map, TS,
        detail::MapTexelOptions{options.floor, options.peak_ratio, options.compensated,
                                map.filter() == MapFilter::Bilinear});
    map_texels_ = level;
    integral_ = level->integral();
    empty_ = !(integral_ > 0);
    build_levels(level->leaf_sums());
    build_cones();
    build_moments(level->leaf_directions());
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return;
  }
  const int per_leaf = fine_grid(map, options).per_leaf;
  F_ = per_leaf * S_;
  N_ = T_ * F_;
  axis_leaf_.resize(static_cast<std::size_t>(N_));
  for (int x = 0; x < N_; ++x) axis_leaf_[static_cast<std::size_t>(x)] = x / per_leaf;
  auto fine = std::make_shared<detail::FineLevel>(TS, per_leaf);  // its cells are the sub-cells
  fine_ = fine;
  const detail::TexelImportanceOptions importance{options.floor, options.peak_ratio, options.compensated};
  if (gathered) {  // the same grid and peak ratio (build_together): the gather's values, then this floor
    fine->values() = gathered->values();
    integral_ = detail::finish_texel_importance(map, *fine, importance);
  } else {
    integral_ = detail::build_texel_importance(map, *fine, importance);
  }
  empty_ = !(integral_ > 0);
  build_levels(fine->build());
  build_cones();
  build_moments(leaf_directions(*fine));
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

float ImportanceTable::importance(int x, int y) const {
  return map_texels_ ? map_texels_->importance(x, y) : fine_->values()[fine_->index(x, y)];
}

int ImportanceTable::importance_width() const { return map_texels_ ? map_texels_->width() : N_; }
int ImportanceTable::importance_height() const { return map_texels_ ? map_texels_->height() : N_; }

void ImportanceTable::cell_and_sub(int leaf, int& c, int& s) const {
  const LeafIndex& e = leaf_index_[static_cast<std::size_t>(leaf)];
  c = e.cell;
  s = e.sub;
}

// From the fine level's sums per sub-cell: the top cells' sums, the top level and each cell's
// sub-cell distribution.
void ImportanceTable::build_levels(const std::vector<double>& subcell_sums) {
  const int cells = T_ * T_, per = S_ * S_, TS = T_ * S_;
  std::vector<double> cell_sums(static_cast<std::size_t>(cells), 0.0);
  const float one = 1.0f;
  whole_cell_ = DiscreteDistribution2D(&one, 1, 1);
  if (S_ > 1) env_sub_.assign(static_cast<std::size_t>(cells), DiscreteDistribution2D(S_, S_));
  for (int c = 0; c < cells; ++c) {
    for (int s = 0; s < per; ++s) {
      const double v = subcell_sums[static_cast<std::size_t>(((c / T_) * S_ + s / S_) * TS + (c % T_) * S_ + s % S_)];
      cell_sums[c] += v;
      if (S_ > 1) env_sub_[c].values()[s] = static_cast<float>(v);
    }
    if (S_ > 1) env_sub_[c].update();
  }
  double total = 0;
  for (double v : cell_sums) total += v;
  top_ = DiscreteDistribution2D(T_, T_);
  for (int c = 0; c < cells; ++c) top_.values()[c] = total > 0 ? static_cast<float>(cell_sums[c] / total) : 0.0f;
  top_.update();
  for (auto& a : soa_) a.assign(static_cast<std::size_t>(top_.padded_size()), 0.0f);
  for (int c = 0; c < cells; ++c) soa_[5][c] = top_.values()[c];
  sub_stride_ = S_ > 1 ? (per + detail::kCellPad - 1) / detail::kCellPad * detail::kCellPad : 0;
  for (auto& a : sub_soa_) a.assign(static_cast<std::size_t>(cells) * sub_stride_, 0.0f);
  for (int c = 0; c < cells && sub_stride_ > 0; ++c)
    for (int s = 0; s < per; ++s) sub_soa_[5][static_cast<std::size_t>(c) * sub_stride_ + s] = env_sub_[c].pmf(s);
}


namespace {
void store_cone(std::vector<float> (&soa)[10], std::size_t i, const Cone& cone) {
  soa[0][i] = cone.axis.x;
  soa[1][i] = cone.axis.y;
  soa[2][i] = cone.axis.z;
  soa[3][i] = cone.cos_half_angle;
  soa[4][i] = cone.sin_half_angle;
}
// Padding entries: probability 0 and a cone that evaluates harmlessly.
void store_padding(std::vector<float> (&soa)[10], std::size_t i) {
  soa[2][i] = 1.0f;
  soa[3][i] = 1.0f;
  soa[8][i] = 1.0f;
}
}  // namespace

void ImportanceTable::build_cones() {
  const int cells = T_ * T_, per = S_ * S_;
  cell_cones_ = detail::cell_cones(T_, S_);
  cones_ = cell_cones_->top.data();
  sub_cones_ = cell_cones_->sub.data();
  for (int c = 0; c < cells; ++c) store_cone(soa_, c, cones_[c]);
  for (int c = cells; c < top_.padded_size(); ++c) store_padding(soa_, c);
  for (int c = 0; c < cells && sub_stride_ > 0; ++c) {
    const std::size_t base = static_cast<std::size_t>(c) * sub_stride_;
    for (int s = 0; s < per; ++s) store_cone(sub_soa_, base + s, subcell_cone(c, s));
    for (int s = per; s < sub_stride_; ++s) store_padding(sub_soa_, base + s);
  }
}

namespace {
// The fine-level cell (a sub-cell) of sub-cell s of top cell c.
int leaf_of(int T, int S, int c, int s) { return ((c / T) * S + s / S) * (T * S) + (c % T) * S + s % S; }
}  // namespace

namespace {
// The cell's mean direction (normalized) and spread 1 - |mean| into entry i of `soa`; importance
// weighted, or uniform where the cell has no importance (a compensated table's dark cells).
void store_moments(std::vector<float> (&soa)[10], std::size_t i, const detail::DirectionSums& s) {
  const bool weighted = s.w > 0;
  const double* m = weighted ? s.v : s.d;
  const double total = weighted ? s.w : s.n;
  const double len = std::sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
  if (!(len > 0) || !(total > 0)) {  // a cell symmetric about the centre (T = 1): no direction
    soa[8][i] = 1.0f;
    soa[9][i] = 1.0f;
    return;
  }
  for (int k = 0; k < 3; ++k) soa[6 + k][i] = static_cast<float>(m[k] / len);
  soa[9][i] = static_cast<float>(std::clamp(1.0 - len / total, 0.0, 1.0));
}
}  // namespace

namespace {
// Per leaf of an equal-area fine level: the sums over its texel centres.
std::vector<detail::DirectionSums> leaf_directions(const detail::FineLevel& fine) {
  const int TS = fine.cells(), P = fine.per_cell(), N = fine.resolution();
  const std::vector<float>& values = fine.values();
  const detail::Kernels& k = detail::kernels_for(Simd::Best);
  std::vector<detail::DirectionSums> leaf(static_cast<std::size_t>(TS) * TS);
  detail::parallel_for(0, TS, [&](int begin, int end) {
    std::vector<float> u(P), v(P), x(P), y(P), z(P);
    for (int ly = begin; ly < end; ++ly)
      for (int lx = 0; lx < TS; ++lx) {
        detail::DirectionSums& s = leaf[static_cast<std::size_t>(ly) * TS + lx];
        for (int j = 0; j < P; ++j) {
          const int ty = ly * P + j;
          for (int i = 0; i < P; ++i) {
            u[i] = (float(lx * P + i) + 0.5f) / float(N);
            v[i] = (float(ty) + 0.5f) / float(N);
          }
          k.square_to_sphere(P, u.data(), v.data(), x.data(), y.data(), z.data());
          for (int i = 0; i < P; ++i) s.add({x[i], y[i], z[i]}, values[fine.index(lx * P + i, ty)], 1.0);
        }
      }
  });
  return leaf;
}
}  // namespace

// Per top cell and sub-cell: the importance-weighted mean direction and spread (the product sampler's
// CellEstimate::Moments), from every fine texel's centre.
void ImportanceTable::build_moments(const std::vector<detail::DirectionSums>& leaf) {
  const int cells = T_ * T_, per = S_ * S_;
  for (int c = 0; c < cells; ++c) {
    detail::DirectionSums cell;
    for (int s = 0; s < per; ++s) {
      const detail::DirectionSums& l = leaf[static_cast<std::size_t>(leaf_of(T_, S_, c, s))];
      cell.add(l);
      if (sub_stride_ > 0) store_moments(sub_soa_, static_cast<std::size_t>(c) * sub_stride_ + s, l);
    }
    store_moments(soa_, c, cell);
  }
}

ImportanceTable::Located ImportanceTable::locate(Point2 p) const {
  // The sub-cell first, and the top cell and texel from it, so that they always agree under rounding.
  const int TS = T_ * S_, F = fine_->per_cell();
  const int lx = std::clamp(static_cast<int>(p.x * TS), 0, TS - 1);
  const int ly = std::clamp(static_cast<int>(p.y * TS), 0, TS - 1);
  const int tx = std::clamp(static_cast<int>(p.x * float(N_)), lx * F, lx * F + F - 1);
  const int ty = std::clamp(static_cast<int>(p.y * float(N_)), ly * F, ly * F + F - 1);
  Located at{0, 0, ly * TS + lx, tx - lx * F, ty - ly * F};
  cell_and_sub(at.leaf, at.cell, at.sub);
  return at;
}

ImportanceTable::Located ImportanceTable::locate_texel(int x, int y) const {
  const int TS = T_ * S_, F = fine_->per_cell(), lx = axis_leaf_[static_cast<std::size_t>(x)],
            ly = axis_leaf_[static_cast<std::size_t>(y)];
  Located at{0, 0, ly * TS + lx, x - lx * F, y - ly * F};
  cell_and_sub(at.leaf, at.cell, at.sub);
  return at;
}

int ImportanceTable::cell_of(Point2 p) const {
  if (!map_texels_) return locate(p).cell;
  int c, sub;
  cell_and_sub(map_texels_->locate(square_to_sphere(p)).leaf, c, sub);
  return c;
}

int ImportanceTable::cell_of_direction(Vec3 d) const {
  if (!is_valid_direction(d)) return -1;
  if (map_texels_) {
    int c, sub;
    cell_and_sub(map_texels_->locate(normalize(d)).leaf, c, sub);
    return c;
  }
  return cell_of(equal_area_sphere_to_square(d));
}

float ImportanceTable::solid_angle_pdf(float cell_pmf, float pdf_in_cell) const {
  return cell_pmf * pdf_in_cell * float(T_) * float(T_) * kInv4Pi;
}

namespace {
struct TexelPoint {
  Point2 p;
  bool interior;  // far enough inside its texel that locate(p) finds this texel again
};

// The equal-area point of texel t (and the offset inside it) of fine-level cell `leaf`, one of TS x TS
// cells of F x F texels.
TexelPoint texel_point(int leaf, int TS, int F, const CumulativeDistribution2DView::Sample& t) {
  const int lx = leaf % TS, ly = leaf / TS, N = TS * F;
  // The square -> sphere -> square round trip is accurate to a few 1e-6 (tests/test_equal_area.cpp);
  // 2% of a texel is at least 7e-6 for N <= 2904 and scales with the texel.
  constexpr float kMargin = 0.02f;
  const bool interior = t.offset.x > kMargin && t.offset.x < 1 - kMargin && t.offset.y > kMargin &&
                        t.offset.y < 1 - kMargin && N <= 2904;
  // Keep the point kEdge inside its cell. Rounding can put it on the cell's far edge (an offset of
  // 1 - 2^-24 in the last texel), and a point within round-off of the edge can come back from
  // square -> sphere -> square in the neighbouring cell, whose product weight may be 0 (a cell wholly
  // below an opaque proxy's horizon): the sample would get pdf 0 where pdf() integrates to 1. The
  // move is under 2% of a texel for N <= 1000 and such samples are never `interior`, so their density
  // is looked up again from the direction, which finds this cell.
  constexpr float kEdge = 2e-5f;
  const float inv = 1.0f / float(TS);
  const float px = (float(lx * F + t.x) + t.offset.x) / float(N);
  const float py = (float(ly * F + t.y) + t.offset.y) / float(N);
  return {{std::clamp(px, float(lx) * inv + kEdge, float(lx + 1) * inv - kEdge),
           std::clamp(py, float(ly) * inv + kEdge, float(ly + 1) * inv - kEdge)},
          interior};
}

}  // namespace

float ImportanceTable::pdf_in_cell(int c, Point2 p) const {
  if (map_texels_) {  // the solid-angle density inside the cell, per unit of the cell's area
    const detail::MapTexelLevel::Located at = map_texels_->locate(square_to_sphere(p));
    int cell, sub;
    cell_and_sub(at.leaf, cell, sub);
    if (cell != c) return 0.0f;
    return subcells(c).pmf(sub) * at.density / solid_angle_pdf(1.0f, 1.0f);
  }
  const Located at = locate(p);
  if (at.cell != c) return 0.0f;
  const float F = float(fine_->per_cell());
  return subcells(c).pmf(at.sub) * float(S_ * S_) * (fine_->cell(at.leaf).pmf(at.tx, at.ty) * F * F);
}

DirectionSample ImportanceTable::sample(const DiscreteDistribution2D& top, Point2 u, const SubcellLevel* sub) const {
  DirectionSample out;
  if (empty_ || !top.valid()) return out;
  ENVPIS_ASSERT(top.width() == T_ && top.height() == T_);
  const DiscreteDistribution2D::Sample cell = top.sample(u);
  const int c = cell.y * T_ + cell.x;
  DiscreteDistribution2D::Sample in{0, 0, cell.offset, 1.0f};  // the sub-cell (S = 1: the cell itself)
  if (S_ > 1) {
    const DiscreteDistribution2D& level = sub ? sub->subcells(c) : env_sub_[c];
    ENVPIS_ASSERT(level.valid() && level.width() == S_);
    in = level.sample(cell.offset);
  }
  const int TS = T_ * S_, leaf = leaf_of(T_, S_, c, in.y * S_ + in.x);
  if (map_texels_) {
    const detail::MapTexelLevel::Sample m = map_texels_->sample(leaf, in.offset);
    out.direction = m.direction;
    out.cell = c;
    out.texture = m.texture;
    // Round-off can put a direction on a texel edge into the neighbouring texel: pdf() of the
    // direction then, so that the two always agree.
    out.pdf = m.exact ? cell.pmf * in.pmf * m.density : pdf(top, out.direction, m.texture, sub);
    return out;
  }
  const int F = fine_->per_cell();
  const CumulativeDistribution2DView::Sample texel = fine_->cell(leaf).sample(in.offset);
  const TexelPoint at = texel_point(leaf, TS, F, texel);
  out.direction = square_to_sphere(at.p);
  out.cell = c;
  // Far from texel edges the sampled texel is the one pdf() finds: its density directly (the same
  // arithmetic); near an edge, pdf() of the direction, so the two always agree.
  out.pdf = at.interior ? solid_angle_pdf(cell.pmf, in.pmf * float(S_ * S_) * (texel.pmf * float(F) * float(F)))
                        : pdf(top, out.direction, sub);
  if (!(out.pdf > 0)) {
    // Round-off took a point at the texel's edge into a neighbour of no importance (a compensated
    // table has many): the texel's middle half instead, where the round trip cannot leave it.
    CumulativeDistribution2DView::Sample inner = texel;
    inner.offset = {0.25f + 0.5f * texel.offset.x, 0.25f + 0.5f * texel.offset.y};
    out.direction = square_to_sphere(texel_point(leaf, TS, F, inner).p);
    out.pdf = pdf(top, out.direction, sub);
  }
  return out;
}

float ImportanceTable::pdf(const DiscreteDistribution2D& top, Vec3 d, const SubcellLevel* sub) const {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  return pdf(top, d, Point2{kNaN, kNaN}, sub);
}

float ImportanceTable::pdf(const DiscreteDistribution2D& top, Vec3 d, Point2 texture, const SubcellLevel* sub) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return 0.0f;
  if (map_texels_) {  // d as given, not normalized: the look-up eval(d) makes, which sample() checks against
    const detail::MapTexelLevel::Located at = std::isfinite(texture.x) && std::isfinite(texture.y)
                                                  ? map_texels_->locate_texture(texture)
                                                  : map_texels_->locate(d);
    int c, s;
    cell_and_sub(at.leaf, c, s);
    const float cell_pmf = top.pmf(c);
    if (!(cell_pmf > 0)) return 0.0f;
    const float sub_pmf = S_ > 1 ? (sub ? sub->subcells(c) : env_sub_[c]).pmf(s) : 1.0f;
    return cell_pmf * sub_pmf * at.density;
  }
  return pdf_square(top, equal_area_sphere_to_square(d), sub);
}

void ImportanceTable::prefetch(Point2 texture) const {
  if (map_texels_ && std::isfinite(texture.x) && std::isfinite(texture.y)) map_texels_->prefetch(texture);
}

float ImportanceTable::pdf_square(const DiscreteDistribution2D& top, Point2 p, const SubcellLevel* sub) const {
  if (empty_ || !top.valid() || !in_unit_square(p)) return 0.0f;
  if (map_texels_) return pdf(top, square_to_sphere(p), sub);  // the map's texels are not the square's
  return pdf_located(top, locate(p), sub);
}

float ImportanceTable::pdf_texel(const DiscreteDistribution2D& top, int x, int y, const SubcellLevel* sub) const {
  if (empty_ || !top.valid() || map_texels_ || x < 0 || y < 0 || x >= N_ || y >= N_) return 0.0f;
  return pdf_located(top, locate_texel(x, y), sub);
}

float ImportanceTable::pdf_located(const DiscreteDistribution2D& top, const Located& at, const SubcellLevel* sub) const {
  const float cell_pmf = top.pmf(at.cell);
  if (!(cell_pmf > 0)) return 0.0f;
  const float sub_pmf = S_ > 1 ? (sub ? sub->subcells(at.cell) : env_sub_[at.cell]).pmf(at.sub) : 1.0f;
  const float F = float(fine_->per_cell());
  return solid_angle_pdf(cell_pmf, sub_pmf * float(S_ * S_) * (fine_->cell(at.leaf).pmf(at.tx, at.ty) * F * F));
}

Point2 ImportanceTable::invert(const DiscreteDistribution2D& top, Vec3 d, const SubcellLevel* sub) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return {0.5f, 0.5f};
  if (map_texels_) {
    const Vec3 n = normalize(d);
    int c, s;
    cell_and_sub(map_texels_->locate(n).leaf, c, s);
    Point2 offset = map_texels_->invert(n);
    if (S_ > 1) offset = (sub ? sub->subcells(c) : env_sub_[c]).invert(s % S_, s / S_, offset);
    return top.invert(c % T_, c / T_, offset);
  }
  const Point2 p = equal_area_sphere_to_square(d);
  const Located at = locate(p);
  const int TS = T_ * S_, F = fine_->per_cell();
  const Point2 in_texel{detail::clamp_unit(p.x * float(N_) - float((at.leaf % TS) * F + at.tx)),
                        detail::clamp_unit(p.y * float(N_) - float((at.leaf / TS) * F + at.ty))};
  Point2 offset = fine_->cell(at.leaf).invert(at.tx, at.ty, in_texel);
  if (S_ > 1) offset = (sub ? sub->subcells(at.cell) : env_sub_[at.cell]).invert(at.sub % S_, at.sub / S_, offset);
  return top.invert(at.cell % T_, at.cell / T_, offset);
}

detail::CellArrays detail::cell_arrays(const ImportanceTable& t) {
  const auto& a = t.soa_;
  return {a[0].data(), a[1].data(), a[2].data(), a[3].data(), a[4].data(), a[5].data(),
          a[6].data(), a[7].data(), a[8].data(), a[9].data(), t.top_.padded_size()};
}

detail::CellArrays detail::subcell_arrays(const ImportanceTable& t, int c) {
  const std::size_t o = static_cast<std::size_t>(c) * t.sub_stride_;
  const auto& a = t.sub_soa_;
  return {a[0].data() + o, a[1].data() + o, a[2].data() + o, a[3].data() + o, a[4].data() + o, a[5].data() + o,
          a[6].data() + o, a[7].data() + o, a[8].data() + o, a[9].data() + o, t.sub_stride_};
}

std::size_t ImportanceTable::bytes_used() const {
  std::size_t b = sizeof(*this);
  b += fine_ ? fine_->bytes_used() : map_texels_->bytes_used();
  b += static_cast<std::size_t>(top_.padded_size() + 2 * T_) * sizeof(float);
  b += (cell_cones_->top.capacity() + cell_cones_->sub.capacity()) * sizeof(Cone);  // shared with tables on the grid
  b += leaf_index_.capacity() * sizeof(LeafIndex) + axis_leaf_.capacity() * sizeof(std::int32_t);
  for (const auto& a : soa_) b += a.capacity() * sizeof(float);
  for (const auto& a : sub_soa_) b += a.capacity() * sizeof(float);
  if (S_ > 1)
    b += env_sub_.size() * (sizeof(DiscreteDistribution2D) + sizeof(float) * (env_sub_[0].padded_size() + 2 * S_));
  return b;
}

std::size_t ImportanceTable::single_level_bytes() const {
  if (map_texels_) {
    const std::size_t w = static_cast<std::size_t>(map_texels_->width()), h = static_cast<std::size_t>(map_texels_->height());
    return sizeof(float) * (w * h + h * (w + 1) + h + (h + 1));
  }
  const std::size_t n = static_cast<std::size_t>(N_);
  return sizeof(float) * (n * n + n * (n + 1) + n + (n + 1));
}

}  // namespace envpis
