// Delta lights: point and directional (reached by next-event estimation only).
#include <cmath>

#include "render/light.h"

namespace knit::render {

bool PointLight::sample(Vec3 p, Vec2, LightSample& s) const {
  const Vec3 d = pos_ - p;
  const float dist2 = length2(d);
  if (!(dist2 > 0)) return false;
  s.wi = d / std::sqrt(dist2);
  s.p = pos_;
  s.infinite = false;
  s.li = intensity_ / dist2;
  s.pdf = 1;
  s.delta = true;
  return true;
}

float PointLight::power(float) const { return 4 * kPi * intensity_.luminance(); }

bool DirectionalLight::sample(Vec3, Vec2, LightSample& s) const {
  s.wi = to_light_;
  s.infinite = true;
  s.li = irradiance_;
  s.pdf = 1;
  s.delta = true;
  return true;
}

float DirectionalLight::power(float scene_radius) const {
  return kPi * scene_radius * scene_radius * irradiance_.luminance();
}

}  // namespace knit::render
