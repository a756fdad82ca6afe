// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "compare_steps.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "compare_json.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace envpis::render;

/// --firefly-log's per-pixel thresholds: a sample is logged when its contribution divided by spp exceeds
/// factor * sqrt(R^2 + kRelEpsilon), R the reference pixel's channel average. That is the tail metric's
/// scale (metrics.h): at factor 10, one logged sample alone takes its pixel about 10x off.
FireflyLogOptions relative_firefly_log(const Reference& ref, int spp, double factor) {
  FireflyLogOptions log;
  const std::size_t npix = static_cast<std::size_t>(ref.width) * ref.height;
  log.pixel_threshold.resize(npix);
  for (std::size_t p = 0; p < npix; ++p) {
    const double R = (double(ref.rgb[p * 3]) + ref.rgb[p * 3 + 1] + ref.rgb[p * 3 + 2]) / 3;
    log.pixel_threshold[p] = static_cast<float>(factor * spp * std::sqrt(R * R + kRelEpsilon));
  }
  return log;
}

Reference render_reference(CompareSession& session) {
  const CompareSettings& s = session.settings;
  session.progress.line("reference: %s @ %d spp (seed %llu) ...", to_string(s.ref_strategy), s.ref_spp,
                        static_cast<unsigned long long>(s.ref_seed));
  RenderResult rr = session.render(s.ref_strategy, s.ref_spp, s.ref_seed, "reference");
  Reference r;
  r.width = rr.width;
  r.height = rr.height;
  r.spp = rr.spp;
  r.rgb = std::move(rr.rgb);
  r.variance = std::move(rr.variance);
  r.seconds = rr.seconds;
  r.seed = s.ref_seed;
  session.progress.line("reference: %.2f s", r.seconds);
  if (rr.nonfinite_pixels > 0)
    std::fprintf(stderr, "envpis compare: warning: %zu non-finite reference pixels set to 0\n", rr.nonfinite_pixels);
  return r;
}

Measured measured_of(const RenderResult& r, Strategy s, int spp, const std::string& stem) {
  Measured m;
  m.strategy = s;
  m.spp = spp;
  m.stem = stem;
  m.seconds_runs.push_back(r.seconds);
  m.seconds = r.seconds;
  m.cpu_seconds = r.cpu_seconds;
  m.nan_count = r.nonfinite_pixels;
  return m;
}

void write_fireflies(CompareSession& session, Strategy s, const RenderResult& r) {
  const std::string csv =
      (fs::path(session.settings.firefly_log) / (std::string("fireflies-") + to_string(s) + ".csv")).string();
  write_firefly_csv(csv, r.fireflies);
  session.progress.line("firefly log: %-8s %zu samples over %g x the reference -> %s", to_string(s),
                        r.fireflies.size(), session.settings.firefly_factor, csv.c_str());
  if (r.fireflies_dropped > 0)
    std::fprintf(stderr, "envpis compare: warning: %zu more %s fireflies not kept (raise --firefly-factor)\n",
                 r.fireflies_dropped, to_string(s));
}

/// Timing repeats, interleaved across strategies (so a change in the machine's load hits all of them),
/// only for the fast renders: a timing under a couple of seconds is the noisy one. Images are
/// deterministic, so only the times are kept; each strategy's time is its minimum.
void repeat_timings(CompareSession& session, std::vector<Measured>& set) {
  const CompareSettings& s = session.settings;
  for (int i = 1; i < s.repeats; ++i)
    for (Measured& m : set) {
      if (m.seconds_runs.front() >= 2.0) continue;
      const RenderResult again = session.render(m.strategy, s.spp, s.seed, "");
      m.seconds_runs.push_back(again.seconds);
      m.seconds = std::min(m.seconds, again.seconds);
      m.cpu_seconds = std::min(m.cpu_seconds, again.cpu_seconds);
    }
  if (s.repeats > 1)
    for (const Measured& m : set)
      session.progress.line("equal spp: %-8s %.3f s (min of %zu runs)", to_string(m.strategy), m.seconds,
                            m.seconds_runs.size());
}

/// Seeds --seed + 1, ...: their metrics only (the images and the timing are the first seed's).
void measure_more_seeds(CompareSession& session, const Comparison& c, Measured& m, const std::string& what) {
  const CompareSettings& s = session.settings;
  for (int k = 1; k < s.nseeds; ++k) {
    const RenderResult r = session.render(m.strategy, m.spp, s.seed + k,
                                          what + ": " + to_string(m.strategy) + " seed " + std::to_string(s.seed + k));
    m.more_seeds.push_back(measure_image(r, c.reference, c.regions));
    m.more_seeds.back().per_pixel = std::vector<float>();  // only the first seed's error map is written
  }
  if (s.nseeds > 1)
    session.progress.line("%s: %-8s relMSE median %.4g over %d seeds", what.c_str(), to_string(m.strategy),
                          headline_relmse(m), s.nseeds);
}

}  // namespace

void obtain_reference(CompareSession& session, Comparison& c) {
  const CompareSettings& s = session.settings;
  const json key = reference_key(session.args.common, session.scene, session.base, s.ref_strategy, s.ref_spp, s.ref_seed);
  c.cache_dir = session.args.no_cache ? "" : (session.args.cache_dir.empty() ? default_cache_dir() : session.args.cache_dir);
  std::optional<Reference> cached;
  if (!c.cache_dir.empty()) cached = load_cached_reference(c.cache_dir, key);
  if (cached) {
    session.progress.line("reference: %s @ %d spp (seed %llu), cached in %s", to_string(s.ref_strategy), s.ref_spp,
                          static_cast<unsigned long long>(s.ref_seed), c.cache_dir.c_str());
    c.reference = std::move(*cached);
  } else {
    c.reference = render_reference(session);
    if (!c.cache_dir.empty()) {
      try {
        store_cached_reference(c.cache_dir, key, c.reference);
      } catch (const std::exception& e) {
        std::fprintf(stderr, "envpis compare: warning: reference not cached: %s\n", e.what());
      }
    }
  }
  c.reference.strategy = s.ref_strategy;
}

