// Point location in UV space: a uniform 2D grid over the UV bounding box,
// each cell listing the triangles whose UV bounds overlap it.
#pragma once

#include <cstdint>
#include <vector>

#include "render/mesh.h"

namespace knit::render {

class UvTriangleGrid {
 public:
  // The mesh must have UVs and outlive the grid. Triangles with no UV area
  // are left out (they cannot contain a point).
  explicit UvTriangleGrid(const TriangleMesh& mesh);

  // A triangle containing `uv` (the first in mesh order when UV islands
  // overlap) and its barycentrics of vertices 1 and 2; -1 if none.
  int64_t locate(Vec2 uv, float& b1, float& b2) const;
  // The triangle whose UV image is closest to `uv`, with the barycentrics of
  // that closest point (inside the triangle); -1 only if the grid is empty
  // or `uv` is not finite (distances are compared in double, so a point
  // 1e30 away still finds its triangle). `inside`, when given, says whether
  // the triangle contains uv (the one locate() returns).
  int64_t nearest(Vec2 uv, float& b1, float& b2, bool* inside = nullptr) const;

  Vec2 uv_min() const { return lo_; }
  Vec2 uv_max() const { return hi_; }
  size_t num_triangles() const { return tri_count_; }
  size_t memory_bytes() const { return (cell_start_.size() + cell_tris_.size()) * sizeof(uint32_t); }
  // Whether triangle `tri` (one locate() can return) contains `uv`, the
  // test locate() makes, with its barycentrics of vertices 1 and 2.
  bool barycentrics(size_t tri, Vec2 uv, float& b1, float& b2) const;

 private:
  void cell_of(Vec2 uv, int& cx, int& cy) const;

  const TriangleMesh& mesh_;
  Vec2 lo_, hi_;
  int nx_ = 1, ny_ = 1;
  float sx_ = 1, sy_ = 1;  // cells per UV unit
  std::vector<uint32_t> cell_start_;  // nx * ny + 1 offsets into cell_tris_
  std::vector<uint32_t> cell_tris_;
  size_t tri_count_ = 0;
};

}  // namespace knit::render
