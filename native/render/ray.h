// Rays with optional differentials (Igehy 1999, "Tracing ray differentials"):
// the two offset rays one pixel to the right and one pixel down, carried
// through the path so hit points know their screen-space footprint.
#pragma once

#include <limits>

#include "render/vec.h"

namespace knit {
class FootprintMemo;
}

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
  // The offsets are this many pixels apart (the camera scales them with the
  // sample count; the knit model rescales its footprint to whole pixels).
  float diff_scale = 1.0f;
  // A camera sample's offset from its pixel's centre, in pixels (-0.5 to
  // 0.5), kept through pass-through and specular events with the
  // differentials: the knit model centres a multi-scale footprint at the
  // pixel's centre (KnitDesc::footprint_centre).
  float pixel_dx = 0, pixel_dy = 0;
  // The pixel's memo of its multi-scale footprint boxes (the camera
  // samples of one pixel share them; knit::FootprintMemo), kept with
  // pixel_dx and pixel_dy; null past a bounce.
  knit::FootprintMemo* footprint_memo = nullptr;
  // Past a non-specular bounce, where there are no differentials: the width
  // one pixel's footprint has at ray distance t is about
  // cone_width + t cone_spread (world units), as for a camera ray of the
  // path's length (pbrt-v4 approximates the footprint the same way after
  // such bounces). cone_spread 0: unknown.
  float cone_width = 0, cone_spread = 0;
};

}  // namespace knit::render
