// SPDX-License-Identifier: Apache-2.0
// Internal: an upper bound of what the map's reconstruction (EnvironmentMap::eval, bilinear or nearest) returns
// inside each texel of an N x N grid over the world's equal-area square.
//
// Why: the table's importance is an average over each texel, and a small bright source (a sun) whose
// bilinear footprint reaches into a texel without raising its average much would be sampled with a
// tiny density and enormous weight L / p (a firefly). ImportanceTable raises every texel to at least
// its peak divided by a fixed ratio, which bounds every light sample's weight.
//
// How: a texel's outline (corners and edge midpoints) is mapped into the map's pixel coordinates; the
// bounding box of those points, widened by a margin for the outline's curvature and by the bilinear
// footprint, contains every map texel that can contribute inside the texel. The peak is the largest of
// those texels (a direct scan of the map's rows; block maxima for wide ranges). Texels near a lat-long
// map's poles take the whole azimuth range; lat-long seams are unwrapped. Rows of the grid run in
// parallel, each mapping its outline points once.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

#include "envpis/environment_map.h"
#include "fine_level.h"

namespace envpis::detail {

// A texel's outline is 8 points going round: corners at even k, edge midpoints at odd k.

/// Texel range [lo, hi] that eval can read at pixel coordinates [a, b] (texel centres at integers): a
/// bilinear look-up reads the texels either side, a nearest one the closest. The margin covers the
/// outline's curvature between its sample points. Bilinear: a fixed fraction of the extent. Nearest:
/// `sag`, how far the outline's edge midpoints lie off the chords of their corners (pixels), measured
/// per texel. Between two sample points half an edge apart the curve strays a quarter of that (a
/// sagitta scales with the square of the chord); half of it plus 0.01 pixel of round-off is kept. A
/// fixed 0.05 + 0.25 (b - a) let every nearest texel reach its neighbours, which drew light samples
/// onto the black beside a small sun (docs/cycles.md, "Why Cycles converged faster in the highlight").
void footprint(float a, float b, bool nearest, float sag, int& lo, int& hi);

/// The outline's largest sagitta along u and along v, in pixels: for each of the 4 edges, the
/// midpoint's distance from the corners' mean. Azimuth differences (turns) are taken across the seam.
std::pair<float, float> outline_sag(const float* us, const float* vs, int w, int h);

/// The map coordinates (u, v) of n world directions (x, y, z), which are replaced by their map-space
/// directions (EnvironmentMap::to_map): direction_to_latlong or equal_area_sphere_to_square of those,
/// bit for bit, the lat-long conversion a few lanes at a time (the gather and the bound read the map
/// through it).
void map_coordinates(const EnvironmentMap& map, std::size_t n, float* x, float* y, float* z, float* u, float* v);

/// `lum` holds the map's per-texel importance (channel average), row-major, width * height.
/// Returns N * N peaks, row-major over the equal-area square (y down).
std::vector<float> texel_peaks(const EnvironmentMap& map, const std::vector<float>& lum, int N);

/// The bound applied in the same pass, without the N * N array of peaks: every texel of `fine` is
/// raised to at least its peak times inv_k (the same values as max(v, texel_peaks(...)[i] * inv_k)).
void raise_to_peaks(const EnvironmentMap& map, const std::vector<float>& lum, float inv_k, FineLevel& fine);

}  // namespace envpis::detail
