#include "render/sampler.h"

namespace envpis::render {

SamplerKind parse_sampler(const std::string& s) {
  if (s == "sobol") return SamplerKind::Sobol;
  if (s == "independent") return SamplerKind::Independent;
  throw Error("unknown sampler '" + s + "' (expected sobol or independent)");
}

const char* to_string(SamplerKind k) { return k == SamplerKind::Sobol ? "sobol" : "independent"; }

}  // namespace envpis::render
