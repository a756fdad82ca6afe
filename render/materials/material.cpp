// SPDX-License-Identifier: Apache-2.0
// Material: a weighted sum of lobes.
//   eval(wo, wi) = sum_k w_k f_k(wo, wi)
//   sample: lobe k is chosen with probability P_k = w_k albedo_k(wo) / sum_j w_j albedo_j(wo) (using uc,
//           which is then rescaled and handed to the lobe), the lobe samples wi, and the sample
//           reports the whole material's f and the mixture pdf sum_k P_k pdf_k(wo, wi), i.e. one-sample
//           MIS over the lobes with the balance heuristic. pdf(wo, wi) returns the same mixture.
// Lobes with zero albedo for wo are never chosen; if every lobe has zero albedo the material is
// black for wo and sample() returns nullopt.
// fill_proxy: every lobe adds itself; for a closed surface only the lobes on the outside are kept
// (render/material.h, set_closed_surface).
#include <array>

#include "render/materials/lobe_common.h"

namespace envpis::render {

namespace {

/// Selection weights w_k albedo_k(wo), on the stack for the usual few lobes.
class Selection {
 public:
  template <class Entries>
  Selection(const Entries& lobes, Vec3 wo) : n_(lobes.size()) {
    if (n_ > kInline) heap_.resize(n_);
    float* p = data();
    for (std::size_t k = 0; k < n_; ++k) {
      const float a = lobes[k].weight_average * lobes[k].lobe->albedo(wo);
      p[k] = std::isfinite(a) && a > 0 ? a : 0.0f;
      total_ += p[k];
    }
  }
  float total() const { return total_; }
  /// Probability of lobe k.
  float probability(std::size_t k) const { return data()[k] / total_; }
  /// Chooses a lobe with uc and rescales uc to [0, 1) within the choice.
  std::size_t choose(float& uc) const {
    const float* p = data();
    float target = uc * total_, acc = 0;
    std::size_t last = 0;
    for (std::size_t k = 0; k < n_; ++k) {
      if (p[k] <= 0) continue;
      last = k;
      if (target < acc + p[k]) {
        uc = std::min((target - acc) / p[k], 0x1.fffffep-1f);
        return k;
      }
      acc += p[k];
    }
    uc = std::min(std::max(uc, 0.0f), 0x1.fffffep-1f);  // rounding at the top end: the last positive lobe
    return last;
  }

