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
  // Normal curvature along x and y in 1/pattern units (> 0 convex), from the
  // triangle under (x, y): constant per triangle (uv_derivatives). Baked
  // frames: 0 (unknown).
  knit::Vec3 curvature(float x, float y) const override;
  // The same, looking first in the triangle of the last lookup made with
  // `hint` (exact mode; a baked image ignores it).
  void frame_near(float x, float y, int64_t& hint, knit::Vec3& t, knit::Vec3& b, knit::Vec3& n) const override;
  knit::Vec3 curvature_near(float x, float y, int64_t& hint) const override;

  // The same in UV, reporting whether uv lies inside a triangle (exact mode)
  // or inside a covered texel (baked mode).
  // `hint` as for frame_near (may be null).
  bool lookup(Vec2 uv, Frame& f, int64_t* hint = nullptr) const;

  float uv_scale() const { return uv_scale_; }
  // Bytes held besides the mesh: the UV grid and per-triangle tables, or the baked image.
  size_t memory_bytes() const;
  bool is_baked() const { return !mesh_; }

 private:
  MeshFrame() = default;
  // Exact mode: the triangle under uv (inside = true) or the nearest one,
  // trying *hint first and keeping the triangle found in it.
  int64_t triangle_at(Vec2 uv, float& b1, float& b2, bool& inside, int64_t* hint) const;
  struct Baked;
  std::shared_ptr<const TriangleMesh> mesh_;
  std::unique_ptr<UvTriangleGrid> grid_;
  std::unique_ptr<Baked> baked_;
  std::vector<Vec2> curvature_;  // per triangle, 1/pattern units (exact mode)
  float uv_scale_ = 1;
};

// Derivatives on one triangle with respect to the UV coordinates: of the
// position and of the (unnormalised, linearly interpolated) vertex normal.
struct UvDerivatives {
  Vec3 dpdu, dpdv, dndu, dndv;
  // Normal curvatures along +u and +v (1 / world units, > 0 convex).
  float curvature_u() const { return dot(dndu, dpdu) / dot(dpdu, dpdu); }
  float curvature_v() const { return dot(dndv, dpdv) / dot(dpdv, dpdv); }
};
// False when the triangle has (almost) no UV area or the mesh has no UVs.
bool uv_derivatives(const TriangleMesh& mesh, size_t tri, UvDerivatives& d);

// Exact frame of `mesh` at barycentrics (b1, b2) of triangle `tri`: the
// interpolated normal, the interpolated tangent orthogonalised against it,
// and b = +-cross(n, t) pointing along +v.
Frame interpolate_frame(const TriangleMesh& mesh, size_t tri, float b1, float b2);

}  // namespace knit::render
