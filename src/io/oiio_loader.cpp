// SPDX-License-Identifier: Apache-2.0
#include "oiio_loader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <vector>

#include "envpis/common.h"

namespace envpis::detail {

namespace {

std::vector<std::string> candidates() {
  if (const char* env = std::getenv("ENVPIS_OIIO_MODULE"); env && *env) return {env};  // the user's choice only
  std::vector<std::string> paths;
#ifdef ENVPIS_OIIO_MODULE_BUILT
  paths.emplace_back(ENVPIS_OIIO_MODULE_BUILT);
#endif
#ifdef ENVPIS_OIIO_MODULE_INSTALLED
  paths.emplace_back(ENVPIS_OIIO_MODULE_INSTALLED);
#endif
  return paths;
}

struct Loaded {
  const EnvpisOiioApi* api = nullptr;
  std::string error;
};

#ifdef ENVPIS_OIIO_LINKED
extern "C" const EnvpisOiioApi* envpis_oiio_module();
Loaded load() { return {envpis_oiio_module(), {}}; }  // linked in (ENVPIS_OIIO_AS_MODULE=OFF)
#else
Loaded load() {
  const std::vector<std::string> paths = candidates();
  if (paths.empty()) return {nullptr, "this build of envpis has no OpenImageIO module; set ENVPIS_OIIO_MODULE"};
  std::string tried;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
      tried += (tried.empty() ? "" : ", ") + path + " (not found)";
      continue;
    }
    // Never closed: OpenImageIO keeps global state (its plugin registry) for the process's life.
    void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = dlerror();
      return {nullptr, "cannot load " + path + ": " + (why ? why : "unknown reason")};
    }
    auto entry = reinterpret_cast<EnvpisOiioEntry>(dlsym(handle, ENVPIS_OIIO_MODULE_ENTRY));
    const EnvpisOiioApi* api = entry ? entry() : nullptr;
    if (!api || api->abi != ENVPIS_OIIO_MODULE_ABI)
      return {nullptr, path + " is not an OpenImageIO module of this envpis version"};
    return {api, {}};
  }
  return {nullptr, "its OpenImageIO module was not found: tried " + tried + "; set ENVPIS_OIIO_MODULE"};
}
#endif

const Loaded& loaded() {
  static const Loaded once = load();  // thread-safe initialization
  return once;
}

}  // namespace

const EnvpisOiioApi& oiio_module() {
  const Loaded& l = loaded();
  if (!l.api) throw Error("reading or writing this format needs OpenImageIO, but " + l.error);
  return *l.api;
}

std::string oiio_module_path() {
  const std::vector<std::string> paths = candidates();
  return paths.empty() ? std::string() : paths.front();
}

}  // namespace envpis::detail
