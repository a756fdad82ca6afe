// SPDX-License-Identifier: Apache-2.0
// metrics.json of `envpis compare`: the settings of the run, the reference, the regions, every measured
// strategy (with the medians and spread over the seeds), the overhead and the convergence series. The
// report (report.h) adds the plots' manifest and embeds the whole in index.html.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "compare_measured.h"
#include "compare_session.h"
#include "compare_steps.h"

namespace envpis::app {

/// Per object: relMSE, its standard error and the mean; `with_z` adds the bias z-score.
nlohmann::json regions_json(const std::vector<Region>& regions, const ImageMetrics& m, bool with_z);

/// One measured strategy: times, relMSE and the tail over the seeds, efficiency, per object, images.
nlohmann::json measured_json(const Measured& x, const std::vector<Region>& regions);

/// The whole of metrics.json but the plots. `exposure` is the PNGs' tonemapping k (compare_images.h).
nlohmann::json metrics_json(const CompareSession& session, const Comparison& c, const std::string& command_line,
                            double exposure);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
