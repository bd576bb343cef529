// Derived mesh attributes: degenerate-triangle removal, smooth normals,
// tangents dP/du, world-space copies.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unordered_map>

#include "render/mesh.h"

namespace knit::render {

void TriangleMesh::bounds(Vec3& lo, Vec3& hi) const {
  const float inf = std::numeric_limits<float>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  for (uint32_t i : indices) {
    lo = vmin(lo, positions[i]);
    hi = vmax(hi, positions[i]);
  }
}

size_t TriangleMesh::memory_bytes() const {
  return positions.size() * sizeof(Vec3) + normals.size() * sizeof(Vec3) + uvs.size() * sizeof(Vec2) +
         tangents.size() * sizeof(Vec3) + tangent_sign.size() * sizeof(float) +
         indices.size() * sizeof(uint32_t);
}

static bool is_degenerate(const TriangleMesh& m, uint32_t a, uint32_t b, uint32_t c) {
  if (a == b || b == c || a == c) return true;
  const Vec3 e1 = m.positions[b] - m.positions[a], e2 = m.positions[c] - m.positions[a];
  const double l1 = length(e1), l2 = length(e2);
  const double area2 = length(cross(e1, e2));
  return !(area2 > 1e-7 * l1 * l2) || !(l1 > 0) || !(l2 > 0);
}

size_t remove_degenerate_triangles(TriangleMesh& mesh, size_t* first) {
  std::vector<uint32_t> kept;
  kept.reserve(mesh.indices.size());
  size_t removed = 0;
  const size_t n = mesh.num_triangles();
  for (size_t t = 0; t < n; ++t) {
    const uint32_t a = mesh.indices[3 * t], b = mesh.indices[3 * t + 1], c = mesh.indices[3 * t + 2];
    if (is_degenerate(mesh, a, b, c)) {
      if (removed == 0 && first) *first = t;
      ++removed;
      continue;
    }
    kept.insert(kept.end(), {a, b, c});
  }
  mesh.indices.swap(kept);
  return removed;
}

namespace {
struct PosKey {
  uint32_t x, y, z;
  bool operator==(const PosKey& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct PosHash {
  size_t operator()(const PosKey& k) const {
    uint64_t h = k.x * 0x9e3779b97f4a7c15ull;
    h ^= (k.y + 0x632be59bd9b4e019ull) + (h << 6) + (h >> 2);
    h ^= (k.z + 0x85ebca77c2b2ae63ull) + (h << 6) + (h >> 2);
    return static_cast<size_t>(h);
  }
};
PosKey key_of(Vec3 p) {
  PosKey k;
  // +0 and -0 are the same position.
  if (p.x == 0) p.x = 0;
  if (p.y == 0) p.y = 0;
  if (p.z == 0) p.z = 0;
  std::memcpy(&k.x, &p.x, 4);
  std::memcpy(&k.y, &p.y, 4);
  std::memcpy(&k.z, &p.z, 4);
  return k;
}

float angle_between(Vec3 a, Vec3 b) {
  const float la = length(a), lb = length(b);
  if (!(la > 0) || !(lb > 0)) return 0;
  const float c = std::clamp(dot(a, b) / (la * lb), -1.0f, 1.0f);
  return std::acos(c);
}
}  // namespace

void compute_smooth_normals(TriangleMesh& mesh) {
  const size_t nv = mesh.positions.size();
  std::unordered_map<PosKey, uint32_t, PosHash> group_of_pos;
  std::vector<uint32_t> group(nv);
  uint32_t groups = 0;
  for (size_t v = 0; v < nv; ++v) {
    auto [it, inserted] = group_of_pos.emplace(key_of(mesh.positions[v]), groups);
    if (inserted) ++groups;
    group[v] = it->second;
  }
  std::vector<Vec3> acc(groups, Vec3(0, 0, 0));
  const size_t nt = mesh.num_triangles();
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t i[3] = {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]};
    const Vec3 p[3] = {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
    const Vec3 fn = normalize(cross(p[1] - p[0], p[2] - p[0]));
    for (int k = 0; k < 3; ++k) {
      const float w = angle_between(p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
      acc[group[i[k]]] += fn * w;
    }
  }
  mesh.normals.assign(nv, Vec3(0, 0, 1));
  for (size_t v = 0; v < nv; ++v) {
    const Vec3 n = acc[group[v]];
    const float l = length(n);
    // A vertex used by no triangle, or whose faces cancel out, keeps +z; it
    // never shades a hit with non-zero barycentric weight in the first case.
    if (l > 1e-20f && std::isfinite(l)) mesh.normals[v] = n / l;
  }
  mesh.normals_from_file = false;
}

void compute_tangents(TriangleMesh& mesh) {
  const size_t nv = mesh.positions.size();
  std::vector<Vec3> su(nv, Vec3(0, 0, 0)), sv(nv, Vec3(0, 0, 0));
  const size_t nt = mesh.num_triangles();
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t i[3] = {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]};
    const Vec3 p0 = mesh.positions[i[0]], e1 = mesh.positions[i[1]] - p0, e2 = mesh.positions[i[2]] - p0;
    const Vec2 t0 = mesh.uvs[i[0]];
    const float du1 = mesh.uvs[i[1]].x - t0.x, dv1 = mesh.uvs[i[1]].y - t0.y;
    const float du2 = mesh.uvs[i[2]].x - t0.x, dv2 = mesh.uvs[i[2]].y - t0.y;
    const float det = du1 * dv2 - dv1 * du2;
    if (!(std::fabs(det) > 1e-20f)) continue;  // no UV area: contributes nothing
    const Vec3 dpdu = (e1 * dv2 - e2 * dv1) / det;
    const Vec3 dpdv = (e2 * du1 - e1 * du2) / det;
    if (!is_finite(dpdu) || !is_finite(dpdv)) continue;
    const Vec3 pp[3] = {mesh.positions[i[0]], mesh.positions[i[1]], mesh.positions[i[2]]};
    for (int k = 0; k < 3; ++k) {
      const float w = angle_between(pp[(k + 1) % 3] - pp[k], pp[(k + 2) % 3] - pp[k]);
      const float lu = length(dpdu), lv = length(dpdv);
      if (lu > 0) su[i[k]] += dpdu * (w / lu);
      if (lv > 0) sv[i[k]] += dpdv * (w / lv);
    }
  }
  mesh.tangents.resize(nv);
  mesh.tangent_sign.resize(nv);
  for (size_t v = 0; v < nv; ++v) {
    const Vec3 n = mesh.normals[v];
    const Frame f = Frame::from_normal_tangent(n, su[v]);
    mesh.tangents[v] = f.t;
    mesh.tangent_sign[v] = dot(cross(n, f.t), sv[v]) < 0 ? -1.0f : 1.0f;
  }
}

TriangleMesh transform_mesh(const TriangleMesh& mesh, const Transform& xf) {
  TriangleMesh out = mesh;
  if (xf.is_identity()) return out;
  for (Vec3& p : out.positions) p = xf.point(p);
  for (Vec3& n : out.normals) n = normalize(xf.normal(n));
  const bool mirror = xf.determinant3() < 0;
  for (size_t v = 0; v < out.tangents.size(); ++v) {
    out.tangents[v] = Frame::from_normal_tangent(out.normals[v], xf.vector(mesh.tangents[v])).t;
    if (mirror) out.tangent_sign[v] = -out.tangent_sign[v];
  }
  if (mirror)
    for (size_t t = 0; t < out.num_triangles(); ++t) std::swap(out.indices[3 * t + 1], out.indices[3 * t + 2]);
  return out;
}

}  // namespace knit::render
