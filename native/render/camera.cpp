#include "render/camera.h"

#include <cmath>

namespace knit::render {

PinholeCamera::PinholeCamera(const CameraDesc& desc, int width, int height)
    : pos_(desc.position), width_(width), height_(height) {
  fwd_ = normalize(desc.look_at - desc.position);
  right_ = normalize(cross(fwd_, desc.up));
  up_ = cross(right_, fwd_);
  tan_half_ = std::tan(radians(desc.fov) * 0.5f);
  aspect_ = static_cast<float>(width) / static_cast<float>(height);
}

Vec3 PinholeCamera::direction(float rx, float ry) const {
  const float sx = (2.0f * rx / static_cast<float>(width_) - 1.0f) * tan_half_ * aspect_;
  const float sy = (1.0f - 2.0f * ry / static_cast<float>(height_)) * tan_half_;
  return normalize(fwd_ + right_ * sx + up_ * sy);
}

RayDifferential PinholeCamera::generate(float raster_x, float raster_y, float diff_scale) const {
  RayDifferential r;
  r.o = pos_;
  r.d = direction(raster_x, raster_y);
  r.has_differentials = true;
  r.diff_scale = diff_scale;
  r.rx_o = pos_;
  r.ry_o = pos_;
  const Vec3 dx = direction(raster_x + 1.0f, raster_y) - r.d;
  r.rx_d = r.d + dx * diff_scale;
  r.ry_d = r.d + (direction(raster_x, raster_y + 1.0f) - r.d) * diff_scale;
  r.cone_spread = length(dx);  // one pixel's angle
  return r;
}

}  // namespace knit::render
