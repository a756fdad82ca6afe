// SPDX-License-Identifier: Apache-2.0
// The reference of `envpis compare` and its cache: <cache>/ref-<hash>.exr (R, G, B, variance) and
// ref-<hash>.json, whose "key" holds everything that changes the reference image (the hash is of the
// key: a reference is reused only when every entry matches).
#pragma once
#ifdef ENVPIS_HAVE_RENDER

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "options.h"

namespace envpis::app {

struct Reference {
  int width = 0, height = 0, spp = 0;
  std::vector<float> rgb, variance;
  std::vector<int> object_id;  // from the first equal-spp render (the cache does not keep it)
  double seconds = 0;
  std::uint64_t seed = 0;
  render::Strategy strategy = render::Strategy::Mis;
  bool cached = false;
};

/// The key of a reference of `strategy` at `spp` and `seed`, rendered with `base` (at its final size)
/// in `scene` as the options in `common` loaded it.
nlohmann::json reference_key(const SceneOptionArgs& common, const render::Scene& scene,
                             const render::RenderOptions& base, render::Strategy strategy, int spp, std::uint64_t seed);

/// The path regularization as JSON (the cache key's and metrics.json's "regularization").
nlohmann::json regularization_json(const render::RegularizationOptions& r);

/// $ENVPIS_CACHE_DIR, else $XDG_CACHE_HOME/envpis/references, else ~/.cache/envpis/references; empty
/// when none is set.
std::string default_cache_dir();

/// The reference cached under `key` in `dir`; nullopt when there is none, or it is unreadable or does
/// not match the key.
std::optional<Reference> load_cached_reference(const std::string& dir, const nlohmann::json& key);

/// Caches `r` under `key` in `dir` (created); throws Error when it cannot be written.
void store_cached_reference(const std::string& dir, const nlohmann::json& key, const Reference& r);

}  // namespace envpis::app

#endif  // ENVPIS_HAVE_RENDER
