#include "envpis/product_sampler.h"

#include <algorithm>
#include <cmath>

#include "envpis/equal_area.h"
#include "kernels.h"
#include "proxy_internal.h"

namespace envpis {

ProductSampler::ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options)
    : table_(&table), options_(options), top_(table.top_resolution(), table.top_resolution()) {
  if (!(options.env_mix >= 0.0f && options.env_mix <= 1.0f)) throw Error("env_mix must be in [0, 1]");
  if (!(options.env_floor >= 0.0f && options.env_floor <= 1.0f)) throw Error("env_floor must be in [0, 1]");
  kernels_ = &detail::kernels_for(options.simd);
}

Simd ProductSampler::simd() const { return parse_simd(kernels_->name); }

bool ProductSampler::prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  valid_ = false;
  fallback_ = false;
  if (table_->empty() || !is_valid_direction(n) || !is_valid_direction(wo)) return false;
  const int cells = table_->cell_count();
  prepared_ = prepare_proxy(proxy, n, wo, options_.proxy);
  float m = options_.env_mix;
  float* prob = top_.values();
  float sum = 0;
  bool seen = false;
  if (prepared_.valid()) {
    kernels_->product_weights(detail::cell_arrays(*table_), detail::to_lobe_params(prepared_), prob);
    sum = top_.update();
    seen = top_.valid();
  }
  // Nothing the proxy can see: environment only. A total below FLT_MIN (denormal lobe weights) counts
  // as nothing too: its reciprocal would overflow to inf and so would every pdf (found by fuzzing).
  if (!seen) {
    fallback_ = true;
    m = 1.0f;
  }
  const float* e = table_->top_level().values();  // E[c]
  if (!fallback_ && options_.env_floor > 0.0f) {  // the environment floor (see product_sampler.h)
    const float a = 1.0f / sum, r = options_.env_floor;
    for (int c = 0; c < cells; ++c)
      if (prob[c] > 0.0f) prob[c] = std::max(prob[c] * a, r * e[c]);
    sum = top_.update();
  }
  if (m > 0.0f) {  // defensive mixture with the environment distribution
    const float a = m < 1.0f ? (1.0f - m) / sum : 0.0f;
    for (int c = 0; c < cells; ++c) {
      // Not a * prob[c] when a == 0: the fallback after an infinite product weight would give 0 * inf = NaN.
      prob[c] = (a > 0.0f ? a * prob[c] : 0.0f) + m * e[c];
    }
    top_.update();
  }
  // The masses stay unnormalized: the distribution scales u by the total and its pmf by the inverse.
  valid_ = top_.valid();
  return valid_;
}

DirectionSample ProductSampler::sample(Point2 u) const {
  return valid_ ? table_->sample(top_, u) : DirectionSample{};
}

float ProductSampler::pdf(Vec3 wi) const { return valid_ ? table_->pdf(top_, wi) : 0.0f; }

}  // namespace envpis
