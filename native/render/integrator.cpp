#include "render/integrator.h"

#include <cmath>
#include <limits>

#include "render/differentials.h"
#include "render/sampling.h"

namespace knit::render {

Vec3 offset_ray_origin(Vec3 p, Vec3 ng, Vec3 d) {
  const float eps = 1e-5f * (1.0f + max_abs_component(p));
  return p + ng * (dot(d, ng) >= 0 ? eps : -eps);
}

namespace {
constexpr float kInf = std::numeric_limits<float>::infinity();

struct PathState {
  bool specular = true;  // no non-delta scattering yet since the last counted emission
  float bsdf_pdf = 0;    // density of the last BSDF sample
  Vec3 prev_p;           // last scattering vertex
};
}  // namespace

Rgb PathIntegrator::shadow_transmittance(Vec3 origin, Vec3 dir, float tmax, PathStats& stats,
                                         Sampler& sampler, float cone_width, float cone_spread) const {
  {
    // Embree's any-hit test first: it settles every shadow ray of a scene
    // without pass-through materials, and in the others the many that meet
    // nothing at all, at a fraction of the closest-hit walk below.
    ++stats.shadow_rays;
    Ray r;
    r.o = origin;
    r.d = dir;
    r.tmax = tmax;
    if (!scene_.accel().occluded(r)) return Rgb(1.0f);
    if (!scene_.has_pass_through()) return Rgb();
  }
  const bool finite = std::isfinite(tmax);
  const Vec3 end = finite ? origin + dir * tmax : Vec3();
  Rgb tr(1.0f);
  RayDifferential r;
  r.o = origin;
  r.d = dir;
  r.tmax = tmax;
  for (int crossing = 0; crossing <= kMaxPassThrough; ++crossing) {
    ++stats.shadow_rays;
    SurfaceInteraction si;
    if (!scene_.accel().intersect(r, si)) return tr;
    if (si.light >= 0) return {};
    const Material& m = scene_.material(si.material);
    if (!m.can_pass_through()) return {};
    if (m.resolves_hits()) ++stats.shadow_resolves;
    si.cone_width = cone_width + dot(si.p - origin, dir) * cone_spread;
    tr *= m.transmittance(si, dir, sampler);
    if (tr.is_black()) return {};
    r.o = offset_ray_origin(si.p, si.ng, dir);
    if (finite) {
      r.tmax = dot(end - r.o, dir);
      if (!(r.tmax > 0)) return tr;
    }
  }
  ++stats.pass_limit;
  return {};
}

Rgb PathIntegrator::li(RayDifferential ray, Sampler& sampler, PathStats& stats) const {
  const Strategy strategy = settings_.strategy;
  const LightSampler& lights = scene_.light_sampler();
  Rgb radiance, beta(1.0f);
  PathState state;
  state.prev_p = ray.o;
  int depth = 0, passes = 0;
  ++stats.camera_rays;

  // MIS weight of emission found by a BSDF-sampled ray (light `index`, seen
  // along `dir` from the last scattering vertex, at `hit` or escaping).
  auto emission_weight = [&](int index, Vec3 dir, const SurfaceInteraction* hit) -> float {
    if (state.specular || strategy == Strategy::Bsdf) return 1.0f;
    if (strategy == Strategy::Nee) return 0.0f;
    const float light_pdf = scene_.light(index).pdf(state.prev_p, dir, hit) *
                            lights.probability(static_cast<size_t>(index));
    return power_heuristic(state.bsdf_pdf, light_pdf);
  };

  // The last vertex's light sample, its shadow once traced (nee.tr, zero
  // when blocked or never traced), for the walk's vertices after it.
  struct NeeSample {
    bool valid = false, traced = false;
    float sel = 0;
    LightSample ls;
    Rgb tr;
  } nee;
  bool walk = false;  // this vertex is the class table's walk from the last (bounce_table)
  SurfaceInteraction si;
  bool inside = false;  // si was found by a bounce inside the last hit's shell (Material::bounce_inside)
  for (;;) {
    const Vec3 wo = -ray.d;
    const Material* mat = nullptr;
    bool resolves = true;
    PassThrough pt;
    if (inside) {
      // Already resolved: no intersection, emission or pass-through.
      inside = false;
      mat = &scene_.material(si.material);
    } else {
      si = SurfaceInteraction{};
      const bool found = scene_.accel().intersect(ray, si);
      si.cone_width = ray.cone_width + si.t * ray.cone_spread;
      if (!found) {
        if (const Light* env = scene_.environment()) {
          const Rgb le = env->environment(ray.d);
          if (!le.is_black()) radiance += beta * le * emission_weight(scene_.environment_index(), ray.d, nullptr);
        }
        break;
      }
      if (si.light >= 0) {
        const Rgb le = scene_.light(si.light).emitted(si, wo);
        if (!le.is_black()) radiance += beta * le * emission_weight(si.light, ray.d, &si);
        break;  // emitters absorb
      }
      mat = &scene_.material(si.material);
      resolves = mat->resolves_hits();
      if (resolves) {
        // The knit model or a yarn tube: finds what lies below the hit and
        // sets the yarn shading frame, or lets the ray pass on straight.
        pt = mat->resolve(si, ray, sampler);
        ++stats.resolves;
        if (pt.pass) ++stats.resolve_passes;
        if (pt.from_table) ++stats.table_resolves;
        if (pt.from_sub_cells) ++stats.sub_cell_resolves;
        if (pt.quarter_cell) ++stats.quarter_cell_resolves;
        if (pt.aggregated) ++stats.aggregate_resolves;
        if (depth == 0) {
          ++stats.camera_resolves;
          if (pt.table_would_serve) ++stats.camera_table_footprints;
          if (!pt.pass && si.yarn.segment > 0 && ray.cone_spread > 0) {
            // A camera path's hit on a yarn tube: how many segments its pixel spans.
            const float span = si.cone_width / si.yarn.segment;
            size_t bin = 0;
            while (bin < kTubeSpanEdges.size() && !(span < kTubeSpanEdges[bin])) ++bin;
            ++stats.tube_spans[bin];
          }
        }
      } else {
        // Where the interpolated normal puts the viewer on the other side than
        // the geometry does (grazing views of smooth-shaded meshes), shade with
        // the geometric normal: otherwise every sampled direction would be on
        // the wrong side of the surface and the path would be lost.
        if (dot(wo, si.shading.n) * dot(wo, si.ng) <= 0) {
          const float sign = dot(si.shading.b, cross(si.shading.n, si.shading.t)) < 0 ? -1.0f : 1.0f;
          si.shading = Frame::from_normal_tangent(si.ng, si.shading.t);
          si.shading.b = si.shading.b * sign;
        }
        if (mat->can_pass_through()) pt = mat->pass_through(si, si.shading.to_local(wo), sampler.get1d());
      }
    }
    const Material& m = *mat;
    const Vec3 wo_l = si.shading.to_local(wo);
    beta *= pt.weight;
    if (pt.pass) {
      if (++passes > kMaxPassThrough) {
        ++stats.pass_limit;
        break;
      }
      RayDifferential next;
      next.o = offset_ray_origin(si.p, si.ng, ray.d);
      next.d = ray.d;
      differentials_pass_through(ray, si, next);
      next.cone_width = si.cone_width;
      next.cone_spread = ray.cone_spread;
      ray = next;
      ++stats.bounce_rays;
      continue;  // not a bounce
    }
    if (depth >= settings_.max_depth) break;

    // Next-event estimation. A vertex of the class table's walk lies at the
    // vertex before it: it reuses that vertex's light sample and, once
    // traced, its shadow (the sample does not depend on the walk's
    // directions, so each vertex's estimate stays unbiased), and costs no
    // light sample or shadow ray of its own.
    const bool walked = walk;
    walk = false;
    if (strategy != Strategy::Bsdf && m.has_smooth_lobes() && !lights.empty()) {
      if (!walked) {
        nee = NeeSample{};
        size_t index = 0;
        const Light* light = lights.pick(sampler.get1d(), nee.sel, index);
        const Vec2 ul = sampler.get2d();
        nee.valid = light && light->sample(si.p, ul, nee.ls) && nee.ls.pdf > 0 && !nee.ls.li.is_black();
      }
      const LightSample& ls = nee.ls;
      const float sel = nee.sel;
      if (nee.valid && !(walked && nee.traced && nee.tr.is_black())) {  // (a shadow known: no evaluation)
        const Vec3 wi_l = si.shading.to_local(ls.wi);
        const bool mis = !ls.delta && strategy == Strategy::Mis;
        float bsdf_pdf = -1;  // (set by materials that evaluate it with f)
        const Rgb f = m.eval_pdf(si, wo_l, wi_l, mis, bsdf_pdf);
        const bool geo_reflect = dot(ls.wi, si.ng) * dot(wo, si.ng) > 0;
        const bool sh_reflect = wi_l.z * wo_l.z > 0;
        const bool lit = !f.is_black() && (resolves || geo_reflect == sh_reflect);
        if (lit && !nee.traced) {
          nee.traced = true;
          const Vec3 origin = offset_ray_origin(si.p, si.ng, ls.wi);
          Vec3 dir = ls.wi;
          float tmax = kInf;
          if (!ls.infinite) {
            const Vec3 to = ls.p - origin;
            const float dist = length(to);
            dir = to / dist;
            tmax = dist * (1.0f - 1e-4f) - 1e-5f * (1.0f + max_abs_component(ls.p));
          }
          // From a yarn point inside the shell, the march through the shell
          // (self_transmittance) costs about ten scene shadow rays: first ask
          // Embree whether anything that no shadow ray passes (the floor, an
          // opaque object) blocks the light. If so, the light is blocked
          // whatever the march finds. (No sampler draw is taken either way.)
          if (tmax > 0 && resolves && si.yarn.in_shell && scene_.has_shadow_blockers()) {
            Ray blocker;
            blocker.o = origin;
            blocker.d = dir;
            blocker.tmax = tmax;
            ++stats.shadow_rays;
            if (scene_.accel().occluded_by_blockers(blocker)) {
              tmax = 0;
              ++stats.marches_spared;
            }
          }
          if (tmax > 0) {
            // Yarn between the shading point and the shell's surface first.
            Rgb tr = resolves ? m.self_transmittance(si, dir) : Rgb(1.0f);
            if (!tr.is_black()) tr *= shadow_transmittance(origin, dir, tmax, stats, sampler, si.cone_width, ray.cone_spread);
            nee.tr = tr;
          }
        }
        if (lit && !nee.tr.is_black()) {
          float w = 1.0f;
          if (!ls.delta && strategy == Strategy::Mis)
            w = power_heuristic(sel * ls.pdf, bsdf_pdf >= 0 ? bsdf_pdf : m.pdf(si, wo_l, wi_l));
          radiance += beta * f * nee.tr * ls.li * (std::fabs(wi_l.z) * w / (sel * ls.pdf));
        }
      }
    }

    // BSDF sampling.
    const float uc = sampler.get1d();
    const Vec2 ub = sampler.get2d();
    BsdfSample bs;
    if (!m.sample(si, wo_l, uc, ub, bs) || !(bs.pdf > 0) || bs.weight.is_black()) break;
    const Vec3 wi = si.shading.to_world(bs.wi);
    const bool geo_reflect = dot(wi, si.ng) * dot(wo, si.ng) > 0;
    const bool lobe_reflect = (bs.flags & kReflection) != 0;
    if (!resolves && geo_reflect != lobe_reflect) break;  // shading normal and geometry disagree: absorbed
    beta *= bs.weight;
    state.specular = bs.is_delta();
    state.bsdf_pdf = bs.pdf;
    state.prev_p = si.p;
    ++depth;
    if (depth >= settings_.rr_depth) {
      const float q = std::min(0.95f, beta.max());
      if (!(q > 0) || sampler.get1d() >= q) break;
      beta = beta / q;
    }
    // Met yarn again inside the shell (the near field's march, or the class
    // table's shadowed share): that is the next vertex.
    const bool again = bs.internal ? m.bounce_table(si, wi, sampler.get1d()) : resolves && m.bounce_inside(si, wi);
    if (bs.internal && !again) break;
    walk = bs.internal;
    if (again) {
      ray.o = si.p;
      ray.d = wi;
      ray.has_differentials = false;
      ray.cone_width = si.cone_width;
      inside = true;
      ++stats.shell_bounces;
      continue;
    }
    RayDifferential next;
    next.o = offset_ray_origin(si.p, si.ng, wi);
    next.d = wi;
    next.cone_width = si.cone_width;
    next.cone_spread = ray.cone_spread;
    if (bs.is_delta()) differentials_specular(ray, si, bs, next);
    ray = next;
    ++stats.bounce_rays;
  }
  return radiance;
}

}  // namespace knit::render
