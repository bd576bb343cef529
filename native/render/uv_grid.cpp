#include "render/uv_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "render/grid_ring.h"

namespace knit::render {

static float uv_area2(Vec2 a, Vec2 b, Vec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

UvTriangleGrid::UvTriangleGrid(const TriangleMesh& mesh) : mesh_(mesh) {
  if (!mesh.has_uvs()) throw std::invalid_argument(mesh.file + ": the mesh has no UV coordinates");
  const size_t nt = mesh.num_triangles();
  const float inf = std::numeric_limits<float>::infinity();
  lo_ = {inf, inf};
  hi_ = {-inf, -inf};
  std::vector<size_t> usable;
  for (size_t t = 0; t < nt; ++t) {
    const Vec2 a = mesh.uvs[mesh.indices[3 * t]], b = mesh.uvs[mesh.indices[3 * t + 1]],
               c = mesh.uvs[mesh.indices[3 * t + 2]];
    if (!(std::fabs(uv_area2(a, b, c)) > 0)) continue;
    usable.push_back(t);
    lo_ = {std::min({lo_.x, a.x, b.x, c.x}), std::min({lo_.y, a.y, b.y, c.y})};
    hi_ = {std::max({hi_.x, a.x, b.x, c.x}), std::max({hi_.y, a.y, b.y, c.y})};
  }
  tri_count_ = usable.size();
  if (usable.empty()) {
    lo_ = hi_ = {0, 0};
    cell_start_.assign(2, 0);
    return;
  }
  const float w = std::max(hi_.x - lo_.x, 1e-12f), h = std::max(hi_.y - lo_.y, 1e-12f);
  // About two triangles per cell, cells roughly square in UV.
  const double cells = std::max(1.0, static_cast<double>(usable.size()) / 2.0);
  nx_ = std::clamp(static_cast<int>(std::sqrt(cells * w / h)), 1, 4096);
  ny_ = std::clamp(static_cast<int>(std::sqrt(cells * h / w)), 1, 4096);
  sx_ = static_cast<float>(nx_) / w;
  sy_ = static_cast<float>(ny_) / h;

  std::vector<uint32_t> count(static_cast<size_t>(nx_) * ny_ + 1, 0);
  auto for_cells = [&](size_t t, auto&& fn) {
    const Vec2 a = mesh.uvs[mesh.indices[3 * t]], b = mesh.uvs[mesh.indices[3 * t + 1]],
               c = mesh.uvs[mesh.indices[3 * t + 2]];
    int x0, y0, x1, y1;
    cell_of({std::min({a.x, b.x, c.x}), std::min({a.y, b.y, c.y})}, x0, y0);
    cell_of({std::max({a.x, b.x, c.x}), std::max({a.y, b.y, c.y})}, x1, y1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) fn(static_cast<size_t>(y) * nx_ + x);
  };
  for (size_t t : usable) for_cells(t, [&](size_t c) { ++count[c + 1]; });
  for (size_t i = 1; i < count.size(); ++i) count[i] += count[i - 1];
  cell_start_ = count;
  cell_tris_.resize(cell_start_.back());
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t t : usable) for_cells(t, [&](size_t c) { cell_tris_[fill[c]++] = static_cast<uint32_t>(t); });
}

void UvTriangleGrid::cell_of(Vec2 uv, int& cx, int& cy) const {
  const float fx = (uv.x - lo_.x) * sx_, fy = (uv.y - lo_.y) * sy_;
  cx = std::isfinite(fx) ? std::clamp(static_cast<int>(std::floor(fx)), 0, nx_ - 1) : 0;
  cy = std::isfinite(fy) ? std::clamp(static_cast<int>(std::floor(fy)), 0, ny_ - 1) : 0;
}

bool UvTriangleGrid::barycentrics(size_t t, Vec2 p, float& b1, float& b2) const {
  const Vec2 a = mesh_.uvs[mesh_.indices[3 * t]], b = mesh_.uvs[mesh_.indices[3 * t + 1]],
             c = mesh_.uvs[mesh_.indices[3 * t + 2]];
  const double area = uv_area2(a, b, c);
  b1 = static_cast<float>(uv_area2(a, p, c) / area);
  b2 = static_cast<float>(uv_area2(a, b, p) / area);
  const float eps = 1e-6f;
  return b1 >= -eps && b2 >= -eps && b1 + b2 <= 1 + eps;
}

int64_t UvTriangleGrid::locate(Vec2 uv, float& b1, float& b2) const {
  if (tri_count_ == 0) return -1;
  const float eps = 1e-6f * std::max(hi_.x - lo_.x, hi_.y - lo_.y);
  if (uv.x < lo_.x - eps || uv.x > hi_.x + eps || uv.y < lo_.y - eps || uv.y > hi_.y + eps) return -1;
  int cx, cy;
  cell_of(uv, cx, cy);
  const size_t c = static_cast<size_t>(cy) * nx_ + cx;
  for (uint32_t i = cell_start_[c]; i < cell_start_[c + 1]; ++i)
    if (barycentrics(cell_tris_[i], uv, b1, b2)) return cell_tris_[i];
  return -1;
}

// Closest point to p on segment [a, b]: parameter in [0, 1]. In double, so
// that a point far outside the charts (UV 1e30, a march at a tiny
// uv_scale) still has a finite squared distance to compare.
static float closest_on_segment(Vec2 p, Vec2 a, Vec2 b, double& d2) {
  const double ex = double(b.x) - a.x, ey = double(b.y) - a.y;
  const double l2 = ex * ex + ey * ey;
  double s = l2 > 0 ? ((double(p.x) - a.x) * ex + (double(p.y) - a.y) * ey) / l2 : 0;
  s = std::clamp(s, 0.0, 1.0);
  const double dx = a.x + s * ex - p.x, dy = a.y + s * ey - p.y;
  d2 = dx * dx + dy * dy;
  return static_cast<float>(s);
}

int64_t UvTriangleGrid::nearest(Vec2 uv, float& b1, float& b2, bool* inside) const {
  if (inside) *inside = false;
  if (tri_count_ == 0) return -1;
  const int64_t in = locate(uv, b1, b2);
  if (in >= 0) {
    if (inside) *inside = true;
    return in;
  }
  if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return -1;
  int cx, cy;
  cell_of(uv, cx, cy);
  // Cell boundaries in double, and a slack that covers cell_of's float
  // rounding: a triangle is listed in every cell its UV bounds overlap, so
  // its point nearest to uv lies in one of its cells grown by the slack.
  const double cw = double(hi_.x - lo_.x) / nx_, ch = double(hi_.y - lo_.y) / ny_;
  const double slack = 1e-4 * std::max(cw, ch) +
                       1e-6 * std::max({std::fabs(double(lo_.x)), std::fabs(double(hi_.x)), std::fabs(double(lo_.y)),
                                        std::fabs(double(hi_.y))});
  const double px = uv.x, py = uv.y;
  // Distance from uv along one axis to cells i0 .. i1 of that axis (the
  // grid's outer cells reaching to infinity), less the slack.
  auto axis_gap = [&](int i0, int i1, int n, double lo, double w, double p) {
    const double a = i0 == 0 ? -HUGE_VAL : lo + i0 * w, b = i1 == n - 1 ? HUGE_VAL : lo + (i1 + 1) * w;
    return std::max(0.0, std::max(a - p, p - b) - slack);
  };
  double best = std::numeric_limits<double>::infinity();
  int64_t best_t = -1;
  const int max_ring = std::max(nx_, ny_);
  for (int ring = 0; ring <= max_ring; ++ring) {
    if (ring > 0) {
      // Every cell of this ring and the ones after it lies beyond one of the
      // sides of the square of rings 0 .. ring - 1 that has cells beyond it,
      // in the columns or rows past that side: the nearest of those bounds
      // their distance from uv.
      const int r = ring - 1;
      double bound = HUGE_VAL;
      if (cx - r - 1 >= 0) bound = std::min(bound, axis_gap(0, cx - r - 1, nx_, lo_.x, cw, px));
      if (cx + r + 1 <= nx_ - 1) bound = std::min(bound, axis_gap(cx + r + 1, nx_ - 1, nx_, lo_.x, cw, px));
      if (cy - r - 1 >= 0) bound = std::min(bound, axis_gap(0, cy - r - 1, ny_, lo_.y, ch, py));
      if (cy + r + 1 <= ny_ - 1) bound = std::min(bound, axis_gap(cy + r + 1, ny_ - 1, ny_, lo_.y, ch, py));
      if (bound == HUGE_VAL) break;  // the square holds the whole grid
      if (best_t >= 0 && bound * bound > best) break;
    }
    int64_t found = -1;  // a triangle that contains uv
    for_each_ring_cell(cx, cy, ring, nx_, ny_, [&](int x, int y) {
      const double gx = axis_gap(x, x, nx_, lo_.x, cw, px), gy = axis_gap(y, y, ny_, lo_.y, ch, py);
      if (best_t >= 0 && gx * gx + gy * gy > best) return false;  // no point of the cell is nearer
      const size_t c = static_cast<size_t>(y) * nx_ + x;
      for (uint32_t i = cell_start_[c]; i < cell_start_[c + 1]; ++i) {
        const size_t t = cell_tris_[i];
        const Vec2 v[3] = {mesh_.uvs[mesh_.indices[3 * t]], mesh_.uvs[mesh_.indices[3 * t + 1]],
                           mesh_.uvs[mesh_.indices[3 * t + 2]]};
        float c1, c2;
        if (barycentrics(t, uv, c1, c2)) {
          b1 = c1;
          b2 = c2;
          found = static_cast<int64_t>(t);
          return true;
        }
        for (int e = 0; e < 3; ++e) {
          double d2;
          const float s = closest_on_segment(uv, v[e], v[(e + 1) % 3], d2);
          if (d2 < best || (d2 == best && static_cast<int64_t>(t) < best_t)) {
            best = d2;
            best_t = static_cast<int64_t>(t);
            // Barycentrics (of vertices 1 and 2) of the point on edge e.
            float w[3] = {0, 0, 0};
            w[e] = 1 - s;
            w[(e + 1) % 3] = s;
            b1 = w[1];
            b2 = w[2];
          }
        }
      }
      return false;
    });
    if (found >= 0) return found;
  }
  return best_t;
}

}  // namespace knit::render
