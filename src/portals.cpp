// SPDX-License-Identifier: Apache-2.0
#include "envpis/portals.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <utility>

#include "envpis/equal_area.h"
#include "kernels.h"
#include "shared_per_grid.h"

#define ENVPIS_KERNEL_NS scalar
#include "portal_kernel_impl.h"

namespace envpis {

namespace {

std::string quad_name(int i) { return "portal " + std::to_string(i) + ": "; }

bool finite(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// Newell's normal: twice the area vector of the polygon, robust for any winding.
Vec3 area_vector(const Quad& q) {
  Vec3 n;
  for (int i = 0; i < 4; ++i) n = n + cross(q.v[i], q.v[(i + 1) % 4]);
  return n;
}

// The thresholds of the classification get a margin, so that round-off never calls a cell outside
// while a direction at its edge still passes the exact test.
constexpr float kMargin = 1e-5f;

}  // namespace

Portals::Portals(const std::vector<Quad>& quads) {
  for (const Quad& q : quads) add(q);
}

void Portals::add(const Quad& q) {
  const std::string name = quad_name(size());
  if (size() >= kMaxPortals) throw Error(name + "at most " + std::to_string(kMaxPortals) + " portals");
  for (const Vec3& v : q.v)
    if (!finite(v)) throw Error(name + "a vertex is not finite (NaN or infinite)");
  float size = 0;  // the longer diagonal
  size = std::max(length(q.v[2] - q.v[0]), length(q.v[3] - q.v[1]));
  if (!(size > 0) || !std::isfinite(size)) throw Error(name + "degenerate quad (all vertices coincide)");
  for (int i = 0; i < 4; ++i)
    if (!(length(q.v[(i + 1) % 4] - q.v[i]) > 1e-6f * size))
      throw Error(name + "degenerate quad (edge " + std::to_string(i) + " has zero length)");
  const Vec3 a = area_vector(q);
  if (!(length(a) * 0.5f > 1e-6f * size * size)) throw Error(name + "degenerate quad (zero area)");
  const Vec3 n = normalize(a);
  const Vec3 centre = (q.v[0] + q.v[1] + q.v[2] + q.v[3]) * 0.25f;
  for (int i = 0; i < 4; ++i)
    if (std::abs(dot(q.v[i] - centre, n)) > 1e-3f * size)
      throw Error(name + "not planar (vertex " + std::to_string(i) + " is off the quad's plane)");
  for (int i = 0; i < 4; ++i) {  // every corner turns the way the normal says
    const Vec3 e0 = q.v[(i + 1) % 4] - q.v[i], e1 = q.v[(i + 2) % 4] - q.v[(i + 1) % 4];
    if (!(dot(cross(e0, e1), n) > 1e-6f * size * size))
      throw Error(name + "not convex (at vertex " + std::to_string((i + 1) % 4) + ")");
  }
  quads_.push_back(q);
  normals_.push_back(n);
}

bool Portals::passes(int i, Vec3 p, Vec3 d) const {
  const Quad& q = quads_[static_cast<std::size_t>(i)];
  const Vec3 n = normals_[static_cast<std::size_t>(i)];
  const float denom = dot(d, n);
  if (!(denom > 0.0f)) return false;  // not outwards (or parallel, or NaN): portals are one-sided
  const float t = dot(q.v[0] - p, n) / denom;
  if (!(t > 0.0f) || !std::isfinite(t)) return false;
  const Vec3 hit = p + d * t;
  for (int k = 0; k < 4; ++k)  // inside every edge (counter-clockwise about n)
    if (dot(cross(q.v[(k + 1) % 4] - q.v[k], hit - q.v[k]), n) < 0.0f) return false;
  return true;
}

bool Portals::passes(Vec3 p, Vec3 d) const {
  for (int i = 0; i < size(); ++i)
    if (passes(i, p, d)) return true;
  return false;
}

const char* to_string(PortalEstimate e) { return e == PortalEstimate::Grid ? "grid" : "cone"; }

PortalEstimate parse_portal_estimate(const std::string& s) {
  if (s == "cone") return PortalEstimate::Cone;
  if (s == "grid") return PortalEstimate::Grid;
  throw Error("unknown portal estimate '" + s + "' (cone, grid)");
}

void PortalView::ConeArrays::assign(std::size_t padded) {
  for (auto* a : {&ax, &ay, &az, &inv_sin, &cos, &sin}) a->assign(padded, 0.0f);
  big.assign(padded, -64.0f);  // padding: never near, never in
  out_thr.assign(padded, 1.0f);
  in_thr.assign(padded, 2.0f);
}

void PortalView::ConeArrays::set(std::size_t i, const Cone& k) {
  ax[i] = k.axis.x, ay[i] = k.axis.y, az[i] = k.axis.z;
  const bool small = k.cos_half_angle > 0.0f && k.sin_half_angle > 0.0f;  // else never in or out
  inv_sin[i] = small ? 1.0f / k.sin_half_angle : 0.0f;
  out_thr[i] = small ? -(k.sin_half_angle + kMargin) : -2.0f;
  in_thr[i] = small ? k.sin_half_angle + kMargin : 2.0f;
  cos[i] = small ? k.cos_half_angle : 0.0f;
  sin[i] = small ? k.sin_half_angle : 0.0f;
  big[i] = small ? 0.0f : 4.0f;  // a cone of 90 degrees or more: always near
}

// The sub-cells' arrays depend on the grid alone (T, S: the table's cones, src/cell_cones.h), so views
// share them as tables share their cones.
std::shared_ptr<const PortalView::ConeArrays> PortalView::subcell_arrays(const ImportanceTable& table,
                                                                          std::size_t stride) {
  return detail::shared_per_grid<ConeArrays>(table.top_resolution(), table.subdivision(), [&] {
    auto a = std::make_shared<ConeArrays>();
    const int cells = table.cell_count(), per = table.subdivision() * table.subdivision();
    a->assign(stride * static_cast<std::size_t>(cells));
    for (int c = 0; c < cells; ++c)
      for (int s = 0; s < per; ++s) a->set(static_cast<std::size_t>(c) * stride + s, table.subcell_cone(c, s));
    return std::shared_ptr<const ConeArrays>(std::move(a));
  });
}

PortalView::PortalView(const ImportanceTable& table, const Portals& portals, const PortalViewOptions& options)
    : table_(&table), portals_(portals), options_(options), kernels_(&detail::kernels_for(options.simd)) {
  if (options.grid < 1 || options.grid > 16) throw Error("portal grid must be in 1..16");
  const int T = table.top_resolution(), cells = table.cell_count(), S = table.subdivision();
  const std::size_t padded = static_cast<std::size_t>(table.top_level().padded_size());
  v_.assign(padded, 0.0f);
  full_.assign(padded, 0.0f);
  seen_.reserve(static_cast<std::size_t>(Portals::kMaxPortals));
  for (int i = 0; i < portals.size(); ++i) {
    const Quad& q = portals.quad(i);
    sizes_.push_back(std::max(length(q.v[2] - q.v[0]), length(q.v[3] - q.v[1])));
  }
  top_.assign(padded);
  for (int c = 0; c < cells; ++c) top_.set(static_cast<std::size_t>(c), table.cell_cone(c));
  if (S > 1) {  // the sub-cells run through the same kernel, one cell's S^2 (padded to 16) at a time
    sub_stride_ = (static_cast<std::size_t>(S) * S + 15) / 16 * 16;
    sub_ = subcell_arrays(table, sub_stride_);
  }
  if (options.estimate != PortalEstimate::Grid) return;
  const int K = options.grid;
  grid_dirs_.reserve(static_cast<std::size_t>(cells) * K * K);
  for (int c = 0; c < cells; ++c)
    for (int j = 0; j < K; ++j)
      for (int i = 0; i < K; ++i)
        grid_dirs_.push_back(equal_area_square_to_sphere(
            {(float(c % T) + (i + 0.5f) / float(K)) / float(T), (float(c / T) + (j + 0.5f) / float(K)) / float(T)}));
}

bool PortalView::prepare(Vec3 p) {
  p_ = p;
  visible_ = false;
  seen_.clear();
  if (!finite(p)) {
    std::fill(v_.begin(), v_.end(), 0.0f);
    return false;
  }
  for (int i = 0; i < portals_.size(); ++i) {
    const Quad& q = portals_.quad(i);
    const float size = sizes_[static_cast<std::size_t>(i)];
    // Outside the room (on the environment's side) or edge-on: the portal shows p nothing.
    if (!(dot(p - q.v[0], portals_.normal(i)) < -1e-6f * size)) continue;
    const Vec3 centre = (q.v[0] + q.v[1] + q.v[2] + q.v[3]) * 0.25f - p;
    Seen s;
    bool ok = true;
    for (int k = 0; k < 4; ++k) {
      Vec3 n = cross(q.v[k] - p, q.v[(k + 1) % 4] - p);
      if (!is_valid_direction(n)) ok = false;
      if (!ok) break;
      n = normalize(n);
      if (dot(n, centre) < 0.0f) n = -n;  // the quad's directions on the positive side
      s.n[k][0] = n.x, s.n[k][1] = n.y, s.n[k][2] = n.z;
    }
    if (!ok) continue;
    // The bounding cone: around the centre's direction, out to the farthest vertex. A cone wider than
    // 90 degrees is not convex on the sphere (it might not hold the edges): then every cell is near.
    // cos_p = min_k g . (v_k - p) / |v_k - p|, from the squares (one square root, not four).
    const Vec3 g = normalize(centre);
    float cos2_p = 1.0f;
    bool wide = false;
    for (int k = 0; k < 4; ++k) {
      const Vec3 e = q.v[k] - p;
      const float d = dot(e, g);
      wide = wide || !(d > 0.0f);
      cos2_p = std::min(cos2_p, d * d / dot(e, e));
    }
    const float cos_p = wide ? 0.0f : std::sqrt(cos2_p);
    s.g[0] = g.x, s.g[1] = g.y, s.g[2] = g.z;
    s.cos_p = cos_p;
    s.sin_p = std::sqrt(std::max(0.0f, 1.0f - cos_p * cos_p));
    s.wide = wide || !(cos_p > 0.0f);
    seen_.push_back(s);
  }
  if (seen_.empty()) {
    std::fill(v_.begin(), v_.end(), 0.0f);
    return false;
  }
  cone_pass();  // sets visible_
  if (options_.estimate == PortalEstimate::Grid) grid_pass();
  return visible_;
}

// Every padded top cell against every seen portal, in one pass of the kernel of options().simd
// (src/portal_kernel_impl.h): a cell whose cone misses a portal's bounding cone, angle(a, g) > b + b_p,
// i.e. a . g < cos b cos b_p - sin b sin b_p, gets 0 from it (most cells are far from a window); the
// others the four planes. Every cell is computed (masked, not skipped): at 16 lanes that is cheaper than
// finding the few near ones and gathering them (docs/portals.md, measured). It writes every v_ and
// full_, so they need no clearing.
bool PortalView::shares(const ConeArrays& a, std::size_t offset, int count, float* v, float* full) const {
  const detail::PortalCellArrays cells{a.ax.data() + offset,      a.ay.data() + offset,      a.az.data() + offset,
                                       a.cos.data() + offset,     a.sin.data() + offset,     a.big.data() + offset,
                                       a.inv_sin.data() + offset, a.out_thr.data() + offset, a.in_thr.data() + offset,
                                       count};
  detail::PortalPlanes planes[Portals::kMaxPortals];
  int n = 0;
  for (const Seen& s : seen_) {
    detail::PortalPlanes& p = planes[n++];
    std::memcpy(p.n, s.n, sizeof p.n);
    std::memcpy(p.g, s.g, sizeof p.g);
    p.cos_p = s.cos_p;
    p.sin_p = s.sin_p;
    p.near_bias = s.wide ? 16.0f : kMargin;  // a wide bounding cone bounds nothing: every cell near
    p.min_partial = kMinPartial;
  }
  return kernels_->portal_shares(cells, planes, n, v, full);
}

void PortalView::cone_pass() { visible_ = shares(top_, 0, static_cast<int>(v_.size()), v_.data(), full_.data()); }

unsigned PortalView::classify(const Cone& cone, bool& inside) const {
  const bool small = cone.cos_half_angle > 0.0f && cone.sin_half_angle > 0.0f;
  const float out_thr = small ? -(cone.sin_half_angle + kMargin) : -2.0f;
  const float in_thr = small ? cone.sin_half_angle + kMargin : 2.0f;
  unsigned partial = 0;
  inside = false;
  for (std::size_t i = 0; i < seen_.size(); ++i) {
    bool out = false, in = true;
    for (int k = 0; k < 4; ++k) {
      const float* m = seen_[i].n[k];
      const float d = cone.axis.x * m[0] + cone.axis.y * m[1] + cone.axis.z * m[2];
      out = out || d < out_thr;
      in = in && d >= in_thr;
    }
    if (in) inside = true;
    if (!out) partial |= 1u << i;
  }
  return partial;
}

// The share of `count` directions that pass through one of the portals in `mask` (the edge planes
// from p: exact for a convex quad), at least kMinPartial.
float PortalView::grid_fraction(const Vec3* dirs, int count, unsigned mask) const {
  int hits = 0;
  for (int j = 0; j < count; ++j) {
    const Vec3 d = dirs[j];
    for (std::size_t i = 0; i < seen_.size(); ++i) {
      if (!(mask >> i & 1u)) continue;
      bool in = true;
      for (int k = 0; k < 4 && in; ++k) {
        const float* m = seen_[i].n[k];
        in = d.x * m[0] + d.y * m[1] + d.z * m[2] >= 0.0f;
      }
      if (in) {
        ++hits;
        break;
      }
    }
  }
  return std::max(float(hits) / float(count), kMinPartial);
}

// After cone_pass: the partial cells (V > 0, no portal covering the whole cone) re-estimated from
// their grid of directions.
void PortalView::grid_pass() {
  const int n = table_->cell_count(), K2 = options_.grid * options_.grid;
  const unsigned all = (1u << seen_.size()) - 1u;
  for (int c = 0; c < n; ++c)
    if (v_[c] > 0.0f && !(full_[c] > 0.0f))
      v_[c] = grid_fraction(&grid_dirs_[static_cast<std::size_t>(c) * K2], K2, all);
}

bool PortalView::subcell_fractions(int c, float* out) const {
  const int S = table_->subdivision(), T = table_->top_resolution();
  if (S == 1) {
    out[0] = v_[static_cast<std::size_t>(c)];
    return out[0] > 0.0f;
  }
  if (!(v_[static_cast<std::size_t>(c)] > 0.0f)) {
    std::fill(out, out + S * S, 0.0f);
    return false;
  }
  if (options_.estimate == PortalEstimate::Cone) {  // the top cells' kernel over the cell's sub-cells
    float v[64], full[64];  // sub_stride_ <= 64 (S <= 8)
    const bool any = shares(*sub_, static_cast<std::size_t>(c) * sub_stride_, static_cast<int>(sub_stride_), v, full);
    std::copy(v, v + S * S, out);
    return any;
  }
  bool any = false;
  const int g = std::max(2, options_.grid / S);
  Vec3 dirs[16 * 16];
  for (int s = 0; s < S * S; ++s) {
    bool inside = false;
    const unsigned partial = classify(table_->subcell_cone(c, s), inside);
    out[s] = inside ? 1.0f : 0.0f;
    if (!inside && partial) {
      const float x0 = float((c % T) * S + s % S), y0 = float((c / T) * S + s / S), TS = float(T * S);
      for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i)
          dirs[j * g + i] = equal_area_square_to_sphere({(x0 + (i + 0.5f) / g) / TS, (y0 + (j + 0.5f) / g) / TS});
      out[s] = grid_fraction(dirs, g * g, partial);
    }
    any = any || out[s] > 0.0f;
  }
  return any;
}

}  // namespace envpis
