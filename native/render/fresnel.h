// Fresnel reflectance of a smooth dielectric interface (unpolarised light).
#pragma once

#include <cmath>

#include "render/vec.h"

namespace knit::render {

// cos_i: cosine of the incident direction with the normal on the outside
// (negative when arriving from inside); eta: IOR inside / IOR outside.
// Returns 1 under total internal reflection.
inline float fresnel_dielectric(float cos_i, float eta) {
  if (cos_i < 0) {
    eta = 1.0f / eta;
    cos_i = -cos_i;
  }
  cos_i = std::min(cos_i, 1.0f);
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return 1.0f;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  const float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
  const float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
  return 0.5f * (r_perp * r_perp + r_par * r_par);
}

// Refracts `wo` (unit, pointing away from the surface, on the side of `n`)
// through an interface with relative IOR eta = IOR(far side) / IOR(wo side).
// Returns false under total internal reflection.
inline bool refract(Vec3 wo, Vec3 n, float eta, Vec3& wi) {
  const float cos_i = dot(wo, n);
  const float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
  if (sin2_t >= 1.0f) return false;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  wi = -wo / eta + n * (cos_i / eta - cos_t);
  return true;
}

}  // namespace knit::render
