#include "render/yarn_tubes.h"

#include <embree3/rtcore.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "knit/yarns.h"
#include "render/errors.h"
#include "render/material_knit.h"
#include "render/uv_grid.h"

namespace knit::render {

YarnTubes build_yarn_tubes(const TriangleMesh& mesh, const knit::KnitMaterial& model, int samples_per_stitch,
                           size_t max_points) {
  const UvTriangleGrid grid(mesh);
  if (grid.num_triangles() == 0) throw std::runtime_error(mesh.file + ": no triangle has a non-zero UV area");
  const float us = model.params().uv_scale;
  const KnitMeshTables tables = knit_mesh_tables(mesh, us);
  const knit::KnitSurface& surf = model.surface();
  const knit::Pattern& pattern = surf.pattern();
  const double px = surf.period_x(), py = surf.period_y(), top = surf.shell_top();
  const double r = model.params().stitch.r;
  const Vec2 lo = grid.uv_min(), hi = grid.uv_max();
  // Whole pattern repeats covering the UV rectangle.
  const long long tx0 = static_cast<long long>(std::floor(us * double(lo.x) / px));
  const long long tx1 = static_cast<long long>(std::ceil(us * double(hi.x) / px));
  const long long ty0 = static_cast<long long>(std::floor(us * double(lo.y) / py));
  const long long ty1 = static_cast<long long>(std::ceil(us * double(hi.y) / py));
  const long long tiles_u = std::max(1LL, tx1 - tx0), tiles_v = std::max(1LL, ty1 - ty0);
  const double rows = double(pattern.rows()) * double(tiles_v);
  const double points = rows * (double(pattern.cols()) * double(tiles_u) * samples_per_stitch + 1);
  if (points > double(max_points) || tiles_u > 4096 || tiles_v > 4096)
    throw std::runtime_error(mesh.file + ": the explicit yarns would need " + fmt_num(points) +
                             " curve points (" + std::to_string(tiles_u) + " x " + std::to_string(tiles_v) +
                             " pattern repeats), more than the limit of " + std::to_string(max_points) +
                             "; lower uv_scale or explicit_samples");
  const knit::ExplicitYarns ey = knit::explicit_yarns(pattern, model.params().stitch, int(tiles_u), int(tiles_v),
                                                      samples_per_stitch);
  const double ox = double(tx0) * px, oy = double(ty0) * py;
  const long long row0 = ty0 * pattern.rows();  // the tiles' first row, from the pattern's row 0

  YarnTubes out;
  out.vertices.reserve(size_t(points) * 4);
  out.color.reserve(size_t(points));
  out.arc.reserve(size_t(points));
  out.fabric_normal.reserve(size_t(points));
  std::vector<uint32_t> piece_of;  // per point: the piece (polyline) it belongs to
  piece_of.reserve(size_t(points));
  uint32_t piece = 0;
  for (const knit::YarnCurve& c : ey.curves) {
    bool open = false;  // the previous point was kept
    for (size_t i = 0; i < c.points.size(); ++i) {
      const auto& p = c.points[i];
      const Vec2 uv{float((p[0] + ox) / us), float((p[1] + oy) / us)};
      float b1 = 0, b2 = 0;
      const int64_t tri = grid.locate(uv, b1, b2);
      if (tri < 0) {
        open = false;
        continue;
      }
      const size_t t = static_cast<size_t>(tri);
      const uint32_t i0 = mesh.indices[3 * t], i1 = mesh.indices[3 * t + 1], i2 = mesh.indices[3 * t + 2];
      const float b0 = 1 - b1 - b2;
      const Vec3 P = mesh.positions[i0] * b0 + mesh.positions[i1] * b1 + mesh.positions[i2] * b2;
      Vec3 N = mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2;
      const float ln = length(N);
      N = ln > 1e-12f ? N / ln : mesh.normals[i0];
      const double S = tables.triangles[t].pattern_per_world;
      const Vec3 pos = P + N * float((p[2] - top) / S);
      if (!open) ++piece;
      if (open) {
        const uint32_t k = static_cast<uint32_t>(out.num_points() - 1);
        out.segments.push_back(k);
      }
      out.vertices.insert(out.vertices.end(), {pos.x, pos.y, pos.z, float(r / S)});
      out.color.push_back(static_cast<uint8_t>(c.color[i]));
      // The ply's length coordinate, as the model has it at this curve
      // parameter and row (the tiles start at x = ox, and t runs with x;
      // at row ty0 times the pattern's rows).
      out.arc.push_back(model.ply_arc(float(ox + ey.t_step * double(i)), int(row0 + c.row)));
      out.fabric_normal.push_back(N);
      piece_of.push_back(piece);
      open = true;
    }
  }
  // Neighbour flags: whether the segment before / after belongs to the same polyline.
  out.flags.resize(out.segments.size());
  const size_t np = out.num_points();
  for (size_t j = 0; j < out.segments.size(); ++j) {
    const uint32_t k = out.segments[j];
    uint8_t f = 0;
    if (k > 0 && piece_of[k - 1] == piece_of[k]) f |= RTC_CURVE_FLAG_NEIGHBOR_LEFT;
    if (k + 2 < np && piece_of[k + 2] == piece_of[k]) f |= RTC_CURVE_FLAG_NEIGHBOR_RIGHT;
    out.flags[j] = f;
  }
  out.curves = piece;
  return out;
}

}  // namespace knit::render
