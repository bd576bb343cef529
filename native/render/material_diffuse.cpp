#include <cmath>

#include "render/materials.h"
#include "render/sampling.h"

namespace knit::render {

Rgb DiffuseMaterial::eval(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const {
  if (!(wo.z * wi.z > 0)) return {};
  return albedo_ * kInvPi;
}

float DiffuseMaterial::pdf(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const {
  if (!(wo.z * wi.z > 0)) return 0;
  return std::fabs(wi.z) * kInvPi;
}

bool DiffuseMaterial::sample(const SurfaceInteraction&, Vec3 wo, float, Vec2 u, BsdfSample& s) const {
  if (wo.z == 0) return false;
  Vec3 wi = sample_cosine_hemisphere(u);
  if (!(wi.z > 0)) return false;
  if (wo.z < 0) wi.z = -wi.z;
  s.wi = wi;
  s.pdf = std::fabs(wi.z) * kInvPi;
  s.weight = albedo_;  // (albedo / pi) |cos| / (|cos| / pi)
  s.flags = kReflection | kDiffuse;
  s.eta = 1;
  return true;
}

ThinMaterial::ThinMaterial(const ThinDesc& d) : transmittance_(d.transmittance), diffuse_(d.albedo) {
  pass_prob_ = d.transmittance.mean();
}

PassThrough ThinMaterial::pass_through(const SurfaceInteraction&, Vec3, float u) const {
  PassThrough p;
  if (!(pass_prob_ > 0)) return p;
  if (u < pass_prob_) {
    p.pass = true;
    p.weight = transmittance_ / pass_prob_;
  } else {
    p.weight = Rgb(1.0f / (1.0f - pass_prob_));
  }
  return p;
}

}  // namespace knit::render