void measure_equal_spp(CompareSession& session, Comparison& c) {
  const CompareSettings& s = session.settings;
  // The firefly log, if asked for, sees the first-seed renders (a log does not change the image).
  std::optional<FireflyLogOptions> log;
  if (!s.firefly_log.empty()) log = relative_firefly_log(c.reference, s.spp, s.firefly_factor);
  MeasuredSet& set = c.equal_spp;
  // The convergence series' images are prefixes of these renders (render/render.h: bit-identical to
  // rendering them apart), so the series costs no render of its own.
  std::vector<int> prefixes;
  if (!session.args.no_convergence)
    for (int n = 1; n < s.spp; n *= 2) prefixes.push_back(n);
  for (Strategy st : s.strategies) {
    session.tables_for(st);  // built before the render: its time is not the sampling's
    RenderResult r = session.render(st, s.spp, s.seed, std::string("equal spp: ") + to_string(st), log ? &*log : nullptr,
                                    prefixes);
    if (log) write_fireflies(session, st, r);
    Measured m = measured_of(r, st, s.spp, std::string("spp-") + to_string(st));
    if (c.regions.empty()) {
      c.reference.object_id = r.object_id;
      c.regions = find_regions(session.scene, r.object_id, session.width, session.height);
    }
    session.progress.line("equal spp: %-8s %d spp  %.3f s", to_string(st), s.spp, m.seconds);
    set.images.push_back(std::move(r));
    set.measured.push_back(std::move(m));
  }
  repeat_timings(session, set.measured);
  for (std::size_t i = 0; i < set.measured.size(); ++i)
    set.measured[i].metrics = measure_image(set.images[i], c.reference, c.regions);
  for (Measured& m : set.measured) measure_more_seeds(session, c, m, "equal spp");
}

void measure_overhead(CompareSession& session, Comparison& c) {
  const Measured *p = c.equal_spp.find(Strategy::Product), *m = c.equal_spp.find(Strategy::Mis);
  if (!p || !m || !(m->seconds > 0)) return;
  c.overhead = {{"ratio", p->seconds / m->seconds},
                {"product_seconds", p->seconds},
                {"mis_seconds", m->seconds},
                {"ratio_cpu", m->cpu_seconds > 0 ? json(p->cpu_seconds / m->cpu_seconds) : json(nullptr)},
                {"product_cpu_seconds", p->cpu_seconds},
                {"mis_cpu_seconds", m->cpu_seconds},
                {"spp", session.settings.spp},
                {"threads", session.threads_used}};
  session.progress.line("overhead: time(product) / time(mis) = %.3f (CPU time: %.3f)", p->seconds / m->seconds,
                        m->cpu_seconds > 0 ? p->cpu_seconds / m->cpu_seconds : 0.0);
}

void measure_convergence(CompareSession& session, Comparison& c) {
  const int spp = session.settings.spp;
  for (std::size_t i = 0; i < c.equal_spp.measured.size(); ++i) {
    const Measured& e = c.equal_spp.measured[i];
    const RenderResult& full = c.equal_spp.images[i];
    json series = json::array();
    for (std::size_t k = 0; k < full.prefixes.size(); ++k) {
      // The equal-spp render's first spp samples per pixel: the same image as a render at that spp
      // with the same seed. It has no time of its own ("seconds": null).
      const RenderResult r = full.prefix(k);
      const ImageMetrics mm = measure_image(r, c.reference, c.regions);
      series.push_back({{"spp", r.spp}, {"seconds", nullptr}, {"relmse", mm.image.relmse},
                        {"regions", regions_json(c.regions, mm, false)}});
    }
    series.push_back({{"spp", spp},
                      {"seconds", e.seconds},
                      {"relmse", e.metrics.image.relmse},
                      {"regions", regions_json(c.regions, e.metrics, false)}});
    c.convergence[to_string(e.strategy)] = series;
    session.progress.line("convergence: %-8s %zu points (prefixes of the equal-spp render)", to_string(e.strategy),
                          full.prefixes.size() + 1);
  }
}

void measure_equal_time(CompareSession& session, Comparison& c) {
  const CompareSettings& s = session.settings;
  if (s.equal_time_auto) {
    const Measured* m = c.equal_spp.find(Strategy::Mis);
    c.budget = (m ? m : &c.equal_spp.measured.front())->seconds;  // mis's time, or the first strategy's without mis
  } else {
    c.budget = s.equal_time_seconds;
  }
  for (const Measured& e : c.equal_spp.measured) {
    const double per_spp = std::max(e.seconds, 1e-9) / e.spp;
    const int n = static_cast<int>(std::clamp(std::floor(c.budget / per_spp + 0.5), 1.0, double(kMaxSpp)));
    RenderResult r = session.render(e.strategy, n, s.seed, std::string("equal time: ") + to_string(e.strategy));
    Measured m = measured_of(r, e.strategy, n, std::string("time-") + to_string(e.strategy));
    m.metrics = measure_image(r, c.reference, c.regions);
    session.progress.line("equal time: %-8s %d spp  %.3f s (budget %.3f s)", to_string(e.strategy), n, r.seconds,
                          c.budget);
    measure_more_seeds(session, c, m, "equal time");
    c.equal_time.images.push_back(std::move(r));
    c.equal_time.measured.push_back(std::move(m));
  }
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
