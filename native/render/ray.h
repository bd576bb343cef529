// Rays with optional differentials (Igehy 1999, "Tracing ray differentials"):
// the two offset rays one pixel to the right and one pixel down, carried
// through the path so hit points know their screen-space footprint.
#pragma once

#include <limits>

#include "render/vec.h"

namespace knit::render {

struct Ray {
  Vec3 o, d;  // d is unit length
  float tmin = 0;
  float tmax = std::numeric_limits<float>::infinity();
};

struct RayDifferential : Ray {
  bool has_differentials = false;
  Vec3 rx_o, rx_d;  // offset ray for x + 1 pixel
  Vec3 ry_o, ry_d;  // offset ray for y + 1 pixel
};

}  // namespace knit::render
