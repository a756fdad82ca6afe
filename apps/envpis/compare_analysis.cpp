// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_analysis.h"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "analysis_json.h"
#include "render/analyzer.h"

namespace envpis::app {
namespace {

using namespace envpis::render;

bool contains(const std::vector<Strategy>& list, Strategy s) { return std::find(list.begin(), list.end(), s) != list.end(); }

/// The compared strategies, then env and product when missing (the decomposition's light distributions);
/// the exact levels 12, 24 and 48 up to the table's fine resolution `fine`.
AnalyzerOptions analyzer_options(const CompareSettings& settings, const RenderOptions& base, int fine) {
  AnalyzerOptions o;
  // The portal variants are left out: the analyzer's shading points carry no position for a PortalView
  // yet (docs/portals.md, "In the renderer"); their base strategies are analyzed when compared.
  o.strategies.clear();
  for (Strategy s : settings.strategies)
    if (!uses_portals(s)) o.strategies.push_back(s);
  for (Strategy s : {Strategy::Env, Strategy::Product})
    if (!contains(o.strategies, s)) o.strategies.push_back(s);
  o.heuristic = base.heuristic;
  o.exact_levels.clear();
  for (int t : {12, 24, 48})
    if (t <= fine) o.exact_levels.push_back(t);
  o.oracle = base.oracle;
  o.product = base.product;
  o.product_compensation = base.product_compensation;
  o.light_table = base.light_table;
  return o;
}

}  // namespace

void analyze_shading_points(CompareSession& session, Comparison& c) {
  const CompareSettings& s = session.settings;
  if (s.analysis_points <= 0) return;
  session.progress.line("analysis: exact variance at up to %d shading points per object ...", s.analysis_points);
  try {
    const RenderOptions& base = session.base;
    const EnvironmentMap& env = session.scene.environment();
    // The compared strategies' tables are the renders' own; the others are built once, with the same options.
    std::map<Strategy, StrategyTables> others;
    // The analyzer integrates over equal-area fine texels (render/analyzer.h): renders with the map's own
    // texels are analyzed through equal-area twins of their tables.
    ImportanceTableOptions equal_area = base.light_table;
    equal_area.fine_texels = FineTexels::EqualArea;
    auto source = [&](Strategy st) {
      if (contains(s.strategies, st)) {
        StrategyTables t = session.tables_for(st);
        if (!t.table || t.table->fine_texels() == FineTexels::EqualArea) return t;
      }
      auto it = others.find(st);
      if (it == others.end())
        it = others.emplace(st, StrategyTables::build(env, st, base.oracle, base.product, equal_area,
                                                      base.product_compensation))
                 .first;
      return it->second;
    };
    const int fine = source(Strategy::Mis).table->fine_resolution();
    const AnalyzerOptions o = analyzer_options(s, base, fine);
    tbb::task_arena arena(session.threads_used);
    arena.execute([&] {
      const Analyzer analyzer(session.scene, o, source);
      const SceneAnalysis a = analyze_scene(analyzer, session.scene, s.analysis_points, s.seed);
      c.analysis = analysis_json(session.scene, analyzer, a);
      session.progress.line("analysis: %zu points, %.3g directions, %.2f s (tables %.2f s)", a.analyzed,
                            double(a.evaluations), a.seconds + analyzer.build_seconds(), analyzer.build_seconds());
    });
  } catch (const std::exception& e) {
    c.analysis = nullptr;
    c.analysis_unavailable = std::string("the analysis failed: ") + e.what();
    std::fprintf(stderr, "envpis compare: warning: %s; metrics.json and the report have no analysis\n",
                 c.analysis_unavailable.c_str());
  }
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
