#include "envpis/product_sampler.h"

#include <cmath>

#include "distribution_util.h"
#include "envpis/equal_area.h"
#include "kernels.h"
#include "proxy_internal.h"

namespace envpis {

ProductSampler::ProductSampler(const ImportanceTable& table, const ProductSamplerOptions& options)
    : table_(&table), options_(options) {
  if (!(options.env_mix >= 0.0f && options.env_mix <= 1.0f)) throw Error("env_mix must be in [0, 1]");
  kernels_ = options.simd ? &detail::kernels_best() : &detail::kernels_scalar();
  prob_.assign(table.padded_cell_count(), 0.0f);
  cdf_.assign(table.cell_count(), 0.0f);
}

bool ProductSampler::prepare(Vec3 n, Vec3 wo, const BsdfProxy& proxy) {
  valid_ = false;
  fallback_ = false;
  if (table_->empty() || !is_valid_direction(n) || !is_valid_direction(wo)) return false;
  const int cells = table_->cell_count();
  prepared_ = prepare_proxy(proxy, n, wo, options_.proxy);
  float m = options_.env_mix;
  double sum = 0;
  if (prepared_.valid()) {
    const detail::CellArrays arrays{table_->soa_axis_x(), table_->soa_axis_y(), table_->soa_axis_z(),
                                    table_->soa_cos(),    table_->soa_sin(),    table_->soa_prob(),
                                    table_->padded_cell_count()};
    static_cast<const detail::Kernels*>(kernels_)->product_weights(arrays, detail::to_lobe_params(prepared_),
                                                                   prob_.data());
    for (int c = 0; c < cells; ++c) sum += prob_[c];
  }
  if (!(sum > 0) || !std::isfinite(sum)) {
    fallback_ = true;
    m = 1.0f;
    sum = 1.0;
  }
  const float scale = static_cast<float>((1.0 - m) / sum);
  const float* e = table_->soa_prob();
  double run = 0;
  for (int c = 0; c < cells; ++c) {
    const float p = (m < 1.0f ? prob_[c] * scale : 0.0f) + (m > 0.0f ? m * e[c] : 0.0f);
    prob_[c] = p;
    cdf_[c] = static_cast<float>(run += p);
  }
  const float last = cdf_[cells - 1];
  if (!(last > 0)) return false;
  const float inv = 1.0f / last;
  for (int c = 0; c < cells; ++c) {
    cdf_[c] *= inv;
    prob_[c] *= inv;
  }
  const float end = cdf_[cells - 1];  // 1 up to rounding: make the tail exactly 1
  for (int c = cells - 1; c >= 0 && cdf_[c] >= end; --c) cdf_[c] = 1.0f;
  valid_ = true;
  return true;
}

DirectionSample ProductSampler::sample(Point2 u) const {
  DirectionSample out;
  if (!valid_) return out;
  const int T = table_->top_resolution();
  const detail::Flat2DSample s = detail::sample_flat2d(cdf_.data(), T, T, u);
  const int c = s.y * T + s.x;
  const Point2 p = table_->sample_in_cell(c, {s.ox, s.oy}, nullptr);
  out.direction = equal_area_square_to_sphere(p);
  out.cell = c;
  out.pdf = pdf(out.direction);
  return out;
}

float ProductSampler::pdf(Vec3 wi) const {
  if (!valid_ || !is_valid_direction(wi)) return 0.0f;
  const Point2 p = equal_area_sphere_to_square(wi);
  const int c = table_->cell_of(p);
  const float T = static_cast<float>(table_->top_resolution());
  return prob_[c] * table_->pdf_in_cell(c, p) * T * T * kInv4Pi;
}

}  // namespace envpis
