// Triangle meshes: loading (OBJ, PLY and whatever else assimp reads),
// validation, smooth normals and per-vertex tangents dP/du.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "render/errors.h"
#include "render/transform.h"
#include "render/vec.h"

namespace knit::render {

// A mesh file that cannot be used; what() starts with the file name.
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TriangleMesh {
  std::string file;
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;        // per vertex, unit length (from the file or computed)
  std::vector<Vec2> uvs;            // per vertex; empty when the file has none
  std::vector<Vec3> tangents;       // per vertex, unit, orthogonal to the normal, along +u
  std::vector<float> tangent_sign;  // +1 when cross(n, t) points along +v, else -1
  std::vector<uint32_t> indices;    // 3 per triangle, counter-clockwise = front
  bool normals_from_file = false;
  size_t degenerate_removed = 0;    // triangles dropped at load time

  size_t num_triangles() const { return indices.size() / 3; }
  bool has_uvs() const { return !uvs.empty(); }
  void bounds(Vec3& lo, Vec3& hi) const;
  size_t memory_bytes() const;
};

// Loads every triangle of `path` (node transforms applied), drops degenerate
// triangles (a warning with their count goes to `warnings`), computes smooth
// normals when the file has none and tangents when it has UVs. Throws
// MeshError: unreadable file, no triangles, every triangle degenerate
// (naming the first), NaN/Inf or zero-length data (naming the vertex).
TriangleMesh load_mesh(const std::string& path, Warnings* warnings = nullptr);

// Angle-weighted vertex normals; vertices at the same position share one
// normal (so UV seams do not show as shading seams).
void compute_smooth_normals(TriangleMesh& mesh);
// Per-vertex tangents dP/du (and handedness) from UVs; needs normals and UVs.
void compute_tangents(TriangleMesh& mesh);
// Removes degenerate triangles (repeated vertex, or sin(angle) < 1e-7);
// returns how many were removed, and the index of the first in `first`.
size_t remove_degenerate_triangles(TriangleMesh& mesh, size_t* first = nullptr);

// A copy of `mesh` in world space (points, normals, tangents; winding kept
// consistent with the normals under mirroring transforms).
TriangleMesh transform_mesh(const TriangleMesh& mesh, const Transform& xf);

}  // namespace knit::render
