#include "render/mesh_frame.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "render/grid_ring.h"

namespace knit::render {

namespace OIIO = OIIO_NAMESPACE;

struct MeshFrame::Baked {
  int width = 0, height = 0;
  Vec2 uv_min, uv_max;
  std::vector<float> data;  // 8 channels per texel
  const float* texel(int x, int y) const { return &data[(static_cast<size_t>(y) * width + x) * 8]; }
};

Frame interpolate_frame(const TriangleMesh& m, size_t tri, float b1, float b2) {
  const uint32_t i0 = m.indices[3 * tri], i1 = m.indices[3 * tri + 1], i2 = m.indices[3 * tri + 2];
  const float b0 = 1 - b1 - b2;
  Vec3 n = m.normals[i0] * b0 + m.normals[i1] * b1 + m.normals[i2] * b2;
  const float l = length(n);
  if (!(l > 1e-20f)) {
    n = normalize(cross(m.positions[i1] - m.positions[i0], m.positions[i2] - m.positions[i0]));
  } else {
    n = n / l;
  }
  Frame f;
  if (m.has_uvs() && !m.tangents.empty()) {
    const Vec3 t = m.tangents[i0] * b0 + m.tangents[i1] * b1 + m.tangents[i2] * b2;
    f = Frame::from_normal_tangent(n, t);
    const float s = m.tangent_sign[i0] * b0 + m.tangent_sign[i1] * b1 + m.tangent_sign[i2] * b2;
    if (s < 0) f.b = -f.b;
  } else {
    f = Frame::from_normal(n);
  }
  return f;
}

bool uv_derivatives(const TriangleMesh& m, size_t tri, UvDerivatives& d) {
  if (!m.has_uvs()) return false;
  const uint32_t i0 = m.indices[3 * tri], i1 = m.indices[3 * tri + 1], i2 = m.indices[3 * tri + 2];
  const Vec2 t0 = m.uvs[i0], t1 = m.uvs[i1], t2 = m.uvs[i2];
  const double du1 = double(t1.x) - t0.x, dv1 = double(t1.y) - t0.y;
  const double du2 = double(t2.x) - t0.x, dv2 = double(t2.y) - t0.y;
  const double det = du1 * dv2 - du2 * dv1;
  const Vec3 e1 = m.positions[i1] - m.positions[i0], e2 = m.positions[i2] - m.positions[i0];
  const double scale = std::max(length2(e1), length2(e2));
  if (!(std::fabs(det) > 1e-12) || !(scale > 0)) return false;
  const float a = float(dv2 / det), b = float(-dv1 / det), c = float(-du2 / det), e = float(du1 / det);
  d.dpdu = e1 * a + e2 * b;
  d.dpdv = e1 * c + e2 * e;
  const Vec3 n1 = m.normals[i1] - m.normals[i0], n2 = m.normals[i2] - m.normals[i0];
  d.dndu = n1 * a + n2 * b;
  d.dndv = n1 * c + n2 * e;
  return is_finite(d.dpdu) && is_finite(d.dpdv) && length2(d.dpdu) > 0 && length2(d.dpdv) > 0;
}

MeshFrame::MeshFrame(std::shared_ptr<const TriangleMesh> mesh, float uv_scale)
    : mesh_(std::move(mesh)), uv_scale_(uv_scale) {
  if (!(uv_scale > 0) || !std::isfinite(uv_scale))
    throw std::invalid_argument("MeshFrame: uv_scale must be finite and > 0");
  if (!mesh_->has_uvs()) throw std::invalid_argument(mesh_->file + ": MeshFrame needs a mesh with UVs");
  grid_ = std::make_unique<UvTriangleGrid>(*mesh_);
  if (grid_->num_triangles() == 0)
    throw std::invalid_argument(mesh_->file + ": no triangle has a non-zero UV area");
  curvature_.resize(mesh_->num_triangles());
  for (size_t i = 0; i < curvature_.size(); ++i) {
    UvDerivatives d;
    if (!uv_derivatives(*mesh_, i, d)) continue;
    // Per pattern unit: a pattern unit along x is |dP/du| / uv_scale world units.
    curvature_[i] = {d.curvature_u() * length(d.dpdu) / uv_scale_, d.curvature_v() * length(d.dpdv) / uv_scale_};
    if (!std::isfinite(curvature_[i].x) || !std::isfinite(curvature_[i].y)) curvature_[i] = {0, 0};
  }
}

size_t MeshFrame::memory_bytes() const {
  size_t b = curvature_.size() * sizeof(Vec2);
  if (grid_) b += grid_->memory_bytes();
  if (baked_) b += baked_->data.size() * sizeof(float);
  return b;
}

int64_t MeshFrame::triangle_at(Vec2 uv, float& b1, float& b2, bool& inside, int64_t* hint) const {
  // A march's lookups mostly stay in one triangle: try the last one first.
  if (hint && *hint >= 0 && static_cast<size_t>(*hint) < mesh_->num_triangles() &&
      grid_->barycentrics(static_cast<size_t>(*hint), uv, b1, b2)) {
    inside = true;
    return *hint;
  }
  const int64_t tri = grid_->nearest(uv, b1, b2, &inside);
  if (inside && hint) *hint = tri;
  return tri;
}

knit::Vec3 MeshFrame::curvature_near(float x, float y, int64_t& hint) const {
  if (!mesh_) return knit::k::kv3(0, 0, 0);
  float b1 = 0, b2 = 0;
  bool inside = false;
  const int64_t tri = triangle_at({x / uv_scale_, y / uv_scale_}, b1, b2, inside, &hint);
  if (tri < 0) return knit::k::kv3(0, 0, 0);
  const Vec2 k = curvature_[static_cast<size_t>(tri)];
  return knit::k::kv3(k.x, k.y, 0);
}

knit::Vec3 MeshFrame::curvature(float x, float y) const {
  int64_t hint = -1;
  return curvature_near(x, y, hint);
}

MeshFrame::~MeshFrame() = default;

std::unique_ptr<MeshFrame> MeshFrame::from_baked(const std::string& path, float uv_scale) {
  if (!(uv_scale > 0) || !std::isfinite(uv_scale))
    throw std::invalid_argument("MeshFrame: uv_scale must be finite and > 0");
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(path + ": cannot read frame image: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  // EXR stores channels sorted by name; find ours by name.
  const char* expected[8] = {"N.X", "N.Y", "N.Z", "T.X", "T.Y", "T.Z", "B.sign", "A"};
  if (spec.nchannels != 8) throw std::runtime_error(path + ": not a baked frame image (need 8 channels)");
  int index[8];
  for (int c = 0; c < 8; ++c) {
    index[c] = -1;
    for (int k = 0; k < 8; ++k)
      if (spec.channel_name(k) == expected[c]) index[c] = k;
    if (index[c] < 0)
      throw std::runtime_error(path + ": not a baked frame image (no channel '" + expected[c] + "')");
  }
  // Two floats; EXR may hand them back as a float[2] or as a V2f.
  auto two_floats = [&](const char* name) {
    const OIIO::ParamValue* p = spec.find_attribute(name);
    if (!p || p->type().basetype != OIIO::TypeDesc::FLOAT || p->type().basevalues() != 2)
      throw std::runtime_error(path + ": missing or malformed " + name + " metadata");
    return p;
  };
  const OIIO::ParamValue* lo = two_floats("knitshade:uv_min");
  const OIIO::ParamValue* hi = two_floats("knitshade:uv_max");
  auto baked = std::make_unique<Baked>();
  baked->width = spec.width;
  baked->height = spec.height;
  const float* plo = static_cast<const float*>(lo->data());
  const float* phi = static_cast<const float*>(hi->data());
  baked->uv_min = {plo[0], plo[1]};
  baked->uv_max = {phi[0], phi[1]};
  if (!(baked->uv_max.x > baked->uv_min.x) || !(baked->uv_max.y > baked->uv_min.y))
    throw std::runtime_error(path + ": empty UV rectangle in the metadata");
  const size_t texels = static_cast<size_t>(spec.width) * spec.height;
  std::vector<float> raw(texels * 8);
  if (!in->read_image(0, 0, 0, 8, OIIO::TypeDesc::FLOAT, raw.data()))
    throw std::runtime_error(path + ": cannot read frame image: " + in->geterror());
  baked->data.resize(texels * 8);
  for (size_t i = 0; i < texels; ++i)
    for (int c = 0; c < 8; ++c) baked->data[i * 8 + c] = raw[i * 8 + index[c]];
  for (float v : baked->data)
    if (!std::isfinite(v)) throw std::runtime_error(path + ": the frame image holds non-finite values");
  std::unique_ptr<MeshFrame> f(new MeshFrame());
  f->baked_ = std::move(baked);
  f->uv_scale_ = uv_scale;
  return f;
}

bool MeshFrame::lookup(Vec2 uv, Frame& f, int64_t* hint) const {
  if (mesh_) {
    float b1 = 0, b2 = 0;
    bool inside = false;
    const int64_t tri = triangle_at(uv, b1, b2, inside, hint);
    if (tri < 0) {  // a non-finite UV: no triangle is nearest
      f = Frame();
      return false;
    }
    f = interpolate_frame(*mesh_, static_cast<size_t>(tri), b1, b2);
    return inside;
  }
  const Baked& bk = *baked_;
  const float fx = (uv.x - bk.uv_min.x) / (bk.uv_max.x - bk.uv_min.x) * static_cast<float>(bk.width) - 0.5f;
  const float fy = (bk.uv_max.y - uv.y) / (bk.uv_max.y - bk.uv_min.y) * static_cast<float>(bk.height) - 0.5f;
  const int x0 = static_cast<int>(std::floor(fx)), y0 = static_cast<int>(std::floor(fy));
  const float tx = fx - static_cast<float>(x0), ty = fy - static_cast<float>(y0);
  Vec3 n(0, 0, 0), t(0, 0, 0);
  float sign = 0, wsum = 0;
  for (int k = 0; k < 4; ++k) {
    const int x = std::clamp(x0 + (k & 1), 0, bk.width - 1), y = std::clamp(y0 + (k >> 1), 0, bk.height - 1);
    const float w = ((k & 1) ? tx : 1 - tx) * ((k >> 1) ? ty : 1 - ty);
    const float* p = bk.texel(x, y);
    if (!(p[7] > 0) || !(w > 0)) continue;
    n += Vec3(p[0], p[1], p[2]) * w;
    t += Vec3(p[3], p[4], p[5]) * w;
    sign += p[6] * w;
    wsum += w;
  }
  bool ok = wsum > 0;
  if (!ok) {
    // Outside every chart: the nearest covered texel, searched in rings.
    const int cx = std::clamp(static_cast<int>(std::lround(fx)), 0, bk.width - 1);
    const int cy = std::clamp(static_cast<int>(std::lround(fy)), 0, bk.height - 1);
    const int rmax = std::max(bk.width, bk.height);
    for (int r = 1; r <= rmax && !(wsum > 0); ++r)
      for_each_ring_cell(cx, cy, r, bk.width, bk.height, [&](int x, int y) {
        const float* p = bk.texel(x, y);
        if (!(p[7] > 0)) return false;
        n = {p[0], p[1], p[2]};
        t = {p[3], p[4], p[5]};
        sign = p[6];
        wsum = 1;
        return true;
      });
  }
  if (!(length(n) > 1e-20f)) n = {0, 0, 1};
  f = Frame::from_normal_tangent(normalize(n), t);
  if (sign < 0) f.b = -f.b;
  return ok;
}

void MeshFrame::frame(float x, float y, knit::Vec3& t, knit::Vec3& b, knit::Vec3& n) const {
  int64_t hint = -1;
  frame_near(x, y, hint, t, b, n);
}

void MeshFrame::frame_near(float x, float y, int64_t& hint, knit::Vec3& t, knit::Vec3& b, knit::Vec3& n) const {
  Frame f;
  lookup({x / uv_scale_, y / uv_scale_}, f, &hint);
  t = knit::k::kv3(f.t.x, f.t.y, f.t.z);
  b = knit::k::kv3(f.b.x, f.b.y, f.b.z);
  n = knit::k::kv3(f.n.x, f.n.y, f.n.z);
}

}  // namespace knit::render