 private:
  static constexpr std::size_t kInline = 8;
  const float* data() const { return n_ > kInline ? heap_.data() : inline_.data(); }
  float* data() { return n_ > kInline ? heap_.data() : inline_.data(); }
  std::size_t n_;
  float total_ = 0;
  std::array<float, kInline> inline_{};
  std::vector<float> heap_;
};

}  // namespace

void Material::add(std::shared_ptr<const Lobe> lobe, float weight) { add(std::move(lobe), Rgb{weight, weight, weight}); }

void Material::add(std::shared_ptr<const Lobe> lobe, Rgb weight) {
  const float avg = weight.average();
  if (!lobe || !std::isfinite(avg) || !(avg > 0)) return;  // contributes nothing
  lobes_.push_back({std::move(lobe), lobe::sanitize_color(weight), avg});
}

Rgb Material::eval(Vec3 wo, Vec3 wi) const {
  Rgb f;
  for (const Entry& e : lobes_) f = f + e.lobe->eval(wo, wi) * e.weight;
  return f;
}

float Material::pdf(Vec3 wo, Vec3 wi) const {
  if (lobes_.empty() || !microfacet::usable(wo) || !microfacet::usable(wi)) return 0.0f;
  const Selection sel(lobes_, wo);
  if (!(sel.total() > 0)) return 0.0f;
  float p = 0;
  for (std::size_t k = 0; k < lobes_.size(); ++k) {
    const float pk = sel.probability(k);
    if (pk > 0) p += pk * lobes_[k].lobe->pdf(wo, wi);
  }
  return p;
}

// The lobes' sum and mixture pdf, lobe k chosen with probability(k).
template <class Probability>
Rgb Material::eval_pdf_lobes(Vec3 wo, Vec3 wi, float* pdf, Probability probability) const {
  Rgb f;
  for (std::size_t k = 0; k < lobes_.size(); ++k) {
    float pl;
    f = f + lobes_[k].lobe->eval_pdf(wo, wi, &pl) * lobes_[k].weight;
    const float pk = probability(k);
    if (pk > 0) *pdf += pk * pl;
  }
  return f;
}

Rgb Material::eval_pdf(Vec3 wo, Vec3 wi, float* pdf) const {
  *pdf = 0;
  if (lobes_.empty() || !microfacet::usable(wo) || !microfacet::usable(wi)) return eval(wo, wi);
  const Selection sel(lobes_, wo);
  const bool chosen = sel.total() > 0;  // else no lobe is ever sampled: pdf 0
  return eval_pdf_lobes(wo, wi, pdf, [&](std::size_t k) { return chosen ? sel.probability(k) : 0.0f; });
}

Material::Choice Material::choice(Vec3 wo) const {
  Choice c;
  c.material_ = this;
  c.wo_ = wo;
  c.usable_ = !lobes_.empty() && microfacet::usable(wo);
  if (!c.usable_) return c;
  const Selection sel(lobes_, wo);
  const bool chosen = sel.total() > 0;
  for (std::size_t k = 0; k < lobes_.size(); ++k) c.probability_.push_back(chosen ? sel.probability(k) : 0.0f);
  return c;
}

Rgb Material::eval_pdf(Vec3 wo, Vec3 wi, float* pdf, const Choice& choice) const {
  const bool mine = choice.material_ == this && choice.wo_.x == wo.x && choice.wo_.y == wo.y && choice.wo_.z == wo.z;
  if (!mine || !choice.usable_ || choice.probability_.size() != lobes_.size()) return eval_pdf(wo, wi, pdf);
  *pdf = 0;
  if (!microfacet::usable(wi)) return eval(wo, wi);
  return eval_pdf_lobes(wo, wi, pdf, [&](std::size_t k) { return choice.probability_[k]; });
}

std::optional<BsdfSample> Material::sample(Vec3 wo, Point2 u, float uc) const {
  if (lobes_.empty() || !microfacet::usable(wo)) return std::nullopt;
  const Selection sel(lobes_, wo);
  if (!(sel.total() > 0)) return std::nullopt;
  const std::size_t k = sel.choose(uc);
  const auto s = lobes_[k].lobe->sample(wo, u, uc);
  if (!s) return std::nullopt;
  if (lobes_.size() == 1) {
    BsdfSample r = *s;  // the lobe's own pdf is the mixture's
    r.f = r.f * lobes_[0].weight;
    r.weight = r.weight * lobes_[0].weight;
    return r;
  }
  Rgb f;
  float p = 0;
  for (std::size_t j = 0; j < lobes_.size(); ++j) {
    f = f + lobes_[j].lobe->eval(wo, s->wi) * lobes_[j].weight;
    const float pj = sel.probability(j);
    if (pj > 0) p += pj * (j == k ? s->pdf : lobes_[j].lobe->pdf(wo, s->wi));
  }
  auto r = lobe::make_sample(wo, s->wi, f, p);
  if (r) r->diffuse = s->diffuse;
  return r;
}

void Material::filter_into(const LobeFilter& filter, Material* out) const {
  out->clear_lobes();
  out->closed_surface_ = closed_surface_;
  for (const Entry& e : lobes_) {
    std::shared_ptr<const Lobe> changed;
    if (!e.lobe->filtered(filter, &changed)) continue;
    out->lobes_.push_back({changed ? std::move(changed) : e.lobe, e.weight, e.weight_average});
  }
}

float Material::albedo(Vec3 wo) const {
  if (!microfacet::usable(wo)) return 0.0f;
  float a = 0;
  for (const Entry& e : lobes_) a += e.weight_average * e.lobe->albedo(wo);
  return a;
}

void Material::fill_proxy(BsdfProxy& proxy, Vec3 wo) const {
  if (!microfacet::usable(wo)) return;
  if (!closed_surface_) {
    for (const Entry& e : lobes_) e.lobe->add_to_proxy(proxy, wo, e.weight_average);
    return;
  }
  // Closed surface: keep only the lobes on the outside, where a light sample can reach the
  // environment. Seen from outside these are the ones on wo's side, seen from inside the ones across.
  BsdfProxy all;
  for (const Entry& e : lobes_) e.lobe->add_to_proxy(all, wo, e.weight_average);
  if (wo.z > 0) {
    proxy.add_diffuse(all.diffuse);
    proxy.add_reflection(all.reflection, all.alpha_reflection);
  } else {
    proxy.add_translucent(all.translucent);
    proxy.add_refraction(all.refraction, all.alpha_refraction, all.ior);
  }
}

}  // namespace envpis::render
