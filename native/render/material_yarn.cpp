#include "render/material_yarn.h"

#include <cmath>

namespace knit::render {

namespace {
bool usable(Vec3 w) { return is_finite(w) && std::fabs(length2(w) - 1.0f) < 1e-3f; }
}  // namespace

Rgb YarnShadedMaterial::eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi) || wi.z == 0.0f) return {};
  const knit::k::kvec3 f = knit::k::yarn_bsdf_eval(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
  const float inv = 1.0f / std::fabs(wi.z);
  return {f.x * inv, f.y * inv, f.z * inv};
}

float YarnShadedMaterial::pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi)) return 0;
  return knit::k::yarn_bsdf_pdf(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
}

bool YarnShadedMaterial::sample(const SurfaceInteraction& si, Vec3 wo, float, Vec2 u, BsdfSample& s) const {
  if (!si.yarn.active || !usable(wo)) return false;
  const knit::k::KBsdfSample k = knit::k::yarn_bsdf_sample(si.yarn.bsdf, to_kvec(wo), u.x, u.y);
  if (!(k.pdf > 0) || k.flags == 0) return false;
  s.wi = from_kvec(k.wi);
  s.weight = {k.weight.x, k.weight.y, k.weight.z};
  s.pdf = k.pdf;
  s.flags = kGlossy | ((k.flags & KB_REFLECT) ? kReflection : kTransmission);
  s.eta = 1;
  return s.weight.is_finite();
}

}  // namespace knit::render
