#include "render/triangle_shape.h"

#include <cmath>
#include <stdexcept>

namespace knit::render {

TriangleShape::TriangleShape(std::shared_ptr<const TriangleMesh> mesh) : mesh_(std::move(mesh)) {}

unsigned TriangleShape::attach(RTCDevice device, RTCScene scene) {
  const TriangleMesh& m = *mesh_;
  vertex_buffer_.assign(m.positions.size() * 3 + 1, 0.0f);
  for (size_t i = 0; i < m.positions.size(); ++i) {
    vertex_buffer_[3 * i] = m.positions[i].x;
    vertex_buffer_[3 * i + 1] = m.positions[i].y;
    vertex_buffer_[3 * i + 2] = m.positions[i].z;
  }
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertex_buffer_.data(), 0,
                             3 * sizeof(float), m.positions.size());
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, m.indices.data(), 0,
                             3 * sizeof(uint32_t), m.num_triangles());
  rtcCommitGeometry(g);
  const unsigned id = rtcAttachGeometry(scene, g);
  rtcReleaseGeometry(g);
  return id;
}

namespace {
// Barycentric coordinates (of vertices 1 and 2) of a point q in the plane of
// the triangle (p0, p0 + e1, p0 + e2); extrapolates outside it.
void plane_barycentrics(Vec3 q, Vec3 p0, Vec3 e1, Vec3 e2, float& c1, float& c2) {
  const Vec3 w = q - p0;
  const double d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
  const double w1 = dot(w, e1), w2 = dot(w, e2);
  const double det = d11 * d22 - d12 * d12;
  c1 = static_cast<float>((d22 * w1 - d12 * w2) / det);
  c2 = static_cast<float>((d11 * w2 - d12 * w1) / det);
}
}  // namespace

void TriangleShape::interaction(const RayDifferential& ray, float t, unsigned prim, float u, float v,
                                SurfaceInteraction& si) const {
  const TriangleMesh& m = *mesh_;
  const uint32_t i0 = m.indices[3 * prim], i1 = m.indices[3 * prim + 1], i2 = m.indices[3 * prim + 2];
  const Vec3 p0 = m.positions[i0], p1 = m.positions[i1], p2 = m.positions[i2];
  const Vec3 e1 = p1 - p0, e2 = p2 - p0;
  const float b0 = 1.0f - u - v;
  si.t = t;
  si.prim_id = prim;
  si.p = p0 * b0 + p1 * u + p2 * v;
  Vec3 ng = normalize(cross(e1, e2));

  auto shading_normal = [&](float c0, float c1, float c2) {
    const Vec3 n = m.normals[i0] * c0 + m.normals[i1] * c1 + m.normals[i2] * c2;
    const float l = length(n);
    return l > 1e-20f && std::isfinite(l) ? n / l : ng;
  };
  const Vec3 ns = shading_normal(b0, u, v);
  if (dot(ng, ns) < 0) ng = -ng;  // the geometric normal follows the shading side
  si.ng = ng;

  if (m.has_uvs()) {
    const Vec2 t0 = m.uvs[i0], t1 = m.uvs[i1], t2 = m.uvs[i2];
    si.uv = {t0.x * b0 + t1.x * u + t2.x * v, t0.y * b0 + t1.y * u + t2.y * v};
    si.has_uv = true;
    const Vec3 tan = m.tangents[i0] * b0 + m.tangents[i1] * u + m.tangents[i2] * v;
    si.shading = Frame::from_normal_tangent(ns, tan);
    const float sign = m.tangent_sign[i0] * b0 + m.tangent_sign[i1] * u + m.tangent_sign[i2] * v;
    if (sign < 0) si.shading.b = -si.shading.b;
  } else {
    si.uv = {u, v};
    si.has_uv = false;
    si.shading = Frame::from_normal(ns);
  }

  si.footprint.valid = false;
  if (!ray.has_differentials) return;
  const Vec3 offs_o[2] = {ray.rx_o, ray.ry_o};
  const Vec3 offs_d[2] = {ray.rx_d, ray.ry_d};
  Vec3 dp[2], dn[2];
  float du[2], dv[2];
  for (int k = 0; k < 2; ++k) {
    const float denom = dot(ng, offs_d[k]);
    if (!(std::fabs(denom) > 1e-8f)) return;
    const float tk = dot(ng, si.p - offs_o[k]) / denom;
    const Vec3 q = offs_o[k] + offs_d[k] * tk;
    if (!is_finite(q)) return;
    dp[k] = q - si.p;
    float c1 = 0, c2 = 0;
    plane_barycentrics(q, p0, e1, e2, c1, c2);
    const float c0 = 1.0f - c1 - c2;
    if (m.has_uvs()) {
      const Vec2 t0 = m.uvs[i0], t1 = m.uvs[i1], t2 = m.uvs[i2];
      du[k] = t0.x * c0 + t1.x * c1 + t2.x * c2 - si.uv.x;
      dv[k] = t0.y * c0 + t1.y * c1 + t2.y * c2 - si.uv.y;
    } else {
      du[k] = c1 - si.uv.x;
      dv[k] = c2 - si.uv.y;
    }
    dn[k] = shading_normal(c0, c1, c2) - ns;
  }
  Footprint& f = si.footprint;
  f.valid = true;
  f.dpdx = dp[0];
  f.dpdy = dp[1];
  f.dudx = du[0];
  f.dvdx = dv[0];
  f.dudy = du[1];
  f.dvdy = dv[1];
  f.dndx = dn[0];
  f.dndy = dn[1];
}

}  // namespace knit::render
