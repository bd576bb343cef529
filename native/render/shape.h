// A Shape is one Embree geometry plus what turns an Embree hit into a
// SurfaceInteraction. Triangle meshes (and quad lights, as two triangles)
// are shapes now; explicit yarn tubes (RTC_GEOMETRY_TYPE_ROUND_BSPLINE_CURVE
// or ROUND_LINEAR_CURVE) will be another Shape with its own interaction code,
// added to the same Accel with its own material.
#pragma once

#include <embree3/rtcore.h>

#include <cstddef>

#include "render/interaction.h"
#include "render/ray.h"

namespace knit::render {

class Shape {
 public:
  virtual ~Shape() = default;
  // Creates and commits the Embree geometry, attaches it to `scene`, returns its id.
  virtual unsigned attach(RTCDevice device, RTCScene scene) = 0;
  // Fills the geometric part of `si` (p, ng, shading frame, uv, footprint)
  // for a hit on primitive `prim` at Embree's barycentrics (u, v), distance t.
  virtual void interaction(const RayDifferential& ray, float t, unsigned prim, float u, float v,
                           SurfaceInteraction& si) const = 0;
  virtual size_t num_primitives() const = 0;
  virtual void bounds(Vec3& lo, Vec3& hi) const = 0;
};

}  // namespace knit::render
