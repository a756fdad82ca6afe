#include "envpis/importance_table.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "envpis_assert.h"
#include "envpis/equal_area.h"
#include "fine_level.h"
#include "kernels.h"
#include "parallel.h"
#include "texel_importance.h"

namespace envpis {

namespace {
constexpr int kMaxTop = 256;
constexpr int kMaxFine = 16384;
constexpr int kAutoFineCap = 2904;  // the automatic N of a 4096 x 2048 map: 67 MB of table
}  // namespace

void validate(const ImportanceTableOptions& options) {
  if (options.top_resolution < 1 || options.top_resolution > kMaxTop)
    throw Error("top-level resolution must be in 1.." + std::to_string(kMaxTop) + ", got " +
                std::to_string(options.top_resolution));
  if (options.fine_resolution < 0 || options.fine_resolution > kMaxFine)
    throw Error("fine resolution must be 0 (automatic) or in 1.." + std::to_string(kMaxFine));
  if (!(options.floor >= 0.0f && options.floor < 1.0f))
    throw Error("importance floor must be in [0, 1)");
  if (!(options.peak_ratio == 0.0f || (options.peak_ratio >= 1.0f && options.peak_ratio <= 1e6f)))
    throw Error("peak ratio must be 0 (off) or in [1, 1e6]");
}

ImportanceTable::ImportanceTable(const EnvironmentMap& map, const ImportanceTableOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  validate(options);
  T_ = options.top_resolution;
  int n = options.fine_resolution;
  if (n == 0) {  // twice the map's resolution per side, up to kAutoFineCap (see the header)
    const double texels = double(map.width()) * double(map.height());
    const int n1 = static_cast<int>(std::ceil(std::sqrt(texels) - 1e-9));
    n = std::max(n1, std::min(2 * n1, kAutoFineCap));
  }
  F_ = std::max(1, (n + T_ - 1) / T_);
  N_ = T_ * F_;
  if (N_ > kMaxFine) {
    F_ = kMaxFine / T_;
    N_ = T_ * F_;
  }
  auto fine = std::make_shared<detail::FineLevel>(T_, F_);
  fine_ = fine;
  integral_ = detail::build_texel_importance(map, *fine, {options.floor, options.peak_ratio, options.compensated});
  empty_ = !(integral_ > 0);
  build_top_level(fine->build());
  build_cones();
  build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

float ImportanceTable::importance(int x, int y) const { return fine_->values()[fine_->index(x, y)]; }

void ImportanceTable::build_top_level(const std::vector<double>& cell_sums) {
  const int cells = T_ * T_;
  double total = 0;
  for (double v : cell_sums) total += v;
  top_ = DiscreteDistribution2D(T_, T_);
  for (int c = 0; c < cells; ++c) top_.values()[c] = total > 0 ? static_cast<float>(cell_sums[c] / total) : 0.0f;
  top_.update();
  for (auto& a : soa_) a.assign(static_cast<std::size_t>(top_.padded_size()), 0.0f);
  for (int c = 0; c < cells; ++c) soa_[5][c] = top_.values()[c];
}

namespace {
// A cone that contains every direction of top cell c of a T x T grid on the equal-area square.
Cone bounding_cone(int T, int c) {
  constexpr int kEdge = 256;  // boundary samples per cell edge
  constexpr int kInner = 16;  // interior grid for the axis
  const int cx = c % T, cy = c / T;
  const float x0 = float(cx) / T, y0 = float(cy) / T, side = 1.0f / T;
  Cone cone;
  if (T <= 2) {  // cells of a quarter sphere or more: use the whole sphere
    cone.axis = equal_area_square_to_sphere({x0 + 0.5f * side, y0 + 0.5f * side});
    cone.cos_half_angle = -1.0f;
    cone.sin_half_angle = 0.0f;
    return cone;
  }
  double ax = 0, ay = 0, az = 0;
  for (int j = 0; j < kInner; ++j)
    for (int i = 0; i < kInner; ++i) {
      const Vec3 d = equal_area_square_to_sphere({x0 + (i + 0.5f) * side / kInner, y0 + (j + 0.5f) * side / kInner});
      ax += d.x;
      ay += d.y;
      az += d.z;
    }
  const double len = std::sqrt(ax * ax + ay * ay + az * az);
  const Vec3 axis{float(ax / len), float(ay / len), float(az / len)};
  // Walk the boundary; the largest angle from the axis over the cell is on its boundary (the cell is
  // a connected region that does not contain the axis' antipode). Every boundary point is within half
  // the largest gap between consecutive samples of one of them, so that half-gap is added.
  double max_angle = 0, max_gap = 0;
  Vec3 prev = equal_area_square_to_sphere({x0, y0});
  for (int k = 1; k <= 4 * kEdge; ++k) {
    const int e = (k - 1) / kEdge;
    const float t = float(k - e * kEdge) / kEdge;
    Point2 p;
    switch (e) {
      case 0: p = {x0 + t * side, y0}; break;
      case 1: p = {x0 + side, y0 + t * side}; break;
      case 2: p = {x0 + side - t * side, y0 + side}; break;
      default: p = {x0, y0 + side - t * side}; break;
    }
    const Vec3 d = equal_area_square_to_sphere(p);
    max_angle = std::max(max_angle, std::acos(std::clamp(double(dot(d, axis)), -1.0, 1.0)));
    max_gap = std::max(max_gap, std::acos(std::clamp(double(dot(d, prev)), -1.0, 1.0)));
    prev = d;
  }
  const double b = std::min(max_angle + 0.5 * max_gap + 1e-4, double(kPi));
  cone.axis = axis;
  cone.cos_half_angle = static_cast<float>(std::cos(b));
  cone.sin_half_angle = static_cast<float>(std::sin(b));
  return cone;
}
}  // namespace

void ImportanceTable::build_cones() {
  const int cells = T_ * T_;
  cones_.assign(cells, Cone{});
  detail::parallel_for(0, cells, [&](int begin, int end) {
    for (int c = begin; c < end; ++c) cones_[c] = bounding_cone(T_, c);
  });
  for (int c = 0; c < cells; ++c) {
    soa_[0][c] = cones_[c].axis.x;
    soa_[1][c] = cones_[c].axis.y;
    soa_[2][c] = cones_[c].axis.z;
    soa_[3][c] = cones_[c].cos_half_angle;
    soa_[4][c] = cones_[c].sin_half_angle;
  }
  // Padding cells: probability 0, a cone that evaluates harmlessly.
  for (int c = cells; c < top_.padded_size(); ++c) {
    soa_[2][c] = 1.0f;
    soa_[3][c] = 1.0f;
  }
}

int ImportanceTable::cell_of(Point2 p) const {
  const int cx = std::clamp(static_cast<int>(p.x * T_), 0, T_ - 1);
  const int cy = std::clamp(static_cast<int>(p.y * T_), 0, T_ - 1);
  return cy * T_ + cx;
}

int ImportanceTable::cell_of_direction(Vec3 d) const {
  if (!is_valid_direction(d)) return -1;
  return cell_of(equal_area_sphere_to_square(d));
}

float ImportanceTable::pdf_in_cell(int c, Point2 p) const { return fine_->pdf(c, p); }

DirectionSample ImportanceTable::sample(const DiscreteDistribution2D& top, Point2 u) const {
  DirectionSample out;
  if (empty_ || !top.valid()) return out;
  ENVPIS_ASSERT(top.width() == T_ && top.height() == T_);
  const DiscreteDistribution2D::Sample cell = top.sample(u);
  const int c = cell.y * T_ + cell.x;
  const detail::FineLevel::Sample s = fine_->sample(c, cell.offset);
  out.direction = equal_area_square_to_sphere(s.p);
  out.cell = c;
  // Far from texel edges the sampled texel is the one pdf() finds: its density directly (the same
  // arithmetic); near an edge, pdf() of the direction, so the two always agree.
  out.pdf = s.interior ? solid_angle_pdf(cell.pmf, s.pdf) : pdf(top, out.direction);
  return out;
}

float ImportanceTable::pdf(const DiscreteDistribution2D& top, Vec3 d) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return 0.0f;
  const Point2 p = equal_area_sphere_to_square(d);
  const int c = cell_of(p);
  return solid_angle_pdf(top.pmf(c), fine_->pdf(c, p));
}

Point2 ImportanceTable::invert(const DiscreteDistribution2D& top, Vec3 d) const {
  if (empty_ || !top.valid() || !is_valid_direction(d)) return {0.5f, 0.5f};
  const Point2 p = equal_area_sphere_to_square(d);
  const int c = cell_of(p);
  return top.invert(c % T_, c / T_, fine_->invert(c, p));
}

detail::CellArrays detail::cell_arrays(const ImportanceTable& t) {
  const auto& a = t.soa_;
  return {a[0].data(), a[1].data(), a[2].data(), a[3].data(), a[4].data(), a[5].data(), t.top_.padded_size()};
}

std::size_t ImportanceTable::bytes_used() const {
  std::size_t b = sizeof(*this);
  b += fine_->bytes_used();
  b += static_cast<std::size_t>(top_.padded_size() + 2 * T_) * sizeof(float);
  b += cones_.capacity() * sizeof(Cone);
  for (const auto& a : soa_) b += a.capacity() * sizeof(float);
  return b;
}

std::size_t ImportanceTable::single_level_bytes() const {
  const std::size_t n = static_cast<std::size_t>(N_);
  return sizeof(float) * (n * n + n * (n + 1) + n + (n + 1));
}

}  // namespace envpis
