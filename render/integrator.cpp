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

/// What the light and the BSDF sample at one path vertex share.
struct Integrator::Vertex {
  const SurfaceHit& hit;
  const ShadingNormals& sn;
  const Frame& frame;
  Vec3 wo, wo_l;
  const Material& bsdf;
  bool transmissive;
  int depth;
  Rgb beta;  // the path's throughput up to this vertex
};

Rgb Integrator::light_sample(const Vertex& v, const DirectionSample& ls, const LightSampler& light,
                             const PathRegularizer& reg, FireflyRecorder* log) const {
  if (!(ls.pdf > 0) || !std::isfinite(ls.pdf) || !is_valid_direction(ls.direction)) return {};
  const Vec3 wi = ls.direction;
  const Vec3 wi_l = v.frame.to_local(wi);
  if (!direction_counts(wi, wi_l.z, v.sn, v.transmissive)) return {};
  // At the texture coordinate the sampler computed, when it did (no second look-up of wi); fetched
  // while the BSDF is evaluated.
  const Point2 tex = std::isfinite(ls.texture.x) ? ls.texture : env_.texture_coord(wi);
  env_.prefetch(tex);
  // f and the BSDF's pdf in one evaluation (they share the half-vector, D and the lobe choice).
  float bsdf_pdf = 0;
  const Rgb f = v.bsdf.eval_pdf(v.wo_l, wi_l, &bsdf_pdf) * std::fabs(wi_l.z);
  if (is_black(f)) return {};
  const Rgb Le = env_.eval_texture(tex);
  if (is_black(Le) || scene_.occluded(offset_ray_origin(v.hit.p, v.hit.ng, wi), wi)) return {};
  const float w = light.uses_mis() ? mis_weight(ls.pdf, bsdf_pdf) : 1.0f;
  const Rgb c = reg.clamp(v.beta * f * Le * (w / ls.pdf), v.depth == 0);
  if (log && log->exceeds(c.average()))
    log->record({SampleTechnique::Light, v.depth, v.hit.object, c, Le, f, v.beta, wi, ls.pdf, bsdf_pdf, w}, light);
  return c;
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
    const unsigned dims = kPixelDimensions + kDimensionsPerVertex * static_cast<unsigned>(depth);
    rng.set_dimension(dims);
    const Point2 u_light = rng.next2d();
    const Point2 u_bsdf = rng.next2d();
    const float u_lobe = rng.next1d();

    const SceneMaterial& mat = scene_.material(hit.material);
    // One material per thread for textured hits, refilled at each (no allocation once grown).
    thread_local Material textured;
    const HitMaterial hm = resolve_material(scene_, &hit, &textured);
    L += reg.clamp(beta * hm.emission, depth <= 1);
    thread_local Material regularized;  // the lobes the path's regularization leaves at this vertex
    const Material& bsdf = reg.material(*hm.bsdf, &regularized);
    const ShadingNormals sn = shading_normals(hit, mat.transmissive, wo);
    const Frame frame(sn.ns);
    const Vertex v{hit, sn, frame, wo, frame.to_local(wo), bsdf, mat.transmissive, depth, beta};

    const bool lights = light.has_light_samples();
    if (lights) {
      ShadingContext sc;
      sc.p = hit.p;
      sc.n = sn.ns;
      sc.wo = wo;
      sc.wo_local = v.wo_l;
      sc.frame = &frame;
      sc.bsdf = &bsdf;
      sc.cos_bent = hm.cos_bent;
      sc.jitter = rng.stream(static_cast<unsigned>(depth));
      sc.opaque = !mat.transmissive;
      sc.depth = depth;
      light.prepare(sc);
    }
    // The BSDF sample's direction before the light sample (which does not depend on it): the
    // environment's texel there and the light density's record are fetched from memory while the
    // light sample and both rays run, and read after the BSDF ray is traced.
    const std::optional<BsdfSample> bs = bsdf.sample(v.wo_l, u_bsdf, u_lobe);
    const Vec3 wi = bs ? frame.to_world(bs->wi) : Vec3{};
    const Vec3 wi_unit = bs ? normalize(wi) : Vec3{};
    const Point2 tex = bs ? env_.texture_coord(wi_unit) : Point2{};
    if (bs) {
      env_.prefetch(tex);
      if (lights) light.prefetch_pdf(tex);
    }

    // 1. Light sample.
    if (lights) {
      const Rgb c = light_sample(v, light.sample(u_light), light, reg, log);
      L += c;
      if (light_part) *light_part += c;
    }

    // 2. BSDF sample: adds the environment if it escapes, otherwise continues the path.
    if (!bs || !(bs->pdf > 0) || !is_finite(bs->weight) || is_black(bs->weight)) break;
    if (!is_valid_direction(wi)) break;
    if (!direction_counts(wi, bs->wi.z, sn, mat.transmissive)) break;
    const Rgb beta_next = beta * bs->weight;
    Ray next{offset_ray_origin(hit.p, hit.ng, wi), wi_unit, kInfinity};
    SurfaceHit next_hit;
    if (!scene_.intersect(next, &next_hit)) {
      if (light.bsdf_hits_count()) {
        const Rgb Le = env_.eval_texture(tex);
        float w = 1.0f;
        if (light.uses_mis() && lights) w = mis_weight(bs->pdf, light.pdf(next.direction, tex));
        const Rgb c = reg.clamp(beta_next * Le * w, depth == 0);
        L += c;
        if (log && log->exceeds(c.average())) {
          const float light_pdf = lights ? light.pdf(next.direction) : 0.0f;
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
      rng.set_dimension(dims + kRouletteDimension);  // drawn only here: most vertices never need it
      if (!(rng.next1d() < q)) break;
      beta = beta / q;
    }
    hit = next_hit;
    wo = -next.direction;
  }
  return L;
}

}  // namespace envpis::render
