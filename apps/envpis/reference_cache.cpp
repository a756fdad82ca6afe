// SPDX-License-Identifier: Apache-2.0
#ifdef ENVPIS_HAVE_RENDER
#include "reference_cache.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "envpis/image_file.h"
#include "render/scenes.h"

namespace envpis::app {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using namespace envpis::render;

std::string fnv1a_hex(const std::string& s) {
  std::uint64_t h = 1469598103934665603ULL;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string cache_base(const std::string& dir, const json& key) {
  return (fs::path(dir) / ("ref-" + fnv1a_hex(key.dump()))).string();
}

/// A file by its canonical path, size and modification time: an edited scene or map is another key.
json file_identity(const std::string& path) {
  std::error_code ec;
  const fs::path canon = fs::weakly_canonical(fs::path(path), ec);
  struct stat st {};
  json j;
  j["path"] = ec ? path : canon.string();
  if (::stat(path.c_str(), &st) == 0) {
    j["size"] = static_cast<std::uint64_t>(st.st_size);
    j["mtime"] = static_cast<std::int64_t>(st.st_mtime);
  }
  return j;
}

/// The options of `strategy` that change its image (each only for the strategies that use it).
void put_strategy_options(json& key, const Scene& scene, const RenderOptions& base, Strategy variant) {
  // A portal variant (render/strategy.h) renders with its base strategy's options, masked by the
  // scene's portals: those go in the key too (the scene file's mtime would catch an edit, a glTF's not).
  const Strategy strategy = base_strategy(variant);
  if (uses_portals(variant)) {
    json quads = json::array();
    for (int i = 0; i < scene.portals().size(); ++i)
      for (const Vec3& v : scene.portals().quad(i).v) quads.push_back({v.x, v.y, v.z});
    key["portals"] = quads;
  }
  if (strategy == Strategy::Oracle)  // "v2": the oracle of render/oracle.h (cell shares by quadrature)
    key["oracle"] = {base.oracle.resolution, base.oracle.directions, base.oracle.mis_compensation, "v2"};
  if (strategy != Strategy::Bsdf && strategy != Strategy::Oracle) key["top"] = base.light_table.top_resolution;
  if (strategy != Strategy::Bsdf) {
    key["peak_ratio"] = base.light_table.peak_ratio;
    key["fine"] = base.light_table.fine_resolution;
    // Sub-cells round the fine resolution to a multiple of T S (old keys stay valid without them).
    if (base.light_table.subdivision > 1) key["subcells"] = base.light_table.subdivision;
    const FineTexels texels = resolve_fine_texels(base.light_table.fine_texels, scene.environment());
    if (strategy != Strategy::Oracle && texels != FineTexels::EqualArea) key["fine_texels"] = to_string(texels);
  }
  if ((strategy == Strategy::Product || strategy == Strategy::Oracle) && !scene.proxy_closed_surfaces())
    key["closed_surfaces"] = false;
  if (strategy == Strategy::Product)
    key["product"] = {static_cast<int>(base.product.proxy.transform), base.product.proxy.min_alpha,
                      base.product.proxy.max_alpha, base.product.env_mix, base.product.env_floor};
  if (strategy == Strategy::Product && base.product.proxy.reflection_lobe != ReflectionLobe::Mirror)  // old keys
    key["proxy_lobe"] = to_string(base.product.proxy.reflection_lobe);
  if (strategy == Strategy::Product && base.product.refine) key["refine_cells"] = base.product.refine_cells;
  if (strategy == Strategy::Product && base.product.cell_estimate != CellEstimate::Cone)  // old keys: cone
    key["cell_estimate"] = to_string(base.product.cell_estimate);
  if (strategy == Strategy::Product && base.product_cache.entries > 0)
    key["product_cache_resolution"] = base.product_cache.resolution;
  // Old keys: product-portal had no cache (and product's key has no step).
  if (variant == Strategy::ProductPortal && base.product_cache.entries > 0)
    key["product_cache_step"] = base.product_cache_step;
  if (strategy == Strategy::Product && base.product_depth > 0) key["product_depth"] = base.product_depth;
  if (strategy == Strategy::Product && base.product_max_roughness < render::kInfinity)
    key["product_max_roughness"] = base.product_max_roughness;
  // What this variant's tables get (on-without-portals: on for product, off for product-portal).
  const render::ProductCompensation compensation = render::compensation_for(base.product_compensation, variant);
  if (compensation != render::ProductCompensation::Off) key["product_compensation"] = to_string(compensation);
}

}  // namespace

json regularization_json(const RegularizationOptions& r) {
  return {{"clamp_direct", r.clamp_direct},
          {"clamp_indirect", r.clamp_indirect},
          {"caustics", caustics_string(r)},
          {"filter_glossy", r.filter_glossy}};
}

json reference_key(const SceneOptionArgs& common, const Scene& scene, const RenderOptions& base, Strategy strategy,
                   int spp, std::uint64_t seed) {
  json key;
  key["version"] = kVersion;
  key["scene"] = is_builtin_scene(common.scene) ? json(common.scene) : file_identity(common.scene);
  key["environment"] = common.env.empty() ? json(scene.environment_description()) : file_identity(common.env);
  if (!common.env.empty()) key["environment_transform"] = {common.env_rotation, common.env_scale};
  // How the map is read changes the image whichever map it is (--env or the scene's), and references
  // cached before the lat-long orientation became an option have no such entry: they do not match.
  if (scene.has_environment())
    key["environment_lookup"] = {to_string(scene.environment().orientation()), to_string(scene.environment().filter())};
  key["width"] = base.width;
  key["height"] = base.height;
  key["integrator"] = to_string(base.integrator);
  key["max_depth"] = base.integrator == IntegratorKind::Path ? base.max_depth : 1;
  key["heuristic"] = to_string(base.heuristic);
  key["sampler"] = to_string(base.sampler);
  // Regularized references are other images; unregularized keys stay as they were.
  if (base.regularization.active()) key["regularization"] = regularization_json(base.regularization);
  key["strategy"] = to_string(strategy);
  key["spp"] = spp;
  key["seed"] = seed;
  put_strategy_options(key, scene, base, strategy);
  return key;
}

std::string default_cache_dir() {
  if (const char* e = std::getenv("ENVPIS_CACHE_DIR"); e && *e) return e;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return (fs::path(x) / "envpis" / "references").string();
  if (const char* h = std::getenv("HOME"); h && *h) return (fs::path(h) / ".cache" / "envpis" / "references").string();
  return "";
}

std::optional<Reference> load_cached_reference(const std::string& dir, const json& key) {
  const std::string base = cache_base(dir, key);
  std::ifstream in(base + ".json");
  if (!in) return std::nullopt;
  json side;
  try {
    in >> side;
  } catch (const std::exception&) {
    return std::nullopt;
  }
  if (!side.contains("key") || side["key"] != key) return std::nullopt;
  ImageFile img;
  try {
    img = read_image_file(base + ".exr");
  } catch (const Error&) {
    return std::nullopt;
  }
  const int W = key["width"].get<int>(), H = key["height"].get<int>();
  if (img.width != W || img.height != H || img.channels != 4) return std::nullopt;
  const std::vector<float>& px = img.pixels;
  Reference r;
  r.width = W;
  r.height = H;
  r.spp = key["spp"].get<int>();
  r.seed = key["seed"].get<std::uint64_t>();
  r.seconds = side.value("seconds", 0.0);
  r.cached = true;
  const std::size_t npix = static_cast<std::size_t>(W) * H;
  r.rgb.resize(npix * 3);
  r.variance.resize(npix);
  for (std::size_t p = 0; p < npix; ++p) {
    for (int c = 0; c < 3; ++c) r.rgb[p * 3 + c] = px[p * 4 + c];
    r.variance[p] = px[p * 4 + 3];
  }
  return r;
}

void store_cached_reference(const std::string& dir, const json& key, const Reference& r) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw Error("cannot create cache directory '" + dir + "': " + ec.message());
  const std::string base = cache_base(dir, key);
  const std::string tmp = base + ".tmp." + std::to_string(::getpid()) + ".exr";
  const std::size_t npix = static_cast<std::size_t>(r.width) * r.height;
  std::vector<float> px(npix * 4);
  for (std::size_t p = 0; p < npix; ++p) {
    for (int c = 0; c < 3; ++c) px[p * 4 + c] = r.rgb[p * 3 + c];
    px[p * 4 + 3] = r.variance[p];
  }
  write_image_file(tmp, r.width, r.height, 4, px.data(), {"R", "G", "B", "variance"});
  fs::rename(tmp, base + ".exr", ec);
  if (ec) throw Error("cannot write '" + base + ".exr': " + ec.message());
  json side;
  side["key"] = key;
  side["seconds"] = r.seconds;
  side["file"] = fs::path(base + ".exr").filename().string();
  std::ofstream(base + ".json") << side.dump(2) << "\n";
}

}  // namespace envpis::app
#endif  // ENVPIS_HAVE_RENDER
