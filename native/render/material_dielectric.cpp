#include <cmath>

#include "render/fresnel.h"
#include "render/materials.h"

namespace knit::render {

bool SmoothDielectricMaterial::sample(const SurfaceInteraction&, Vec3 wo, float uc, Vec2, BsdfSample& s) const {
  const float cos_o = wo.z;
  if (cos_o == 0) return false;
  const float f = fresnel_dielectric(cos_o, eta_);
  if (uc < f) {
    s.wi = {-wo.x, -wo.y, wo.z};
    s.weight = Rgb(1.0f);  // F / P(reflect) with P(reflect) = F
    s.pdf = f;
    s.flags = kReflection | kSpecular;
    s.eta = 1;
    return true;
  }
  // eta_rel = IOR of the far side / IOR of wo's side.
  const bool entering = cos_o > 0;
  const float eta_rel = entering ? eta_ : 1.0f / eta_;
  Vec3 wi;
  if (!refract(wo, Vec3(0, 0, entering ? 1.0f : -1.0f), eta_rel, wi)) return false;  // TIR has f = 1
  s.wi = wi;
  // (1 - F) / P(refract) = 1; radiance is scaled by 1 / eta_rel^2 across the interface.
  s.weight = tint_ / (eta_rel * eta_rel);
  s.pdf = 1.0f - f;
  s.flags = kTransmission | kSpecular;
  s.eta = eta_rel;
  return true;
}

}  // namespace knit::render
