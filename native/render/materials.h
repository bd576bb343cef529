// The materials the renderer has now (docs/scene-format.md#materials).
#pragma once

#include "render/material.h"
#include "render/scene_desc.h"

namespace knit::render {

// Lambertian, two-sided: reflects on whichever side wo is.
class DiffuseMaterial final : public Material {
 public:
  explicit DiffuseMaterial(Rgb albedo) : albedo_(albedo) {}
  const char* kind() const override { return "diffuse"; }
  bool has_smooth_lobes() const override { return true; }
  Rgb eval(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const override;
  float pdf(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const override;
  bool sample(const SurfaceInteraction&, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const override;

 private:
  Rgb albedo_;
};

// Smooth dielectric interface (delta reflection + delta refraction with the
// exact Fresnel term). The shading normal points outside; eta = IOR inside /
// IOR outside. `tint` scales refracted light. A roughness above 0 is a
// RoughDielectricMaterial.
class SmoothDielectricMaterial final : public Material {
 public:
  explicit SmoothDielectricMaterial(const DielectricDesc& d) : eta_(d.eta), tint_(d.tint) {}
  const char* kind() const override { return "dielectric"; }
  bool has_smooth_lobes() const override { return false; }
  Rgb eval(const SurfaceInteraction&, Vec3, Vec3) const override { return {}; }
  float pdf(const SurfaceInteraction&, Vec3, Vec3) const override { return 0; }
  bool sample(const SurfaceInteraction&, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const override;

 private:
  float eta_;
  Rgb tint_;
};

// Rough dielectric interface: isotropic GGX microfacets with alpha =
// roughness^2 (Blender's and Cycles' convention), reflection and refraction
// after Walter et al. 2007 with the exact dielectric Fresnel term and
// height-correlated Smith shadowing, sampled from the visible normals
// (Heitz 2018; the kernel's mf_ggx_* functions). As the smooth one: the
// shading normal points outside, eta = IOR inside / IOR outside, radiance is
// scaled by 1 / eta_rel^2 across the interface, `tint` scales refracted
// light. Single scattering: light that the microfacets shadow is lost.
class RoughDielectricMaterial final : public Material {
 public:
  explicit RoughDielectricMaterial(const DielectricDesc& d);
  const char* kind() const override { return "rough dielectric"; }
  bool has_smooth_lobes() const override { return true; }
  Rgb eval(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const override;
  float pdf(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const override;
  bool sample(const SurfaceInteraction&, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const override;

 private:
  float eta_, alpha_;
  Rgb tint_;
};

// A thin sheet: with probability P = mean(transmittance) a ray passes straight
// through (weight transmittance / P); otherwise the surface reflects
// diffusely with `albedo` (weight 1 / (1 - P)). Shadow rays see
// `transmittance`. Exercises the pass-through machinery the knit model uses.
class ThinMaterial final : public Material {
 public:
  explicit ThinMaterial(const ThinDesc& d);
  const char* kind() const override { return "thin"; }
  PassThrough pass_through(const SurfaceInteraction&, Vec3 wo, float u) const override;
  Rgb transmittance(const SurfaceInteraction&, Vec3, Sampler&) const override { return transmittance_; }
  bool can_pass_through() const override { return pass_prob_ > 0; }
  bool has_smooth_lobes() const override { return true; }
  Rgb eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const override { return diffuse_.eval(si, wo, wi); }
  float pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const override { return diffuse_.pdf(si, wo, wi); }
  bool sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const override {
    return diffuse_.sample(si, wo, uc, u, s);
  }

 private:
  Rgb transmittance_;
  float pass_prob_ = 0;
  DiffuseMaterial diffuse_;
};

}  // namespace knit::render
