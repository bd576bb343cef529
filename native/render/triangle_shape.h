// Triangle mesh shape for Embree (RTC_GEOMETRY_TYPE_TRIANGLE), sharing the
// mesh's own vertex and index arrays.
#pragma once

#include <memory>

#include "render/mesh.h"
#include "render/shape.h"

namespace knit::render {

class TriangleShape final : public Shape {
 public:
  explicit TriangleShape(std::shared_ptr<const TriangleMesh> mesh);

  unsigned attach(RTCDevice device, RTCScene scene) override;
  void interaction(const RayDifferential& ray, float t, unsigned prim, float u, float v,
                   SurfaceInteraction& si) const override;
  size_t num_primitives() const override { return mesh_->num_triangles(); }
  void bounds(Vec3& lo, Vec3& hi) const override { mesh_->bounds(lo, hi); }
  const TriangleMesh& mesh() const { return *mesh_; }

 private:
  std::shared_ptr<const TriangleMesh> mesh_;
  std::vector<float> vertex_buffer_;  // xyz per vertex + 1 float of padding for Embree's SSE loads
};

}  // namespace knit::render
