// SPDX-License-Identifier: Apache-2.0
// Lobe::eval_pdf and Material::eval_pdf give exactly (bit for bit) what eval and pdf give, for every
// lobe, over random directions on the whole sphere (below the horizon, transmission, grazing and
// degenerate ones included), at roughness 0 (clamped), 1 and between, and for lobes a LobeFilter
// changed: the oracle and the analyzer use the fused form and must stay the same as before it. The
// material's form with its lobe choice computed once (the analyzer's) gives the same bits.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "render/material.h"

namespace envpis::render {
namespace {

struct Named {
  std::string name;
  std::shared_ptr<const Lobe> lobe;
};

std::vector<Named> lobes() {
  std::vector<Named> v;
  v.push_back({"lambert", make_lambert({0.8f, 0.5f, 0.2f})});
  v.push_back({"translucent", make_translucent({0.3f, 0.6f, 0.9f})});
  for (float a : {0.0f, 0.02f, 0.3f, 1.0f}) {
    const std::string s = " a=" + std::to_string(a);
    v.push_back({"conductor" + s, make_conductor(a, {0.143f, 0.374f, 1.442f}, {3.983f, 2.385f, 1.603f})});
    v.push_back({"schlick" + s, make_conductor_reflectance(a, {0.9f, 0.6f, 0.3f})});
    v.push_back({"dielectric 1.5" + s, make_dielectric(a, 1.5f)});
    v.push_back({"dielectric 0.8 tinted" + s, make_dielectric(a, 0.8f, {0.9f, 0.7f, 0.5f})});
    v.push_back({"dielectric dark" + s, make_dielectric(a, 1.5f, {0.1f, 0.2f, 0.05f})});
    v.push_back({"coated" + s, make_coated_diffuse({0.7f, 0.3f, 0.1f}, a, 1.5f)});
  }
  v.push_back({"dielectric index-matched", make_dielectric(0.3f, 1.001f)});
  // The filtered variants: a part removed, or the roughness raised.
  const std::vector<Named> base = v;
  for (const Named& n : base) {
    for (const LobeFilter& f : {LobeFilter{0.0f, false, true}, LobeFilter{0.0f, true, false}, LobeFilter{0.5f, true, true}}) {
      std::shared_ptr<const Lobe> changed;
      if (n.lobe->filtered(f, &changed) && changed) v.push_back({n.name + " filtered", changed});
    }
  }
  return v;
}

Vec3 random_direction(std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (;;) {
    const Vec3 d{u(rng), u(rng), u(rng)};
    const float l2 = dot(d, d);
    if (l2 > 1e-4f && l2 <= 1.0f) return d * (1.0f / std::sqrt(l2));
  }
}

// Random pairs, plus wi near the mirror and the refraction of wo (the lobes' peaks), grazing and
// degenerate directions.
std::vector<std::pair<Vec3, Vec3>> pairs() {
  std::mt19937 rng(7);
  std::vector<std::pair<Vec3, Vec3>> p;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 wo = random_direction(rng), wi = random_direction(rng);
    p.push_back({wo, wi});
    p.push_back({wo, normalize(Vec3(-wo.x, -wo.y, wo.z) + wi * 0.01f)});  // near the mirror direction
    p.push_back({wo, normalize(-wo + wi * 0.05f)});                       // near straight through
  }
  p.push_back({{0.6f, 0.0f, 0.8f}, {0.6f, 0.0f, 0.0f}});  // wi on the tangent plane
  p.push_back({{0.0f, 0.6f, 0.0f}, {0.0f, 0.0f, 1.0f}});  // wo on the tangent plane
  p.push_back({{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 1.0f}});  // normal incidence, the mirror itself
  p.push_back({{0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, -1.0f}});
  return p;
}

void expect_same(Rgb a, Rgb b, const std::string& what) {
  EXPECT_EQ(a.r, b.r) << what;
  EXPECT_EQ(a.g, b.g) << what;
  EXPECT_EQ(a.b, b.b) << what;
}

TEST(BsdfEvalPdf, EveryLobeEqualsEvalAndPdf) {
  const auto ps = pairs();
  for (const Named& n : lobes()) {
    int mismatches = 0;
    for (const auto& [wo, wi] : ps) {
      float p = -1;
      const Rgb f = n.lobe->eval_pdf(wo, wi, &p);
      const Rgb fe = n.lobe->eval(wo, wi);
      const float pe = n.lobe->pdf(wo, wi);
      if (f.r != fe.r || f.g != fe.g || f.b != fe.b || !(p == pe)) ++mismatches;
    }
    EXPECT_EQ(mismatches, 0) << n.name;
  }
}

TEST(BsdfEvalPdf, MaterialEqualsEvalAndPdf) {
  std::vector<Material> materials(3);
  materials[0].add(make_conductor_reflectance(0.02f, {0.9f, 0.6f, 0.3f}));
  materials[1].add(make_lambert({0.2f, 0.6f, 0.1f}), 0.4f);
  materials[1].add(make_coated_diffuse({0.2f, 0.6f, 0.1f}, 0.3f, 1.4f), Rgb{0.6f, 0.2f, 0.9f});
  materials[1].add(make_dielectric(0.2f, 1.5f), 0.5f);
  materials[2].add(make_lambert({0.0f, 0.0f, 0.0f}));  // albedo 0: never sampled, pdf 0
  const auto ps = pairs();
  for (std::size_t m = 0; m < materials.size(); ++m)
    for (const auto& [wo, wi] : ps) {
      float p = -1;
      const Rgb f = materials[m].eval_pdf(wo, wi, &p);
      expect_same(f, materials[m].eval(wo, wi), "material " + std::to_string(m));
      EXPECT_EQ(p, materials[m].pdf(wo, wi)) << "material " << m;
      // ...also with the lobe choice at wo computed once (Material::choice), and with another
      // material's choice or one at another wo, which must not be taken for this one's
      float q = -1;
      expect_same(materials[m].eval_pdf(wo, wi, &q, materials[m].choice(wo)), f, "material " + std::to_string(m));
      EXPECT_EQ(q, p) << "material " << m << " with its choice";
      q = -1;
      expect_same(materials[m].eval_pdf(wo, wi, &q, materials[(m + 1) % materials.size()].choice(wo)), f,
                  "material " + std::to_string(m));
      EXPECT_EQ(q, p) << "material " << m << " with another's choice";
      q = -1;
      expect_same(materials[m].eval_pdf(wo, wi, &q, materials[m].choice(wi)), f, "material " + std::to_string(m));
      EXPECT_EQ(q, p) << "material " << m << " with a choice at another wo";
    }
}

}  // namespace
}  // namespace envpis::render
