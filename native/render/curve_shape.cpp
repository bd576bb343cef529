#include "render/curve_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace knit::render {

CurveShape::CurveShape(std::shared_ptr<const YarnTubes> tubes) : tubes_(std::move(tubes)) {}

unsigned CurveShape::attach(RTCDevice device, RTCScene scene) {
  const YarnTubes& y = *tubes_;
  // Embree 3's round linear curves lose accuracy when the tubes are thin in
  // absolute units: yarns of radius 2e-4 (a real gauge in metres) block
  // 99% of straight-down rays where the same yarns at radius 0.02 block 92%
  // (measured with Embree 3.13 alone; docs/renderer.md). So the tubes are
  // built scaled up to a median radius of about 0.02 in a scene of their
  // own, instanced with the inverse scale: Embree transforms the rays into
  // it, and ray distances stay those of the world.
  std::vector<float> radii;
  radii.reserve(y.num_points());
  for (size_t i = 0; i < y.num_points(); ++i) radii.push_back(y.radius(i));
  float median = 0;
  if (!radii.empty()) {
    std::nth_element(radii.begin(), radii.begin() + long(radii.size() / 2), radii.end());
    median = radii[radii.size() / 2];
  }
  embree_scale_ = median > 0 && std::isfinite(median) ? 0.02f / median : 1.0f;
  scaled_.resize(y.vertices.size());
  for (size_t i = 0; i < y.vertices.size(); ++i) scaled_[i] = y.vertices[i] * embree_scale_;
  RTCScene inner = rtcNewScene(device);
  rtcSetSceneFlags(inner, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneBuildQuality(inner, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_ROUND_LINEAR_CURVE);
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, scaled_.data(), 0,
                             4 * sizeof(float), y.num_points());
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT, y.segments.data(), 0, sizeof(uint32_t),
                             y.segments.size());
  rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_FLAGS, 0, RTC_FORMAT_UCHAR, y.flags.data(), 0, sizeof(uint8_t),
                             y.flags.size());
  rtcCommitGeometry(g);
  rtcAttachGeometry(inner, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(inner);
  RTCGeometry inst = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(inst, inner);
  const float s = 1.0f / embree_scale_;
  const float m[12] = {s, 0, 0, 0, s, 0, 0, 0, s, 0, 0, 0};  // 3x4, column major
  rtcSetGeometryTransform(inst, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, m);
  rtcCommitGeometry(inst);
  const unsigned id = rtcAttachGeometry(scene, inst);
  rtcReleaseGeometry(inst);
  rtcReleaseScene(inner);  // the instance keeps it
  return id;
}

void CurveShape::bounds(Vec3& lo, Vec3& hi) const {
  const float inf = std::numeric_limits<float>::infinity();
  lo = {inf, inf, inf};
  hi = {-inf, -inf, -inf};
  const YarnTubes& y = *tubes_;
  for (size_t i = 0; i < y.num_points(); ++i) {
    const Vec3 r(y.radius(i), y.radius(i), y.radius(i));
    lo = vmin(lo, y.point(i) - r);
    hi = vmax(hi, y.point(i) + r);
  }
}

// Tangent at point `end` (0 or 1) of segment `seg`: central differences
// where the neighbouring segment exists.
Vec3 CurveShape::tangent_at(size_t seg, size_t end) const {
  const YarnTubes& y = *tubes_;
  const size_t k = y.segments[seg] + end;
  const uint8_t f = y.flags[seg];
  const bool has_prev = end == 1 || (f & RTC_CURVE_FLAG_NEIGHBOR_LEFT);
  const bool has_next = end == 0 || (f & RTC_CURVE_FLAG_NEIGHBOR_RIGHT);
  const Vec3 a = has_prev ? y.point(k - 1) : y.point(k);
  const Vec3 b = has_next ? y.point(k + 1) : y.point(k);
  return b - a;
}

void CurveShape::interaction(const RayDifferential& ray, float t, unsigned prim, float u, float,
                             SurfaceInteraction& si) const {
  const YarnTubes& y = *tubes_;
  const size_t k = y.segments[prim];
  const Vec3 p0 = y.point(k), p1 = y.point(k + 1);
  si.t = t;
  si.prim_id = prim;
  si.p = ray.o + ray.d * t;
  // Outward normal: from the closest point of the segment's axis.
  const Vec3 e = p1 - p0;
  const float e2 = length2(e);
  const float w = e2 > 0 ? std::clamp(dot(si.p - p0, e) / e2, 0.0f, 1.0f) : 0.0f;
  Vec3 n = si.p - (p0 + e * w);
  const float ln = length(n);
  n = ln > 0 && std::isfinite(ln) ? n / ln : Frame::from_normal(normalize(e)).t;
  si.ng = n;
  const float s = std::clamp(u, 0.0f, 1.0f);
  Vec3 tan = tangent_at(prim, 0) * (1 - s) + tangent_at(prim, 1) * s;
  if (!(length2(tan) > 0)) tan = e;
  // Shaded smooth: the normal turned perpendicular to the tangent
  // interpolated along the segment. A segment's own normal is perpendicular
  // to its chord and jumps at every point by the curve's turn between
  // points, which moved the glints with explicit_samples (docs/renderer.md,
  // "Tube density"); this one follows the curve's, to second order in the
  // segment's length. The geometric normal stays the segment's.
  const Vec3 th = normalize(tan);
  Vec3 ns = n - th * dot(n, th);
  const float lns = length(ns);
  ns = lns > 1e-4f && std::isfinite(lns) ? ns / lns : n;
  si.shading = Frame::from_normal_tangent(ns, tan);
  si.uv = {s, 0};
  si.has_uv = false;
  si.footprint.valid = false;
  // Shading data for the yarn BSDF.
  const size_t nearest = s < 0.5f ? k : k + 1;
  si.yarn.color = y.color[nearest];
  si.yarn.segment = std::sqrt(e2);
  si.yarn.arc = y.arc[k] * (1 - s) + y.arc[k + 1] * s;
  // Azimuth around the yarn from the fabric normal, as knit::KnitMaterial::shade.
  const Vec3 tt = si.shading.t;
  const Vec3 nf = y.fabric_normal[k] * (1 - s) + y.fabric_normal[k + 1] * s;
  Vec3 ref = nf - tt * dot(nf, tt);
  if (length(ref) < 1e-4f) ref = Frame::from_normal(tt).t;
  ref = normalize(ref);
  si.yarn.phi = std::atan2(dot(ns, cross(tt, ref)), dot(ns, ref));
}

}  // namespace knit::render
