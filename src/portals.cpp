// SPDX-License-Identifier: Apache-2.0
#include "envpis/portals.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
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
  x = x < -1.0f ? -1.0f : x;
  x = x > 1.0f ? 1.0f : x;
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
  for (auto* a : {&ax_, &ay_, &az_, &inv_sin_, &out_thr_, &in_thr_, &cos_, &sin_, &big_, &full_})
    a->assign(padded, 0.0f);
  near_.assign(padded, 0);
  candidates_.assign(padded, 0);
  for (auto& g : gather_) g.assign(padded, 0.0f);
  for (int c = 0; c < cells; ++c) {
    const Cone& k = table.cell_cone(c);
    ax_[c] = k.axis.x, ay_[c] = k.axis.y, az_[c] = k.axis.z;
    const bool small = k.cos_half_angle > 0.0f && k.sin_half_angle > 0.0f;  // else never in or out
    inv_sin_[c] = small ? 1.0f / k.sin_half_angle : 0.0f;
    out_thr_[c] = small ? -(k.sin_half_angle + kMargin) : -2.0f;
    in_thr_[c] = small ? k.sin_half_angle + kMargin : 2.0f;
    cos_[c] = small ? k.cos_half_angle : 0.0f;
    sin_[c] = small ? k.sin_half_angle : 0.0f;
    big_[c] = small ? 0.0f : 4.0f;  // a cone of 90 degrees or more: always near
  }
  for (std::size_t c = static_cast<std::size_t>(cells); c < padded; ++c) big_[c] = -8.0f;  // padding: never near
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
  std::fill(full_.begin(), full_.end(), 0.0f);
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
    if (!ok) continue;
    // The bounding cone: around the centre's direction, out to the farthest vertex. A cone wider than
    // 90 degrees is not convex on the sphere (it might not hold the edges): then every cell is near.
    const Vec3 g = normalize(centre);
    float cos_p = 1.0f;
    for (int k = 0; k < 4; ++k) cos_p = std::min(cos_p, dot(normalize(q.v[k] - p), g));
    s.g[0] = g.x, s.g[1] = g.y, s.g[2] = g.z;
    s.cos_p = cos_p;
    s.sin_p = std::sqrt(std::max(0.0f, 1.0f - cos_p * cos_p));
    s.wide = !(cos_p > 0.0f);
    seen_.push_back(s);
  }
  if (seen_.empty()) return false;
  cone_pass();  // sets visible_
  if (options_.estimate == PortalEstimate::Grid) grid_pass();
  return visible_;
}

// The near cells (candidates_[0, count)) against seen portal s, vectorized: their cones gathered into
// scratch arrays, the branch-free estimate over those (the compiler vectorizes it with
// -fno-trapping-math), the shares added back.
void PortalView::near_cells(const Seen& s, int count) {
  float* __restrict gx = gather_[0].data();
  float* __restrict gy = gather_[1].data();
  float* __restrict gz = gather_[2].data();
  float* __restrict gk = gather_[3].data();
  float* __restrict go = gather_[4].data();
  float* __restrict gi = gather_[5].data();
  for (int i = 0; i < count; ++i) {
    const int c = candidates_[i];
    gx[i] = ax_[c], gy[i] = ay_[c], gz[i] = az_[c], gk[i] = inv_sin_[c], go[i] = out_thr_[c], gi[i] = in_thr_[c];
  }
  const float(&m)[4][3] = s.n;
  const float x0 = m[0][0], y0 = m[0][1], z0 = m[0][2], x1 = m[1][0], y1 = m[1][1], z1 = m[1][2];
  const float x2 = m[2][0], y2 = m[2][1], z2 = m[2][2], x3 = m[3][0], y3 = m[3][1], z3 = m[3][2];
  for (int i = 0; i < count; ++i) {
    const float d0 = gx[i] * x0 + gy[i] * y0 + gz[i] * z0, d1 = gx[i] * x1 + gy[i] * y1 + gz[i] * z1;
    const float d2 = gx[i] * x2 + gy[i] * y2 + gz[i] * z2, d3 = gx[i] * x3 + gy[i] * y3 + gz[i] * z3;
    const float lo01 = d0 < d1 ? d0 : d1, lo23 = d2 < d3 ? d2 : d3, lo = lo01 < lo23 ? lo01 : lo23;
    const float k = gk[i];
    const float share = cut_share(d0 * k) * cut_share(d1 * k) * cut_share(d2 * k) * cut_share(d3 * k);
    float own = share > kMinPartial ? share : kMinPartial;
    own = lo < go[i] ? 0.0f : own;
    gx[i] = lo >= gi[i] ? 1.0f : own;  // gx: the share now
  }
  for (int i = 0; i < count; ++i) {
    const int c = candidates_[i];
    // Selects, not branches (the shares fall at random: a branch mispredicts).
    v_[c] = std::min(1.0f, v_[c] + gx[i]);
    full_[c] = gx[i] >= 1.0f ? 1.0f : full_[c];  // the portal holds the whole cone (see grid_pass)
    visible_ |= gx[i] > 0.0f;
  }
}

