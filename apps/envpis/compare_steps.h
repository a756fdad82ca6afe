// SPDX-License-Identifier: Apache-2.0
// The measuring steps of `envpis compare`, in the order a run takes them (compare.cpp): the reference
// (cached), every strategy at equal spp (timing repeated, more seeds), the overhead of product over
// mis, the convergence series, and every strategy at equal time.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "compare_measured.h"
#include "compare_session.h"
#include "reference_cache.h"

namespace envpis::app {

/// Everything a run measured: what metrics.json, the images and the summary are made of.
struct Comparison {
  Reference reference;
  std::string cache_dir;  // where the reference is cached; empty with --no-cache
  std::vector<Region> regions;
  MeasuredSet equal_spp, equal_time;  // equal_time is empty without --equal-time
  double budget = 0;                  // seconds of sampling per strategy at equal time
  nlohmann::json overhead = nullptr;  // product against mis at equal spp; null without both
  nlohmann::json convergence = nlohmann::json::object();
  nlohmann::json analysis = nullptr;  // the exact variance analysis (compare_analysis.h); null when off
  std::string analysis_unavailable;   // why there is none, when it was asked for
};

/// Step 4: the reference, from the cache or rendered (and then cached).
void obtain_reference(CompareSession& session, Comparison& c);
/// Step 5: every strategy at --spp; also gives the object-id AOV (the reference's and the regions) and
/// the equal-time calibration.
void measure_equal_spp(CompareSession& session, Comparison& c);
/// Step 6: time(product) / time(mis) at equal spp, same run, same threads.
void measure_overhead(CompareSession& session, Comparison& c);
/// Step 7: relMSE at spp 1, 2, 4, ... and --spp (prefixes of the equal-spp renders: same seed).
void measure_convergence(CompareSession& session, Comparison& c);
/// Step 8: every strategy at the spp that fits the time budget (from its equal-spp seconds per spp).
void measure_equal_time(CompareSession& session, Comparison& c);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
