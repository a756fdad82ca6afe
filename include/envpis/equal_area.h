// SPDX-License-Identifier: Apache-2.0
// Clarberg's equal-area mapping between the unit square [0,1]^2 and the unit sphere
// (P. Clarberg, "Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", JGT 13(3), 2008).
//
// The square is folded like an octahedron: the diamond |2x-1| + |2y-1| <= 1 maps to the upper
// hemisphere (z >= 0, north pole at the square's centre), the four corner triangles to the lower
// hemisphere (south pole at the four corners). Every region of the square maps to a region of the
// sphere with 4*pi times its area, so a density over the square converts to a density over solid
// angle by a constant: pdf_solid_angle = pdf_square / (4*pi).
//
// Edges wrap with a mirror: the point (0, y) touches (0, 1 - y) on the sphere, and likewise for the
// other three edges; see equal_area_wrap().
#pragma once

#include <cstddef>

#include "envpis/common.h"
#include "envpis/simd.h"

namespace envpis {

/// Density over solid angle of a uniform density over the unit square: 1 / (4 pi).
constexpr float kEqualAreaPdf = kInv4Pi;

/// Whether p lies in the closed square [0,1]^2 (false for NaN): a point whose density is defined.
inline bool in_unit_square(Point2 p) { return p.x >= 0 && p.x <= 1 && p.y >= 0 && p.y <= 1; }

/// The centre of texel (x, y) of an n x n grid over the square.
inline Point2 texel_centre(int x, int y, int n) { return {(float(x) + 0.5f) / float(n), (float(y) + 0.5f) / float(n)}; }

/// Square [0,1]^2 -> unit direction. Inputs outside [0,1] are clamped.
Vec3 equal_area_square_to_sphere(Point2 p);

/// Unit direction -> square [0,1]^2. The direction need not be normalized, but must be non-zero.
Point2 equal_area_sphere_to_square(Vec3 d);

/// Wraps integer texel coordinates of an n x n equal-area image so that neighbours across an edge
/// of the square are the texels that are neighbours on the sphere. Returns false if (x, y) is more
/// than one image width outside (the caller clamps then).
bool equal_area_wrap(int n, int& x, int& y);

/// Batched (structure-of-arrays) versions, vectorized with the instruction set `simd` (envpis/simd.h;
/// by default the widest this CPU runs). Any alignment works; the arrays must not overlap.
void equal_area_square_to_sphere(std::size_t n, const float* u, const float* v, float* x, float* y,
                                 float* z, Simd simd = Simd::Best);
void equal_area_sphere_to_square(std::size_t n, const float* x, const float* y, const float* z, float* u,
                                 float* v, Simd simd = Simd::Best);

}  // namespace envpis
