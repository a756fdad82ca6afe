// SPDX-License-Identifier: Apache-2.0
// The pictures of `envpis table`: the map in its own layout, the fine importance and the T x T cell
// probabilities on the equal-area square, with the horizon, the shading normal and the proxy's lobe axes
// drawn over them.
#pragma once

#include <vector>

#include "envpis/envpis.h"
#include "picture.h"

namespace envpis::app {

/// The map in its own layout: exposure so that the log-average luminance lands at 0.18, Reinhard, sRGB.
Image tonemap_map(const EnvironmentMap& map);

/// The fine importance on a log scale, t in [0, 1] per fine texel (row-major, N x N).
std::vector<float> importance_levels(const ImportanceTable& table);

/// Draws on a square picture: the top-level grid (if `grid`, with opacity `grid_alpha`), the horizon
/// as a dashed diamond, the normal as a green +, and the proxy's active lobe axes as rings (green:
/// diffuse N / translucent -N, cyan: reflection R, magenta: refraction T; none for a null `proxy`).
void draw_overlays(Image& img, int T, const PreparedProxy* proxy, Vec3 normal, bool grid, float grid_alpha);

/// T x T probabilities (row-major), log scale over four decades below the largest, zero cells dark grey.
Image cell_image(int T, const std::vector<float>& prob);

}  // namespace envpis::app
