// SPDX-License-Identifier: Apache-2.0
// The exact variance analyzer's results as JSON (docs/analyzer.md, "JSON"): what `envpis analyze --json`
// writes and what `envpis compare` puts under "analysis" in metrics.json, for its report.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <nlohmann/json.hpp>

#include "render/analyzer.h"

namespace envpis::app {

/// The settings, per object the pooled values and the decomposition, and every point's values.
nlohmann::json analysis_json(const render::Scene& scene, const render::Analyzer& analyzer,
                             const render::SceneAnalysis& analysis);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
