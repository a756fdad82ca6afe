// envpis: fast product importance sampling of environment maps
// (Conty Estevez & Lecocq, SIGGRAPH 2018 Talks). The umbrella header.
//
//   EnvironmentMap   map   = EnvironmentMap::load("sky.exr");       // once per map
//   ImportanceTable  table(map);                                    // once per map, shared
//   ProductSampler   ps(table);                                     // once per thread
//   ...per shading point:
//   BsdfProxy proxy; proxy.add_reflection(albedo, alpha); ...       // from the material's lobes
//   ps.prepare(normal, wo, proxy);
//   DirectionSample s = ps.sample(u);                               // {direction, pdf}
//   float w = power_heuristic(1, s.pdf, 1, bsdf_pdf(s.direction));  // MIS with BSDF sampling
#pragma once

#include "envpis/bsdf_proxy.h"
#include "envpis/common.h"
#include "envpis/discrete_distribution_2d.h"
#include "envpis/environment_map.h"
#include "envpis/equal_area.h"
#include "envpis/importance_table.h"
#include "envpis/mis.h"
#include "envpis/product_sampler.h"
#include "envpis/simd.h"

namespace envpis {
constexpr const char* kVersion = "0.1.0";
}
