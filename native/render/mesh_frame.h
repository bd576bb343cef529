// MeshFrame: the base mesh's frame (tangent along +u, bitangent along +v,
// normal) at a pattern-space point, for CAPM (knit::FrameProvider).
// Pattern space maps to UV by u = x / uv_scale, v = y / uv_scale.
//
// Two sources: exact lookups on the mesh (UV -> triangle through a UV grid ->
// interpolated normal and tangent), or bilinear lookups in a frame image
// written by `knitshade bake-frames` (docs/renderer.md#baked-frames).
#pragma once

#include <memory>
#include <string>

#include "knit/frame.h"
#include "render/image.h"
#include "render/mesh.h"
#include "render/uv_grid.h"

namespace knit::render {

class MeshFrame final : public knit::FrameProvider {
 public:
  // Exact lookups on `mesh` (which must have UVs); uv_scale > 0.
  MeshFrame(std::shared_ptr<const TriangleMesh> mesh, float uv_scale);
  // Lookups in a baked frame image (EXR written by bake_frames()).
  static std::unique_ptr<MeshFrame> from_baked(const std::string& path, float uv_scale);
  ~MeshFrame() override;

  // FrameProvider: x, y in pattern space; an orthonormal frame in world space.
  // Points outside every UV triangle get the frame of the nearest one.
  void frame(float x, float y, knit::Vec3& t, knit::Vec3& b, knit::Vec3& n) const override;

  // The same in UV, reporting whether uv lies inside a triangle (exact mode)
  // or inside a covered texel (baked mode).
  bool lookup(Vec2 uv, Frame& f) const;

  float uv_scale() const { return uv_scale_; }
  bool is_baked() const { return !mesh_; }

 private:
  MeshFrame() = default;
  struct Baked;
  std::shared_ptr<const TriangleMesh> mesh_;
  std::unique_ptr<UvTriangleGrid> grid_;
  std::unique_ptr<Baked> baked_;
  float uv_scale_ = 1;
};

// Exact frame of `mesh` at barycentrics (b1, b2) of triangle `tri`: the
// interpolated normal, the interpolated tangent orthogonalised against it,
// and b = +-cross(n, t) pointing along +v.
Frame interpolate_frame(const TriangleMesh& mesh, size_t tri, float b1, float b2);

}  // namespace knit::render
