// SPDX-License-Identifier: Apache-2.0
// Shared fixtures of the benchmarks: the blender maps, their tables, and precomputed arrays of
// shading points and random numbers (so the timed loops only cycle through memory).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "envpis/envpis.h"
#include "kernels.h"

namespace envpis_bench {

/// Number of precomputed shading points / random values the loops cycle through (power of two).
constexpr std::size_t kRing = 1024;

/// Directory of the blender studio-light maps (ENVPIS_BENCH_WORLD_DIR overrides at run time).
std::string world_dir();

/// Maps and tables, loaded / built once on first use (never inside a timed loop).
const envpis::EnvironmentMap& sunset_map();
const envpis::EnvironmentMap& studio_map();
/// sunset.exr resampled (bilinear, through EnvironmentMap::eval_texture) to 4096 x 2048.
const envpis::EnvironmentMap& sunset_4k_map();
/// A synthetic clear sky with a small sun (no file needed), 4096 x 2048 and 8192 x 4096.
const envpis::EnvironmentMap& sky_4k_map();
const envpis::EnvironmentMap& sky_8k_map();
const envpis::ImportanceTable& sunset_table();
/// The same map's table with 4 x 4 sub-cells per top cell (the refined product's).
const envpis::ImportanceTable& sunset_table_subcells();
/// The same map's table on its own texels with 4 x 4 sub-cells (the renderer's default for lat-long maps).
const envpis::ImportanceTable& sunset_table_map_texels();

struct ShadingPoint {
  envpis::Vec3 n, wo;
  envpis::BsdfProxy proxy;
};
/// kRing shading points: random normals, outgoing directions (90% above the surface) and a mix of
/// materials (diffuse, plastic, metal, glass, translucent) with random weights and roughnesses.
const std::vector<ShadingPoint>& shading_points();
/// kRing uniform points in [0,1)^2.
const std::vector<envpis::Point2>& uniform_points();
/// kRing uniform unit directions.
const std::vector<envpis::Vec3>& uniform_directions();
/// The instruction set the benchmarks ask the library for: ENVPIS_SIMD (best, scalar, sse2, avx2,
/// avx512), default best. The library itself never reads the environment.
envpis::Simd bench_simd();

}  // namespace envpis_bench
