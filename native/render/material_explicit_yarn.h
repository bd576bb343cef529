// The material of explicit yarn tubes (CurveShape): the same yarn BSDF as the
// knit model (knit::KnitMaterial::kernel_bsdf with its palette, roughness and
// ply profile), at the tube's surface.
//
//  - Shading frame: x along the yarn, z the outward tube normal, perturbed
//    by the ply profile at the hit's azimuth and ply coordinate (when the
//    material has ply detail), exactly as the model perturbs its yarn frame.
//  - Colour from the curve's per-point colour index; layers = 1 (a second
//    yarn behind is real geometry here, not an attenuation factor).
//  - A ray that meets a tube from inside (dot(dir, ng) > 0: it was
//    transmitted into this tube) passes on through it, a null event; shadow
//    rays likewise see transmittance 1 from inside and 0 from outside.
#pragma once

#include <memory>

#include "knit/shading.h"
#include "render/material_yarn.h"

namespace knit::render {

class ExplicitYarnMaterial final : public YarnShadedMaterial {
 public:
  explicit ExplicitYarnMaterial(std::shared_ptr<const knit::KnitMaterial> model);
  const char* kind() const override { return "explicit yarn"; }
  PassThrough resolve(SurfaceInteraction& si, const RayDifferential& ray, Sampler& sampler) const override;
  Rgb transmittance(const SurfaceInteraction& si, Vec3 w, Sampler& sampler) const override;

 private:
  std::shared_ptr<const knit::KnitMaterial> model_;
};

}  // namespace knit::render
