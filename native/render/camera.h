// The pinhole camera: raster position -> primary ray with differentials.
#pragma once

#include "render/ray.h"
#include "render/scene_desc.h"

namespace knit::render {

class PinholeCamera {
 public:
  PinholeCamera(const CameraDesc& desc, int width, int height);

  // Raster coordinates: x in [0, width) to the right, y in [0, height) down;
  // pixel (i, j) covers [i, i+1) x [j, j+1). The differential offset rays are
  // `diff_scale` pixels away (the renderer uses max(1/8, 1/sqrt(spp)), so a
  // footprint covers one sample's share of the pixel, as in pbrt-v4).
  RayDifferential generate(float raster_x, float raster_y, float diff_scale = 1.0f) const;

  Vec3 position() const { return pos_; }
  Vec3 forward() const { return fwd_; }

 private:
  Vec3 direction(float raster_x, float raster_y) const;
  Vec3 pos_, fwd_, right_, up_;
  float tan_half_ = 0, aspect_ = 1;
  int width_ = 1, height_ = 1;
};

}  // namespace knit::render
