#include <cmath>

#include "render/light.h"

namespace knit::render {

QuadLight::QuadLight(const LightDesc& d)
    : corner_(d.corner), eu_(d.edge_u), ev_(d.edge_v), emission_(d.emission), two_sided_(d.two_sided) {
  const Vec3 c = cross(eu_, ev_);
  area_ = length(c);
  n_ = c / area_;
}

bool QuadLight::sample(Vec3 p, Vec2 u, LightSample& s) const {
  const Vec3 q = corner_ + eu_ * u.x + ev_ * u.y;
  const Vec3 d = q - p;
  const float dist2 = length2(d);
  if (!(dist2 > 0)) return false;
  const float dist = std::sqrt(dist2);
  const Vec3 wi = d / dist;
  const float cos_l = -dot(wi, n_);  // > 0 when p is on the emitting (front) side
  if (!two_sided_ && cos_l <= 0) return false;
  const float acos_l = std::fabs(cos_l);
  if (!(acos_l > 1e-7f)) return false;
  s.wi = wi;
  s.p = q;
  s.infinite = false;
  s.li = emission_;
  s.pdf = dist2 / (acos_l * area_);
  s.delta = false;
  return std::isfinite(s.pdf);
}

float QuadLight::pdf(Vec3 p, Vec3 wi, const SurfaceInteraction* hit) const {
  if (!hit) return 0;
  const float dist2 = length2(hit->p - p);
  const float acos_l = std::fabs(dot(wi, n_));
  if (!two_sided_ && dot(wi, n_) >= 0) return 0;  // seen from behind: sample() never goes there
  if (!(acos_l > 1e-7f)) return 0;
  return dist2 / (acos_l * area_);
}

Rgb QuadLight::emitted(const SurfaceInteraction&, Vec3 wo) const {
  return two_sided_ || dot(wo, n_) > 0 ? emission_ : Rgb();
}

float QuadLight::power(float) const {
  return emission_.luminance() * area_ * kPi * (two_sided_ ? 2.0f : 1.0f);
}

std::shared_ptr<TriangleMesh> QuadLight::make_mesh() const {
  auto m = std::make_shared<TriangleMesh>();
  m->file = "(quad light)";
  m->positions = {corner_, corner_ + eu_, corner_ + eu_ + ev_, corner_ + ev_};
  m->normals.assign(4, n_);
  m->uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m->indices = {0, 1, 2, 0, 2, 3};
  compute_tangents(*m);
  return m;
}

}  // namespace knit::render
