// FrameProvider: the base-mesh frame at a pattern-space point, for CAPM's ray
// bending. Split out of surface.h so that hosts (the renderer's MeshFrame) can
// implement it without depending on the KnitSurface implementation.
//
// Pattern space (docs/geometry.md): x along the course, y along the wale, z out
// of the fabric, in stitch-curve units. UV maps to pattern space by
// x = uv_scale * u, y = uv_scale * v.
#pragma once

#include <cstdint>

#include "knit/kernel.h"

namespace knit {

using Vec3 = k::kvec3;

// The frame's axes are world directions: t along +x (u), b along +y (v), n the
// surface normal; an orthonormal frame is expected.
class FrameProvider {
 public:
  virtual ~FrameProvider() = default;
  virtual void frame(float x, float y, Vec3& t, Vec3& b, Vec3& n) const = 0;
  // Normal curvature along x and y (1/pattern units, > 0 convex) for CAPM's
  // metric correction and segment length; {0, 0, 0} when unknown.
  virtual Vec3 curvature(float /*x*/, float /*y*/) const { return {0, 0, 0}; }

  // The same for a caller that looks up many points near each other (a CAPM
  // march): `hint` is the caller's, -1 at first (or where the caller knows
  // the points start, e.g. the mesh triangle a ray hit: BaseHit::frame_hint),
  // and a provider may keep in it where the last point was found (a mesh
  // triangle) and look there first; a hint that does not hold the point, or
  // names no place, only costs the ordinary lookup. The result may differ
  // from frame()'s only where the point lies on the border of two places
  // within rounding; it depends on the sequence of lookups made with that
  // hint, never on other threads.
  virtual void frame_near(float x, float y, int64_t& /*hint*/, Vec3& t, Vec3& b, Vec3& n) const {
    frame(x, y, t, b, n);
  }
  virtual Vec3 curvature_near(float x, float y, int64_t& /*hint*/) const { return curvature(x, y); }
  // True when the frame is the same everywhere (a flat base): a march then
  // neither looks it up nor bends the ray.
  virtual bool is_flat() const { return false; }
};

}  // namespace knit
