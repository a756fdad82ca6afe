// SPDX-License-Identifier: Apache-2.0
#include "render/firefly_log.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <tuple>

#include "render/strategy.h"

namespace envpis::render {

const char* to_string(SampleTechnique t) { return t == SampleTechnique::Light ? "light" : "bsdf"; }

void validate(const FireflyLogOptions& o, int width, int height) {
  if (o.pixel_threshold.empty()) {
    if (!(o.threshold > 0) || !std::isfinite(o.threshold))
      throw Error("firefly log: the threshold must be a positive finite number");
    return;
  }
  if (o.pixel_threshold.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw Error("firefly log: " + std::to_string(o.pixel_threshold.size()) + " pixel thresholds for a " +
                std::to_string(width) + "x" + std::to_string(height) + " image");
  for (float t : o.pixel_threshold)
    if (!(t >= 0) || !std::isfinite(t)) throw Error("firefly log: pixel thresholds must be finite and >= 0");
}

void sort_records(std::vector<FireflyRecord>& records) {
  std::sort(records.begin(), records.end(), [](const FireflyRecord& a, const FireflyRecord& b) {
    return std::make_tuple(a.y, a.x, a.sample, a.depth, static_cast<int>(a.technique)) <
           std::make_tuple(b.y, b.x, b.sample, b.depth, static_cast<int>(b.technique));
  });
}

void write_firefly_csv(const std::string& path, const std::vector<FireflyRecord>& records) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw Error("cannot write '" + path + "': " + std::strerror(errno));
  std::fputs(
      "x,y,sample,depth,object,technique,contribution,threshold,light_pdf,bsdf_pdf,mis_weight,radiance,f_cos,beta,"
      "dir_x,dir_y,dir_z,cell,texel_x,texel_y,texel_importance,table_pdf,cell_env_probability,"
      "cell_probability,pdf_in_cell,proxy_cell,proxy_direction\n",
      f);
  for (const FireflyRecord& r : records)
    std::fprintf(f, "%d,%d,%d,%d,%d,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d,%d,%.9g,%.9g,%.9g,"
                    "%.9g,%.9g,%.9g,%.9g\n",
                 r.x, r.y, r.sample, r.depth, r.object, to_string(r.technique), r.contribution.average(), r.threshold,
                 r.light_pdf, r.bsdf_pdf, r.mis_weight, r.radiance.average(), r.f_cos.average(), r.beta.average(),
                 r.direction.x, r.direction.y, r.direction.z, r.cell, r.texel_x, r.texel_y, r.texel_importance,
                 r.table_pdf, r.cell_env_probability, r.cell_probability, r.pdf_in_cell, r.proxy_cell,
                 r.proxy_direction);
  const bool ok = !std::ferror(f);
  if (std::fclose(f) != 0 || !ok) throw Error("cannot write '" + path + "': " + std::strerror(errno));
}

FireflyRecorder::FireflyRecorder(const FireflyLogOptions& options, int width, const ImportanceTable* table,
                                 std::atomic<std::size_t>* kept)
    : options_(&options), width_(width), table_(table && !table->empty() ? table : nullptr), kept_(kept) {}

void FireflyRecorder::begin_sample(int x, int y, int sample) {
  x_ = x;
  y_ = y;
  sample_ = sample;
  threshold_ = options_->pixel_threshold.empty()
                   ? options_->threshold
                   : options_->pixel_threshold[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + x];
}

void FireflyRecorder::record(const FireflyEvent& e, const LightSampler& light) {
  if (kept_->fetch_add(1, std::memory_order_relaxed) >= options_->max_records) {
    ++dropped;
    return;
  }
  FireflyRecord r;
  r.x = x_;
  r.y = y_;
  r.sample = sample_;
  r.depth = e.depth;
  r.object = e.object;
  r.technique = e.technique;
  r.contribution = e.contribution;
  r.threshold = threshold_;
  r.light_pdf = e.light_pdf;
  r.bsdf_pdf = e.bsdf_pdf;
  r.mis_weight = e.mis_weight;
  r.radiance = e.radiance;
  r.f_cos = e.f_cos;
  r.beta = e.beta;
  r.direction = e.direction;
  add_table_view(light, r);
  records.push_back(r);
}

// The table's view of the direction, through the library's public API: the texel is found as the
// table's pdf_in_cell finds it (the equal-area point times N, clamped into the direction's top cell).
void FireflyRecorder::add_table_view(const LightSampler& light, FireflyRecord& r) const {
  if (!table_ || !is_valid_direction(r.direction)) return;
  const Point2 p = equal_area_sphere_to_square(r.direction);
  const int T = table_->top_resolution(), F = table_->cell_resolution(), N = table_->fine_resolution();
  r.cell = table_->cell_of(p);
  const int cx = r.cell % T, cy = r.cell / T;
  if (table_->fine_texels() == FineTexels::EqualArea) {  // a Map table's texels are the map's: not logged
    r.texel_x = std::clamp(static_cast<int>(p.x * float(N)), cx * F, cx * F + F - 1);
    r.texel_y = std::clamp(static_cast<int>(p.y * float(N)), cy * F, cy * F + F - 1);
    r.texel_importance = table_->importance(r.texel_x, r.texel_y);
  }
  r.table_pdf = table_->pdf(r.direction);
  r.cell_env_probability = table_->cell_probability(r.cell);
  r.pdf_in_cell = table_->pdf_in_cell(r.cell, p);
  // Every table-based strategy's density is (its cell probability) * pdf_in_cell * T^2 / (4 pi), so
  // the cell probability follows from the light pdf whatever weighted the cells (product, oracle). For
  // the refined product it is the effective one: the cell's probability times its sub-cell's
  // probability relative to the environment's share of it.
  const float per_cell = table_->solid_angle_pdf(1.0f, r.pdf_in_cell);
  r.cell_probability = per_cell > 0 ? r.light_pdf / per_cell : 0.0f;
  if (const ProductSampler* ps = light.product_sampler(); ps && ps->valid()) {
    const Cone& cone = table_->cell_cone(r.cell);
    r.proxy_cell = ps->prepared_proxy().eval_cone(cone.axis, cone.cos_half_angle, cone.sin_half_angle);
    r.proxy_direction = ps->prepared_proxy().eval(r.direction);
  }
}

}  // namespace envpis::render
