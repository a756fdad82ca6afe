// SPDX-License-Identifier: Apache-2.0
// Internal: the importance of every fine texel of the table (the rule is documented in
// importance_table.h): a gather of stratified bilinear look-ups, a splat of the map's texels where they
// are small, the peak bound, then the floor (or the MIS compensation).
#pragma once

#include "envpis/environment_map.h"
#include "fine_level.h"

namespace envpis::detail {

struct TexelImportanceOptions {
  float floor = 0;       ///< minimum importance relative to the mean
  float peak_ratio = 0;  ///< K of the peak bound, 0 = off
  bool compensated = false;
};

/// Writes every texel's importance into fine.values(); returns the importance integrated over the
/// sphere, 0 when the map is black (every value is then 0). The two steps below, in turn.
double build_texel_importance(const EnvironmentMap& map, FineLevel& fine, const TexelImportanceOptions& options);

/// The gather, the splat and the peak bound: what depends only on the map, the grid and peak_ratio,
/// so that tables on one grid can share it (ImportanceTable::build_together).
void gather_texel_importance(const EnvironmentMap& map, FineLevel& fine, float peak_ratio);
/// The floor or the compensation of the gathered values (options.peak_ratio is not used); returns the
/// integral as build_texel_importance() does.
double finish_texel_importance(const EnvironmentMap& map, FineLevel& fine, const TexelImportanceOptions& options);

}  // namespace envpis::detail
