// SPDX-License-Identifier: Apache-2.0
// Step 9 of `envpis compare`: the exact variance analysis (render/analyzer.h) of the scene and map it
// renders, at --analysis-points first-hit points per object, with the run's own tables and sampling
// options. The compared strategies are analyzed, and env and product besides when they are not compared:
// the decomposition of issue 10 (V(env) / V(product), V(product) / V(exact-12), V(exact-12) /
// V(exact-48)) needs their light distributions. Its results go to metrics.json ("analysis") and the
// report's table of V per object and strategy.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include "compare_session.h"
#include "compare_steps.h"

namespace envpis::app {

/// Sets c.analysis; a failure is a warning (the renders are kept) and leaves c.analysis_unavailable.
void analyze_shading_points(CompareSession& session, Comparison& c);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
