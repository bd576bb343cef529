// Sample warps used by lights and materials, and the MIS power heuristic.
// Every warp documents its density; tests check them against histograms.
#pragma once

#include <cmath>

#include "render/vec.h"

namespace knit::render {

// Concentric square-to-disk map (Shirley and Chiu 1997): uniform on the unit disk.
inline Vec2 sample_disk_concentric(Vec2 u) {
  const float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
  if (ox == 0 && oy == 0) return {0, 0};
  float r, theta;
  if (std::fabs(ox) > std::fabs(oy)) {
    r = ox;
    theta = (kPi / 4) * (oy / ox);
  } else {
    r = oy;
    theta = kPi / 2 - (kPi / 4) * (ox / oy);
  }
  return {r * std::cos(theta), r * std::sin(theta)};
}

// Cosine-weighted upper hemisphere (z >= 0); density cos(theta) / pi.
inline Vec3 sample_cosine_hemisphere(Vec2 u) {
  const Vec2 d = sample_disk_concentric(u);
  const float z = std::sqrt(std::max(0.0f, 1.0f - d.x * d.x - d.y * d.y));
  return {d.x, d.y, z};
}
inline float cosine_hemisphere_pdf(float cos_theta) { return cos_theta > 0 ? cos_theta * kInvPi : 0; }

// Uniform on the unit sphere; density 1 / (4 pi).
inline Vec3 sample_uniform_sphere(Vec2 u) {
  const float z = 1.0f - 2.0f * u.x;
  const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
  const float phi = 2.0f * kPi * u.y;
  return {r * std::cos(phi), r * std::sin(phi), z};
}
constexpr float uniform_sphere_pdf() { return kInv4Pi; }

// Power heuristic with beta = 2 (Veach 1997) for one sample of each strategy:
// the weight of the strategy with density `pa` against one with density `pb`.
inline float power_heuristic(float pa, float pb) {
  if (std::isinf(pa)) return 1.0f;
  const float a = pa * pa, b = pb * pb;
  return a + b > 0 ? a / (a + b) : 0.0f;
}

}  // namespace knit::render