// One cell against one seen portal: the classification by the minimum of the four dot products
// (outside one plane: outside; inside all: inside) and the Cone estimate (portals.h).
inline float PortalView::cone_share(const Seen& s, int c) const {
  const float(&m)[4][3] = s.n;
  const float x = ax_[c], y = ay_[c], z = az_[c], k = inv_sin_[c];
  float lo = 2.0f, share = 1.0f;
  for (int i = 0; i < 4; ++i) {
    const float d = x * m[i][0] + y * m[i][1] + z * m[i][2];
    lo = std::min(lo, d);
    share *= cut_share(d * k);
  }
  if (lo < out_thr_[c]) return 0.0f;
  return lo >= in_thr_[c] ? 1.0f : std::max(share, kMinPartial);
}

// Every top cell against every seen portal. Most cells are far from a portal: a first pass, which the
// compiler vectorizes (branch-free, restrict pointers), keeps the cells whose cone meets the portal's
// bounding cone, angle(a, g) <= b + b_p, i.e. a . g >= cos b cos b_p - sin b sin b_p; only those get
// the four planes.
void PortalView::cone_pass() {
  const int n = table_->cell_count();
  const float* __restrict ax = ax_.data();
  const float* __restrict ay = ay_.data();
  const float* __restrict az = az_.data();
  const float* __restrict cosb = cos_.data();
  const float* __restrict sinb = sin_.data();
  const float* __restrict big = big_.data();
  const int padded = static_cast<int>(v_.size());  // a multiple of 16: whole words of flags
  std::uint8_t* __restrict flag = near_.data();
  for (const Seen& s : seen_) {
    const float gx = s.g[0], gy = s.g[1], gz = s.g[2], cp = s.cos_p, sp = s.sin_p;
    if (s.wide) {
      for (int c = 0; c < n; ++c) {
        const float share = cone_share(s, c);
        v_[c] = std::min(1.0f, v_[c] + share);
        if (share >= 1.0f) full_[c] = 1.0f;
        if (share > 0.0f) visible_ = true;
      }
      continue;
    }
    for (int c = 0; c < padded; ++c)
      flag[c] = ax[c] * gx + ay[c] * gy + az[c] * gz - (cosb[c] * cp - sinb[c] * sp) + big[c] + kMargin >= 0.0f;
    // The near cells' indices: eight flags at a time, one bit each, most words zero.
    int count = 0;
    for (int w = 0; w < padded; w += 8) {
      std::uint64_t bits;
      std::memcpy(&bits, flag + w, sizeof bits);
      for (; bits; bits &= bits - 1) candidates_[count++] = w + __builtin_ctzll(bits) / 8;
    }
    near_cells(s, count);
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
