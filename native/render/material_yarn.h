// Materials shaded with the yarn BSDF (paper Eq. 1, native/kernel/yarn_bsdf.h):
// the knit model on a base mesh (material_knit.h) and explicit yarn tubes
// (material_explicit_yarn.h). Both resolve every hit first (Material::resolve)
// and leave the kernel BSDF of the hit point in si.yarn; eval, pdf and sample
// below read it, in the yarn's local frame (si.shading: z the yarn surface
// normal, x the yarn tangent). The knit model with bsdf_model Cycles leaves
// the smooth lobes of Cycles' closures instead (si.yarn.cycles,
// bsdf_cycles.h).
#pragma once

#include "render/material.h"

namespace knit::render {

inline knit::k::kvec3 to_kvec(Vec3 v) { return knit::k::kv3(v.x, v.y, v.z); }
inline Vec3 from_kvec(knit::k::kvec3 v) { return {v.x, v.y, v.z}; }

class YarnShadedMaterial : public Material {
 public:
  bool has_smooth_lobes() const override { return true; }
  bool resolves_hits() const override { return true; }
  bool can_pass_through() const override { return true; }
  // f(wo, wi) without the cosine (the kernel's eval includes it).
  Rgb eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const override;
  float pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const override;
  // The class table's tabulated BSDF evaluates once for both.
  Rgb eval_pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi, bool want_pdf, float& pdf_out) const override;
  // The yarn BSDF uses u (lobe choice and direction); the class table's
  // tabulated BSDF uses uc too (its cell, then the direction in it).
  bool sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const override;
};

}  // namespace knit::render
