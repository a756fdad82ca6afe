// SPDX-License-Identifier: Apache-2.0
// What every render of one `envpis compare` run shares: the scene, the sampling options at the
// comparison's image size, each strategy's tables (built once, before its first render, and reported
// apart from the sampling time) and the progress lines.
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <cstdint>
#include <map>
#include <string>

#include "compare_options.h"
#include "progress.h"
#include "render/render.h"
#include "render/scene.h"

namespace envpis::app {

class CompareSession {
 public:
  /// `settings.base` with its size resolved against the scene's camera: a width or height of 0 follows
  /// the other and the camera's aspect, both 0 give half the camera's size.
  CompareSession(const CompareArgs& args, const CompareSettings& settings, const render::Scene& scene,
                 Progress& progress);

  const CompareArgs& args;
  const CompareSettings& settings;
  const render::Scene& scene;
  render::RenderOptions base;  // the settings' options at width x height
  int width = 0, height = 0;
  int threads_used = 0;        // --threads, or the hardware's
  Progress& progress;

  /// The strategy's tables, built on first use.
  const render::StrategyTables& tables_for(render::Strategy s);
  const std::map<render::Strategy, render::StrategyTables>& tables() const { return tables_; }
  /// Renders `spp` samples per pixel of `s` with `seed`; `label` names it on the progress bar a render
  /// of over 2 s shows on a terminal (none for an empty label); `log` collects its fireflies;
  /// `prefix_spp`: the images of fewer samples to keep as well (RenderOptions::prefix_spp).
  render::RenderResult render(render::Strategy s, int spp, std::uint64_t seed, const std::string& label,
                              const render::FireflyLogOptions* log = nullptr,
                              const std::vector<int>& prefix_spp = {});

 private:
  std::map<render::Strategy, render::StrategyTables> tables_;
  bool bar_ = false;
};

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
