// SPDX-License-Identifier: Apache-2.0
#include "render/integrator.h"

#include <algorithm>
#include <cmath>

namespace envpis::render {

IntegratorKind parse_integrator(const std::string& s) {
  if (s == "direct") return IntegratorKind::Direct;
  if (s == "path") return IntegratorKind::Path;
  throw Error("unknown integrator '" + s + "' (expected direct or path)");
}

const char* to_string(IntegratorKind k) { return k == IntegratorKind::Direct ? "direct" : "path"; }

Integrator::Integrator(const Scene& scene, const IntegratorOptions& options)
    : scene_(scene), env_(scene.environment()), options_(options) {
  if (options_.max_depth < 1) throw Error("max depth must be at least 1");
  if (options_.rr_depth < 1) throw Error("Russian roulette depth must be at least 1");
}

float Integrator::mis_weight(float pdf_f, float pdf_g) const {
  return options_.heuristic == Heuristic::Power ? power_heuristic(1, pdf_f, 1, pdf_g)
                                                : balance_heuristic(1, pdf_f, 1, pdf_g);
}

ShadingNormals shading_normals(const SurfaceHit& hit, bool transmissive, Vec3 wo) {
  ShadingNormals sn{hit.ng, hit.ns};
  if (!transmissive && dot(wo, sn.ng) < 0) {  // opaque materials are two-sided
    sn.ng = -sn.ng;
    sn.ns = -sn.ns;
  }
  if ((dot(wo, sn.ns) > 0) != (dot(wo, sn.ng) > 0)) sn.ns = sn.ng;  // shading normal facing away from the viewer
  return sn;
}

HitMaterial resolve_material(const Scene& scene, SurfaceHit* hit, Material* scratch) {
  const SceneMaterial& mat = scene.material(hit->material);
  HitMaterial out;
  out.bsdf = &mat.bsdf;
  if (!mat.textured()) {
    out.emission = mat.emission;
    return out;
  }
  mat.pbr->assemble(hit->uv, scratch);
  scratch->set_closed_surface(mat.bsdf.closed_surface());
  out.bsdf = scratch;
  out.emission = mat.pbr->emission(hit->uv);
  if (mat.pbr->has_normal_map()) {
    const Vec3 n = mat.pbr->normal_mapped(hit->uv, hit->ns, hit->dpdu, hit->bitangent_sign);
    if (dot(n, hit->ng) > 0) {
      hit->ns = n;
      if (scene.widen_bent_normals()) out.cos_bent = dot(n, hit->ng);
    }
  }
  return out;
}

Rgb Integrator::li(const Ray& camera_ray, PixelSampler& rng, LightSampler& light, FireflyRecorder* log,
                   Rgb* light_part) const {
  Rgb L{0, 0, 0};
  if (light_part) *light_part = L;
  PathRegularizer reg(options_.regularization);
  SurfaceHit hit;
  if (!scene_.intersect(camera_ray, &hit)) return reg.clamp(env_.eval(camera_ray.direction), true);

  const bool path = options_.kind == IntegratorKind::Path;
  const int max_depth = path ? options_.max_depth : 1;
  Rgb beta{1, 1, 1};
  Vec3 wo = -camera_ray.direction;
  for (int depth = 0; depth < max_depth; ++depth) {
    rng.set_dimension(kPixelDimensions + kDimensionsPerVertex * static_cast<unsigned>(depth));
    const Point2 u_light = rng.next2d();
    const Point2 u_bsdf = rng.next2d();
    const float u_lobe = rng.next1d();
    const float u_rr = rng.next1d();

    const SceneMaterial& mat = scene_.material(hit.material);
    // One material per thread for textured hits, refilled at each (no allocation once grown).
    thread_local Material textured;
    const HitMaterial hm = resolve_material(scene_, &hit, &textured);
    L += reg.clamp(beta * hm.emission, depth <= 1);
    const float cos_bent = hm.cos_bent;
    thread_local Material regularized;  // the lobes the path's regularization leaves at this vertex
    const Material& bsdf = reg.material(*hm.bsdf, &regularized);
    const ShadingNormals sn = shading_normals(hit, mat.transmissive, wo);
    const Frame frame(sn.ns);
    const Vec3 wo_l = frame.to_local(wo);

    // 1. Light sample.
    if (light.has_light_samples()) {
      ShadingContext sc;
      sc.p = hit.p;
      sc.n = sn.ns;
      sc.wo = wo;
      sc.wo_local = wo_l;
      sc.frame = &frame;
      sc.bsdf = &bsdf;
      sc.cos_bent = cos_bent;
      sc.jitter = rng.stream(static_cast<unsigned>(depth));
      sc.opaque = !mat.transmissive;
      sc.depth = depth;
      light.prepare(sc);
      const DirectionSample ls = light.sample(u_light);
      if (ls.pdf > 0 && std::isfinite(ls.pdf) && is_valid_direction(ls.direction)) {
        const Vec3 wi = ls.direction;
        const Vec3 wi_l = frame.to_local(wi);
        if (direction_counts(wi, wi_l.z, sn, mat.transmissive)) {
          // The radiance before the BSDF, so that its texel's memory read overlaps the BSDF's arithmetic;
          // at the texture coordinate the sampler computed, when it did (no second look-up of wi).
          const Rgb Le = env_.eval_texture(std::isfinite(ls.texture.x) ? ls.texture : env_.texture_coord(wi));
          const Rgb f = bsdf.eval(wo_l, wi_l) * std::fabs(wi_l.z);
          if (!is_black(f)) {
            if (!is_black(Le) && !scene_.occluded(offset_ray_origin(hit.p, hit.ng, wi), wi)) {
              const float w = light.uses_mis() ? mis_weight(ls.pdf, bsdf.pdf(wo_l, wi_l)) : 1.0f;
              const Rgb c = reg.clamp(beta * f * Le * (w / ls.pdf), depth == 0);
              L += c;
              if (light_part) *light_part += c;
              if (log && log->exceeds(c.average()))
                log->record({SampleTechnique::Light, depth, hit.object, c, Le, f, beta, wi, ls.pdf, bsdf.pdf(wo_l, wi_l), w},
                            light);
            }
          }
        }
      }
    }

    // 2. BSDF sample: adds the environment if it escapes, otherwise continues the path.
    const std::optional<BsdfSample> bs = bsdf.sample(wo_l, u_bsdf, u_lobe);
    if (!bs || !(bs->pdf > 0) || !is_finite(bs->weight) || is_black(bs->weight)) break;
    const Vec3 wi = frame.to_world(bs->wi);
    if (!is_valid_direction(wi)) break;
    if (!direction_counts(wi, bs->wi.z, sn, mat.transmissive)) break;
    const Rgb beta_next = beta * bs->weight;
    Ray next{offset_ray_origin(hit.p, hit.ng, wi), normalize(wi), kInfinity};
    // The environment's radiance along the ray before the ray is traced, so that its texel's memory read
    // overlaps the traversal (wasted where the ray hits something); one look-up for it and the pdf.
    const Point2 tex = env_.texture_coord(next.direction);
    const Rgb Le = light.bsdf_hits_count() ? env_.eval_texture(tex) : Rgb{};
    SurfaceHit next_hit;
    if (!scene_.intersect(next, &next_hit)) {
      if (light.bsdf_hits_count()) {
        float w = 1.0f;
        if (light.uses_mis() && light.has_light_samples()) w = mis_weight(bs->pdf, light.pdf(next.direction, tex));
        const Rgb c = reg.clamp(beta_next * Le * w, depth == 0);
        L += c;
        if (log && log->exceeds(c.average())) {
          const float light_pdf = light.has_light_samples() ? light.pdf(next.direction) : 0.0f;
          log->record({SampleTechnique::Bsdf, depth, hit.object, c, Le, bs->weight * bs->pdf, beta, next.direction, light_pdf,
                       bs->pdf, w},
                      light);
        }
      }
      break;
    }
    beta = beta_next;
    reg.bounce(*bs);
    if (depth + 1 >= max_depth) break;
    if (depth + 1 >= options_.rr_depth) {
      const float q = std::min(0.95f, max_component(beta));
      if (!(u_rr < q)) break;
      beta = beta / q;
    }
    hit = next_hit;
    wo = -next.direction;
  }
  return L;
}

}  // namespace envpis::render
