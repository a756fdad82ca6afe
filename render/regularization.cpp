// SPDX-License-Identifier: Apache-2.0
#include "render/regularization.h"

#include <string>

namespace envpis::render {

namespace {
void check(float v, const char* what) {
  if (!(v >= 0) || !std::isfinite(v))
    throw Error(std::string(what) + " must be a finite number >= 0 (0: off), got " + std::to_string(v));
}
}  // namespace

void validate(const RegularizationOptions& o) {
  check(o.clamp_direct, "clamp direct");
  check(o.clamp_indirect, "clamp indirect");
  check(o.filter_glossy, "filter glossy");
}

void parse_caustics(const std::string& s, RegularizationOptions* o) {
  if (s == "reflective,refractive" || s == "refractive,reflective" || s == "all") {
    o->caustics_reflective = o->caustics_refractive = true;
  } else if (s == "reflective" || s == "refractive" || s == "none") {
    o->caustics_reflective = s == "reflective";
    o->caustics_refractive = s == "refractive";
  } else {
    throw Error("unknown caustics '" + s + "' (expected reflective,refractive, reflective, refractive or none)");
  }
}

std::string caustics_string(const RegularizationOptions& o) {
  if (o.caustics_reflective && o.caustics_refractive) return "reflective,refractive";
  if (o.caustics_reflective) return "reflective";
  if (o.caustics_refractive) return "refractive";
  return "none";
}

}  // namespace envpis::render
