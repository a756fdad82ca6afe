#include "envpis/product_sampler.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "distribution_util.h"
#include "envpis/equal_area.h"
#include "kernels.h"
#include "proxy_internal.h"

namespace envpis {

ProductSampler::ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options)
    : table_(&table), options_(options) {
  if (!(options.env_mix >= 0.0f && options.env_mix <= 1.0f)) throw Error("env_mix must be in [0, 1]");
  if (!(options.env_floor >= 0.0f && options.env_floor <= 1.0f)) throw Error("env_floor must be in [0, 1]");
  kernels_ = options.simd ? &detail::kernels_best() : &detail::kernels_scalar();
  prob_.assign(table.padded_cell_count(), 0.0f);
  row_sum_.assign(table.top_resolution(), 0.0f);
  row_cdf_.assign(table.top_resolution(), 0.0f);
}

bool ProductSampler::prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  valid_ = false;
  fallback_ = false;
  if (table_->empty() || !is_valid_direction(n) || !is_valid_direction(wo)) return false;
  const int cells = table_->cell_count();
  prepared_ = prepare_proxy(proxy, n, wo, options_.proxy);
  float m = options_.env_mix;
  float* prob = prob_.data();
  float sum = 0;
  if (prepared_.valid()) {
    const detail::CellArrays arrays{table_->soa_axis_x(), table_->soa_axis_y(), table_->soa_axis_z(),
                                    table_->soa_cos(),    table_->soa_sin(),    table_->soa_prob(),
                                    table_->padded_cell_count()};
    static_cast<const detail::Kernels*>(kernels_)->product_weights(arrays, detail::to_lobe_params(prepared_), prob);
    sum = row_sums();
  }
  // Nothing the proxy can see: environment only. A sum below FLT_MIN (denormal lobe weights) counts as
  // nothing too: its reciprocal would overflow to inf and so would every pdf (found by fuzzing).
  if (!(sum >= std::numeric_limits<float>::min()) || !std::isfinite(sum)) {
    fallback_ = true;
    m = 1.0f;
  }
  if (!fallback_ && options_.env_floor > 0.0f) {  // the environment floor (see product_sampler.h)
    const float* e = table_->soa_prob();
    const float a = 1.0f / sum, r = options_.env_floor;
    for (int c = 0; c < cells; ++c)
      if (prob[c] > 0.0f) prob[c] = std::max(prob[c] * a, r * e[c]);
    sum = row_sums();
  }
  if (m > 0.0f) {  // defensive mixture with the environment distribution
    const float* e = table_->soa_prob();
    const float a = m < 1.0f ? (1.0f - m) / sum : 0.0f;
    for (int c = 0; c < cells; ++c) {
      // Not a * prob[c] when a == 0: the fallback after an infinite product weight would give 0 * inf = NaN.
      prob[c] = (a > 0.0f ? a * prob[c] : 0.0f) + m * e[c];
    }
    sum = row_sums();
  }
  if (!(sum > 0) || !std::isfinite(sum)) return false;
  // prob_ and the row sums stay unnormalized: sampling scales u by the total, pdf() multiplies by its
  // inverse.
  total_ = sum;
  inv_total_ = 1.0f / sum;
  valid_ = true;
  return true;
}

float ProductSampler::row_sums() {
  // Only the T row totals and their running sums: a sample finds its row among them and then scans
  // the T cells of that row (sample_row_scan), so prepare() writes no per-cell running sums.
  const int T = table_->top_resolution();
  return detail::store_row_sums(prob_.data(), T, T, row_sum_.data(), row_cdf_.data());
}

DirectionSample ProductSampler::sample(Point2 u) const {
  DirectionSample out;
  if (!valid_) return out;
  const int T = table_->top_resolution();
  const detail::Flat2DSample s =
      detail::sample_row_scan(row_cdf_.data(), row_sum_.data(), prob_.data(), T, T, u, total_);
  const int c = s.y * T + s.x;
  float pc;
  bool interior;
  const Point2 p = table_->sample_in_cell(c, {s.ox, s.oy}, &pc, &interior);
  out.direction = equal_area_square_to_sphere(p);
  out.cell = c;
  // Far from texel edges the sampled texel is the one pdf() finds: its density directly (same
  // arithmetic as pdf()); near an edge, pdf() of the direction, so the two always agree.
  out.pdf = interior ? prob_[c] * inv_total_ * pc * float(T) * float(T) * kInv4Pi : pdf(out.direction);
  return out;
}

float ProductSampler::pdf(Vec3 wi) const {
  if (!valid_ || !is_valid_direction(wi)) return 0.0f;
  const Point2 p = equal_area_sphere_to_square(wi);
  const int c = table_->cell_of(p);
  const float T = static_cast<float>(table_->top_resolution());
  return prob_[c] * inv_total_ * table_->pdf_in_cell(c, p) * T * T * kInv4Pi;  // as in sample()
}

}  // namespace envpis
