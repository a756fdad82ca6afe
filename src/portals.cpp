// SPDX-License-Identifier: Apache-2.0
#include "envpis/portals.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "envpis/equal_area.h"

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

// Share of a ball on the positive side of a plane at signed distance x (in radii): a smooth estimate
// of a cone's share on one side of a plane (within 0.04 of the disk's share; see portals.h).
inline float cut_share(float x) {
  x = std::min(std::max(x, -1.0f), 1.0f);
  return 0.5f + x * (0.75f - 0.25f * x * x);
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

PortalView::PortalView(const ImportanceTable& table, const Portals& portals, const PortalViewOptions& options)
    : table_(&table), portals_(portals), options_(options) {
  if (options.grid < 1 || options.grid > 16) throw Error("portal grid must be in 1..16");
  const int T = table.top_resolution(), cells = table.cell_count();
  const std::size_t padded = static_cast<std::size_t>(table.top_level().padded_size());
  v_.assign(padded, 0.0f);
  seen_.reserve(static_cast<std::size_t>(Portals::kMaxPortals));
  for (auto* a : {&ax_, &ay_, &az_, &inv_sin_, &out_thr_, &in_thr_}) a->assign(padded, 0.0f);
  for (int c = 0; c < cells; ++c) {
    const Cone& k = table.cell_cone(c);
    ax_[c] = k.axis.x, ay_[c] = k.axis.y, az_[c] = k.axis.z;
    const bool small = k.cos_half_angle > 0.0f && k.sin_half_angle > 0.0f;  // else never in or out
    inv_sin_[c] = small ? 1.0f / k.sin_half_angle : 0.0f;
    out_thr_[c] = small ? -(k.sin_half_angle + kMargin) : -2.0f;
    in_thr_[c] = small ? k.sin_half_angle + kMargin : 2.0f;
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
  std::fill(v_.begin(), v_.end(), 0.0f);
  if (!finite(p)) return false;
  for (int i = 0; i < portals_.size(); ++i) {
    const Quad& q = portals_.quad(i);
    const float size = std::max(length(q.v[2] - q.v[0]), length(q.v[3] - q.v[1]));
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
    if (ok) seen_.push_back(s);
  }
  if (seen_.empty()) return false;
  if (options_.estimate == PortalEstimate::Grid)
    grid_pass();
  else
    cone_pass();
  const int cells = table_->cell_count();
  for (int c = 0; c < cells && !visible_; ++c) visible_ = v_[c] > 0.0f;
  return visible_;
}

// Every top cell against every seen portal, in arrays the compiler vectorizes: four dot products per
// cell and portal, the classification, the Cone estimate (portals.h).
void PortalView::cone_pass() {
  const int n = table_->cell_count();
  float* v = v_.data();
  for (const Seen& s : seen_) {
    for (int c = 0; c < n; ++c) {
      float share = 1.0f, lo = 2.0f;
      for (int k = 0; k < 4; ++k) {
        const float d = ax_[c] * s.n[k][0] + ay_[c] * s.n[k][1] + az_[c] * s.n[k][2];
        lo = std::min(lo, d - in_thr_[c]);  // >= 0 on every plane: inside
        share *= d < out_thr_[c] ? 0.0f : cut_share(d * inv_sin_[c]);
      }
      const float own = lo >= 0.0f ? 1.0f : (share > 0.0f ? std::max(share, kMinPartial) : 0.0f);
      v[c] = std::min(1.0f, v[c] + own);
    }
  }
}

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

float PortalView::cone_fraction(const Cone& cone) const {
  bool inside = false;
  const unsigned partial = classify(cone, inside);
  if (inside) return 1.0f;
  const float inv_sin = cone.cos_half_angle > 0.0f && cone.sin_half_angle > 0.0f ? 1.0f / cone.sin_half_angle : 0.0f;
  float v = 0;
  for (std::size_t i = 0; i < seen_.size(); ++i) {
    if (!(partial >> i & 1u)) continue;
    float share = 1.0f;
    for (int k = 0; k < 4; ++k) {
      const float* m = seen_[i].n[k];
      share *= cut_share((cone.axis.x * m[0] + cone.axis.y * m[1] + cone.axis.z * m[2]) * inv_sin);
    }
    v += std::max(share, kMinPartial);
  }
  return std::min(v, 1.0f);
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

void PortalView::grid_pass() {
  const int n = table_->cell_count(), K2 = options_.grid * options_.grid;
  for (int c = 0; c < n; ++c) {
    bool inside = false;
    const unsigned partial = classify(table_->cell_cone(c), inside);
    v_[c] = inside ? 1.0f : (partial ? grid_fraction(&grid_dirs_[static_cast<std::size_t>(c) * K2], K2, partial) : 0.0f);
  }
}

bool PortalView::subcell_fractions(int c, float* out) const {
  const int S = table_->subdivision(), T = table_->top_resolution();
  if (S == 1) {
    out[0] = v_[static_cast<std::size_t>(c)];
    return out[0] > 0.0f;
  }
  bool any = false;
  const bool grid = options_.estimate == PortalEstimate::Grid;
  const int g = std::max(2, options_.grid / S);
  Vec3 dirs[16 * 16];
  for (int s = 0; s < S * S; ++s) {
    out[s] = 0.0f;
    if (!(v_[static_cast<std::size_t>(c)] > 0.0f)) continue;
    const Cone& cone = table_->subcell_cone(c, s);
    if (!grid) {
      out[s] = cone_fraction(cone);
    } else {
      bool inside = false;
      const unsigned partial = classify(cone, inside);
      if (inside) {
        out[s] = 1.0f;
      } else if (partial) {
        const float x0 = float((c % T) * S + s % S), y0 = float((c / T) * S + s / S), TS = float(T * S);
        for (int j = 0; j < g; ++j)
          for (int i = 0; i < g; ++i)
            dirs[j * g + i] = equal_area_square_to_sphere({(x0 + (i + 0.5f) / g) / TS, (y0 + (j + 0.5f) / g) / TS});
        out[s] = grid_fraction(dirs, g * g, partial);
      }
    }
    any = any || out[s] > 0.0f;
  }
  return any;
}

}  // namespace envpis
