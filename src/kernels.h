// SPDX-License-Identifier: Apache-2.0
// Internal: the vectorized kernels and their run-time dispatch.
#pragma once

#include <cstddef>
#include <vector>

#include "envpis/simd.h"

namespace envpis {
class ImportanceTable;
}

namespace envpis::detail {

/// Top-level cells in structure-of-arrays form, padded to a multiple of kCellPad with zero-probability
/// cells, so any SIMD width processes whole vectors.
constexpr int kCellPad = 16;
struct CellArrays {
  const float* ax;
  const float* ay;
  const float* az;    ///< cone axis
  const float* cosb;  ///< cos / sin of the cone half-angle
  const float* sinb;
  const float* prob;  ///< environment probability of the cell (sums to 1)
  const float* mx;    ///< the cell's importance-weighted mean direction, normalized
  const float* my;
  const float* mz;
  const float* spread;  ///< 1 - length of the unnormalized mean (its angular spread: E[1 - cos])
  int padded_count;
};

/// The proxy, prepared for one shading point: lobe axes and the coefficients of
///   diffuse     kd * max(0, cos t_N)
///   translucent kt * max(0, cos t_-N)
///   reflection  cr / (1 + mr cos^2 t_R)^2   for cos t_R > 0  (cr = w a^2 / pi, mr = a^2 - 1)
///   refraction  ct / (1 + mt cos^2 t_T)^2   for cos t_T > 0
/// where each t is the angle from the lobe axis to the closest direction of the cell's cone;
/// reflection and diffuse need the cell to reach above the horizon, refraction and translucent below.
///
/// With `moments` set, each lobe is evaluated instead at the cell's importance-weighted mean direction
/// (CellEstimate::Moments in envpis/product_sampler.h): the glossy lobes as above at that direction, the
/// cosine lobes as kd * E[max(0, N.w)] over the cell (a smooth maximum of the mean N.w and its spread);
/// the cone only gates the horizon.
struct LobeParams {
  float n[3], r[3], t[3];
  float kd, kt, cr, mr, ct, mt;
  float co;     ///< N.wo (= N.R)
  int half;     ///< the reflection lobe: 0 around R (c = R.wi), 1 GGX of the half-vector (c = N.h)
  int moments;  ///< 0: the cone-closest direction (the paper's), 1: the mean direction
};

/// The portal view's top cells (PortalView, src/portals.cpp), padded like CellArrays: each cell's cone
/// axis, cos / sin of its half-angle, `big` (4 for a cone of 90 degrees or more: always near; -64 for
/// padding: never), 1 / sin of the half-angle and the outside / inside thresholds of the planes.
struct PortalCellArrays {
  const float *ax, *ay, *az, *cosb, *sinb, *big, *inv_sin, *out_thr, *in_thr;
  int padded_count;
};
/// One portal seen from the shading point: its four edge planes' unit normals (inwards), its bounding
/// cone (axis g, cos / sin of its half-angle), the near test's bias (the margin, or 16 for a portal wider
/// than 90 degrees: every cell near) and the least partial share.
struct PortalPlanes {
  float n[4][3];
  float g[3];
  float cos_p, sin_p, near_bias, min_partial;
};

using SquareToSphereFn = void (*)(std::size_t, const float*, const float*, float*, float*, float*);
using SphereToSquareFn = void (*)(std::size_t, const float*, const float*, const float*, float*, float*);
/// Writes every cell's weight E[c] proxy(c) and returns their total (summed in lanes: not bit for bit
/// DiscreteDistribution2D's sum).
using ProductWeightsFn = float (*)(const CellArrays&, const LobeParams&, float* weights);
using FloorWeightsFn = void (*)(float* weights, const float* env, int count, float scale, float floor);
/// The fractions v of `count` portals' shares and the full cells; returns whether any is positive.
using PortalSharesFn = bool (*)(const PortalCellArrays&, const PortalPlanes* planes, int count, float* v,
                                float* full);

struct Kernels {
  const char* name;
  int width;
  SquareToSphereFn square_to_sphere;
  SphereToSquareFn sphere_to_square;
  ProductWeightsFn product_weights;
  FloorWeightsFn floor_weights;
  PortalSharesFn portal_shares;
};

const Kernels& kernels_scalar();
const Kernels& kernels_sse2();
const Kernels* kernels_avx2();    ///< nullptr when not compiled in
const Kernels* kernels_avx512();  ///< nullptr when not compiled in
/// Every set this build has and this CPU can run, from the scalar reference to the widest.
std::vector<const Kernels*> kernels_available();
/// The available set of that name ("scalar", "sse2", "avx2", "avx512"), or nullptr.
const Kernels* kernels_named(const char* name);
/// The set `simd` names (Best: the widest available); throws Error when it is not available.
const Kernels& kernels_for(Simd simd);

/// The table's top cells in the layout above (the table befriends this accessor).
CellArrays cell_arrays(const ImportanceTable& table);

}  // namespace envpis::detail
