// Explicit yarn tubes as an Embree shape (RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE:
// capped cones joined by spheres, per-point radius), sharing YarnTubes'
// buffers. A hit record carries the outward tube normal as the geometric
// normal (so dot(ray, ng) > 0 means the ray hit the tube from inside), a
// shading frame with x along the yarn (tangents interpolated between
// points) and z the outward normal, and in si.yarn the colour index, the arc
// length along the yarn and the azimuth of the hit around it measured from
// the base mesh's normal (for the ply profile, as the knit model does).
#pragma once

#include <memory>
#include <vector>

#include "render/shape.h"
#include "render/yarn_tubes.h"

namespace knit::render {

class CurveShape final : public Shape {
 public:
  explicit CurveShape(std::shared_ptr<const YarnTubes> tubes);

  unsigned attach(RTCDevice device, RTCScene scene) override;
  void interaction(const RayDifferential& ray, float t, unsigned prim, float u, float v,
                   SurfaceInteraction& si) const override;
  size_t num_primitives() const override { return tubes_->segments.size(); }
  void bounds(Vec3& lo, Vec3& hi) const override;
  const YarnTubes& tubes() const { return *tubes_; }
  // Embree sees the tubes scaled by this factor, inside an instance that
  // scales them back (see attach).
  float embree_scale() const { return embree_scale_; }

 private:
  Vec3 tangent_at(size_t seg, size_t end) const;
  std::shared_ptr<const YarnTubes> tubes_;
  std::vector<float> scaled_;  // the vertices as Embree sees them
  float embree_scale_ = 1;
};

}  // namespace knit::render
