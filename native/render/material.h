// The material contract. Directions are in the local shading frame (z the
// shading normal, x along +u, y along +v); wo points away from the surface
// toward where the light goes (the viewer), wi toward where it comes from.
//
//   eval(wo, wi)          f(wo, wi) without the cosine; 0 for delta lobes
//   pdf(wo, wi)           solid-angle density of sample(); 0 for delta lobes
//   sample(wo, uc, u)     -> {wi, weight = f |cos wi| / pdf, pdf, flags}
//
// Pass-through (for the knit model's CAPM misses and delta transmission): before
// shading, pass_through() may decide that the ray continues straight on
// unchanged with a weight; that is not a bounce. When it does not pass, its
// weight (e.g. 1 / (1 - P)) multiplies the path throughput before shading.
// Shadow rays crossing the surface are attenuated by transmittance(w), which
// must equal the expected pass-through weight so NEE and BSDF paths agree.
//
// Hit resolution (the knit model and explicit yarns, resolves_hits() true):
// resolve() runs once at every hit of a path, first. It finds what the ray
// really meets below the hit (CAPM through the yarn shell; the inside of a
// yarn tube) and either passes the ray on straight (a pass-through event, as
// above) or sets the shading frame and si.yarn for eval/pdf/sample. The
// integrator then neither swaps in the geometric normal nor rejects
// directions on the "wrong" side of the geometric normal: the yarn BSDF's
// reflection and transmission are about the yarn, not the base surface.
#pragma once

#include <cstdint>

#include "render/interaction.h"
#include "render/ray.h"
#include "render/rng.h"
#include "render/vec.h"

namespace knit::render {

enum BsdfFlags : uint32_t {
  kReflection = 1u << 0,
  kTransmission = 1u << 1,
  kDiffuse = 1u << 2,
  kGlossy = 1u << 3,
  kSpecular = 1u << 4,  // a delta lobe: eval and pdf are zero, only sample() reaches it
};

struct BsdfSample {
  Vec3 wi;
  Rgb weight;        // f |cos| / pdf (delta lobes: the lobe's share over its probability)
  float pdf = 0;     // solid angle; for delta lobes the discrete probability of the lobe
  uint32_t flags = 0;
  float eta = 1;     // relative IOR crossed by a transmission (for ray differentials)
  // The knit model's class table: wi meets other yarn of the same footprint
  // first, where the path scatters again (Material::bounce_table).
  bool internal = false;
  bool is_delta() const { return (flags & kSpecular) != 0; }
};

struct PassThrough {
  bool pass = false;
  Rgb weight{1.0f};
  bool from_table = false;  // the knit model read the hit from its multi-scale class table
  bool from_sub_cells = false;  // ... from the table's sub-cells
  bool quarter_cell = false;    // ... shaded as the near field, but table_min_cells 0.25 would read it from the table
  bool aggregated = false;  // the knit model aggregated marches over the hit's multi-scale footprint
  bool table_would_serve = false;  // near-field mode: multi-scale mode would read the hit from its class table
};

class Material {
 public:
  virtual ~Material() = default;
  virtual const char* kind() const = 0;

  // Stochastic pass-through decision with the uniform number u.
  virtual PassThrough pass_through(const SurfaceInteraction&, Vec3 /*wo*/, float /*u*/) const { return {}; }
  // Straight-through transmittance for a shadow ray crossing along the world
  // direction w (stochastic materials draw from `sampler`).
  virtual Rgb transmittance(const SurfaceInteraction&, Vec3 /*w*/, Sampler& /*sampler*/) const { return {}; }
  // Hit resolution (see above).
  virtual bool resolves_hits() const { return false; }
  virtual PassThrough resolve(SurfaceInteraction&, const RayDifferential&, Sampler&) const { return {}; }
  // Self-shadowing of a resolved hit: the transmittance, along the world
  // direction w, of what lies between the shading point and the surface the
  // hit was found on (the knit model's yarn shell); shadow rays towards a
  // light start beyond that surface.
  virtual Rgb self_transmittance(const SurfaceInteraction&, Vec3 /*w*/) const { return Rgb(1.0f); }
  // A sample with `internal` set (the knit model's class table): wi (world)
  // meets other yarn of the same footprint; si becomes that scattering
  // point, seen from -wi (u: a uniform number for its choices). False
  // when the material has no such samples.
  virtual bool bounce_table(SurfaceInteraction&, Vec3 /*wi*/, float /*u*/) const { return false; }
  // A bounce of a resolved hit that stays inside it: when the ray leaving si
  // along wi (world) meets the same material again before leaving the
  // surface's shell, si becomes that hit (shading set, as resolve does) and
  // the result is true; false when the ray leaves and is traced on.
  virtual bool bounce_inside(SurfaceInteraction&, Vec3 /*wi*/) const { return false; }
  // True when pass_through() or transmittance() can be non-zero.
  virtual bool can_pass_through() const { return false; }
  // False when every lobe is delta: next-event estimation is skipped.
  virtual bool has_smooth_lobes() const = 0;

  virtual Rgb eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const = 0;
  virtual float pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const = 0;
  // eval; a material that can share the work also sets pdf_out to
  // pdf(si, wo, wi) when want_pdf (light sampling's MIS weight), else it
  // leaves pdf_out as it is (the caller asks pdf() when it needs it).
  virtual Rgb eval_pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi, bool /*want_pdf*/, float& /*pdf_out*/) const {
    return eval(si, wo, wi);
  }
  virtual bool sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const = 0;
};

}  // namespace knit::render
