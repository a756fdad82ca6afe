// SPDX-License-Identifier: Apache-2.0
// Internal: PreparedProxy -> the kernels' LobeParams.
#pragma once

#include "envpis/bsdf_proxy.h"
#include "kernels.h"

#include <algorithm>

namespace envpis::detail {

inline LobeParams to_lobe_params(const PreparedProxy& p) {
  LobeParams l{};
  l.n[0] = p.n.x; l.n[1] = p.n.y; l.n[2] = p.n.z;
  l.r[0] = p.r.x; l.r[1] = p.r.y; l.r[2] = p.r.z;
  l.t[0] = p.t.x; l.t[1] = p.t.y; l.t[2] = p.t.z;
  l.kd = p.kd;
  l.kt = p.kt;
  const float a2r = p.alpha_r * p.alpha_r, a2t = p.alpha_t * p.alpha_t;
  l.cr = p.wr * a2r * kInvPi;
  l.mr = a2r - 1.0f;
  l.ct = p.wt * a2t * kInvPi;
  l.mt = a2t - 1.0f;
  l.co = p.n.x * p.r.x + p.n.y * p.r.y + p.n.z * p.r.z;
  l.half = p.half_vector;
  // D(N.h) / (4 N.wo) integrates over wi to about 1, as the mirror lobe does (N.wo kept from 0).
  if (l.half) l.cr = p.wr * a2r * kInvPi / (4.0f * std::max(l.co, 0.05f));
  l.moments = 0;
  return l;
}

}  // namespace envpis::detail
