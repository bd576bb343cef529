// Explicit yarns on a mesh: the ground truth the knit model is compared with.
//
// knit::explicit_yarns() gives the exact yarn centre curves in pattern space
// for enough pattern repeats to cover the mesh's UV rectangle. Each point
// (x, y, z) is mapped to UV (x / uv_scale, y / uv_scale), located on the mesh
// (exact lookup through a UV grid) and placed at P + ((z - shell_top) / S) N
// with radius r / S, where P and N are the surface point and its
// interpolated normal and S the triangle's pattern units per world unit (the
// base mesh is the top of the yarn shell, as for the model). Points outside
// the UV domain are dropped and the polylines split there. The result feeds
// one Embree ROUND_LINEAR_CURVE geometry (CurveShape).
#pragma once

#include <cstdint>
#include <vector>

#include "knit/shading.h"
#include "render/mesh.h"

namespace knit::render {

struct YarnTubes {
  // Embree buffers: x, y, z, radius per point (RTC_FORMAT_FLOAT4); the first
  // point of every segment (RTC_FORMAT_UINT); RTC_CURVE_FLAG_NEIGHBOR_* per
  // segment (RTC_FORMAT_UCHAR).
  std::vector<float> vertices;
  std::vector<uint32_t> segments;
  std::vector<uint8_t> flags;
  // Shading data per point: colour index, the ply profile's length
  // coordinate along the yarn (KnitMaterial::ply_arc at the point's curve
  // parameter, pattern units), the base mesh's normal (the reference for the
  // ply azimuth).
  std::vector<uint8_t> color;
  std::vector<float> arc;
  std::vector<Vec3> fabric_normal;
  size_t curves = 0;  // polylines after splitting at the UV domain's border

  size_t num_points() const { return vertices.size() / 4; }
  Vec3 point(size_t i) const { return {vertices[4 * i], vertices[4 * i + 1], vertices[4 * i + 2]}; }
  float radius(size_t i) const { return vertices[4 * i + 3]; }
  // The geometry handed to Embree (vertex, index and flag buffers).
  size_t geometry_bytes() const {
    return vertices.size() * sizeof(float) + segments.size() * sizeof(uint32_t) + flags.size();
  }
  // The per-point shading data.
  size_t shading_bytes() const {
    return color.size() + arc.size() * sizeof(float) + fabric_normal.size() * sizeof(Vec3);
  }
};

// The yarns of `model` over `mesh` (world space, with UVs), with
// `samples_per_stitch` polyline points per stitch. Throws std::runtime_error
// when the mesh has no UV area or the yarns would need more than
// `max_points` points.
YarnTubes build_yarn_tubes(const TriangleMesh& mesh, const knit::KnitMaterial& model, int samples_per_stitch,
                           size_t max_points = 100'000'000);

}  // namespace knit::render
