// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_session.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

namespace envpis::app {
namespace {

/// `side` from the other side `other` given and the camera's aspect other_cam : side_cam; half the
/// camera's size when neither is given.
int resolve_side(int side, int other, int side_cam, int other_cam) {
  if (side > 0) return side;
  if (other > 0) return std::max(1, static_cast<int>(std::lround(double(other) * side_cam / other_cam)));
  return std::max(1, side_cam / 2);
}

}  // namespace

CompareSession::CompareSession(const CompareArgs& a, const CompareSettings& s, const render::Scene& sc, Progress& p)
    : args(a), settings(s), scene(sc), base(s.base), progress(p) {
  const auto& cam = scene.camera();
  width = resolve_side(s.base.width, s.base.height, cam.width, cam.height);
  height = resolve_side(s.base.height, s.base.width, cam.height, cam.width);
  base.width = width;
  base.height = height;
  threads_used = base.threads > 0 ? base.threads : static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  bar_ = !a.quiet && isatty(STDERR_FILENO);
}

const render::StrategyTables& CompareSession::tables_for(render::Strategy s) {
  auto it = tables_.find(s);
  if (it == tables_.end()) {
    it = tables_.emplace(s, render::build_render_tables(scene.environment(), s, base)).first;
  }
  return it->second;
}

render::RenderResult CompareSession::render(render::Strategy s, int spp, std::uint64_t seed, const std::string& label,
                                            const render::FireflyLogOptions* log,
                                            const std::vector<int>& prefix_spp) {
  render::RenderOptions o = base;
  o.firefly_log = log;
  o.prefix_spp = prefix_spp;
  o.strategy = s;
  o.spp = spp;
  o.seed = seed;
  o.tables = &tables_for(s);
  const auto t0 = std::chrono::steady_clock::now();
  const bool bar = bar_ && !label.empty();
  if (bar)
    o.progress = [&label, t0](double f) {
      if (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(2)) return;
      std::fprintf(stderr, "\r  %s: %3d%%", label.c_str(), static_cast<int>(f * 100 + 0.5));
      std::fflush(stderr);
    };
  render::RenderResult r = render::render(scene, o);
  if (bar && std::chrono::steady_clock::now() - t0 >= std::chrono::seconds(2))
    std::fprintf(stderr, "\r%*s\r", static_cast<int>(label.size()) + 10, "");
  return r;
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
