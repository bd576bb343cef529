// KnitSurface: the host side of the analytic stitch queries and CAPM.
#include "knit/surface.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace knit {

void FlatFrame::frame(float, float, Vec3& t, Vec3& b, Vec3& n) const {
  t = {1, 0, 0};
  b = {0, 1, 0};
  n = {0, 0, 1};
}

void CylinderFrame::frame(float x, float, Vec3& t, Vec3& b, Vec3& n) const {
  const float phi = x / radius_;
  const float s = std::sin(phi), c = std::cos(phi);
  t = {c, 0, -s};
  b = {0, 1, 0};
  n = {s, 0, c};
}

void SphereFrame::frame(float x, float y, Vec3& t, Vec3& b, Vec3& n) const {
  const float lon = x / radius_, lat = y / radius_;
  const float sl = std::sin(lon), cl = std::cos(lon), sb = std::sin(lat), cb = std::cos(lat);
  n = {cb * sl, sb, cb * cl};
  t = {cl, 0, -sl};
  b = {-sb * sl, cb, -sb * cl};
}

KnitSurface::KnitSurface(Pattern pattern, StitchParams params)
    : pattern_(std::move(pattern)), params_(params) {
  params_.validate();
  const bool floats = pattern_.uses(Stitch::Front) || pattern_.uses(Stitch::Back);
  geom_ = k::knit_geom_make(params_.a, params_.h, params_.d, params_.r, pattern_.rows(),
                            pattern_.cols(), floats ? 1 : 0);
  if (!floats) {
    // Each cell's span of three (the kernel's knit_span: the cells left of,
    // at and right of it, with their depth signs), 3 bits a cell, set for
    // purl.
    const auto purl_bits = [](const k::KCell& c) {
      return unsigned(c.sg.x < 0 ? 1 : 0) | unsigned(c.sg.y < 0 ? 2 : 0) | unsigned(c.sg.z < 0 ? 4 : 0);
    };
    const int rows = pattern_.rows(), cols = pattern_.cols();
    span_bits_.assign(size_t(rows) * size_t(cols) + 1, 0);  // (+1: padding for the 32-bit gathers)
    for (int pr = 0; pr < rows; ++pr) {
      const k::KRow rw = k::knit_row(geom_, rows - 1 - pr);  // codes row pr (written top first)
      for (int cm = 0; cm < cols; ++cm) {
        const k::KSpan sp = k::knit_span(geom_, codes(), rw, cm);
        span_bits_[size_t(rw.off) + size_t(cm)] =
            uint16_t(purl_bits(sp.left) | (purl_bits(sp.mid) << 3) | (purl_bits(sp.right) << 6));
      }
    }
  }
}

float KnitSurface::shell_top() const { return geom_.shell_top; }
float KnitSurface::cell_width() const { return 6.28318530717958647692f; }
float KnitSurface::cell_height() const { return geom_.row_spacing; }
float KnitSurface::period_x() const { return cell_width() * float(pattern_.cols()); }
float KnitSurface::period_y() const { return cell_height() * float(pattern_.rows()); }

static TubeCrossing to_crossing(const k::KnitLineHit& h) {
  TubeCrossing c;
  c.s_in = h.s_in;
  c.s_out = h.s_out;
  c.p_in = h.p;
  c.normal = h.n;
  c.tangent = h.tangent;
  c.row = h.row;
  c.col = h.col;
  c.stitch = h.code;
  c.color = h.colour;
  c.layer = ((h.row % 2) + 2) % 2;
  c.t = h.t;
  return c;
}

std::vector<TubeCrossing> KnitSurface::crossings(float x, float y) const {
  std::vector<TubeCrossing> out;
  const float top = geom_.shell_top + 0.01f;
  const Vec3 o = k::kv3(x, y, top), D = k::kv3(0, 0, -1);
  float s_min = 0;
  for (int guard = 0; guard < 16; ++guard) {
    k::KnitLineHit h = k::knit_line_query(geom_, codes(), colors(), o, D, s_min, 2 * top, KNIT_QUERY_EXIT);
    if (!h.hit) break;
    out.push_back(to_crossing(h));
    s_min = h.s_in + 1e-4f;
  }
  return out;
}

// The yarn-hit fields of a SurfaceHit from the kernel's line hit.
static SurfaceHit from_line_hit(const k::KnitLineHit& h) {
  SurfaceHit s;
  s.hit = h.hit != 0;
  if (s.hit) {
    s.position = h.p;
    s.normal = h.n;
    s.tangent = h.tangent;
    s.row = h.row;
    s.col = h.col;
    s.stitch = h.code;
    s.color = h.colour;
  }
  return s;
}

SurfaceHit KnitSurface::query(float x, float y) const {
  const k::KnitLineHit h = k::knit_vertical_query(geom_, codes(), colors(), x, y);
  SurfaceHit s = from_line_hit(h);
  s.layers = h.crossings;
  return s;
}

SurfaceHit KnitSurface::capm(float x, float y, Vec3 wi_local, const FrameProvider* frame,
                             const CapmOptions& opt) const {
  static const FlatFrame flat_frame;
  const FrameProvider& fp = frame ? *frame : flat_frame;
  Vec3 t, b, n;
  fp.frame(x, y, t, b, n);
  const Vec3 wi = k::kv3_normalize(wi_local);
  const Vec3 ray_world = k::kv3_neg(k::kv3_from_local(wi, t, b, n));
  return to_hit(march(k::knit_capm_start(geom_, x, y, wi), ray_world, frame, opt));
}

k::KnitCapm KnitSurface::march(k::KnitCapm start, Vec3 ray_world, const FrameProvider* frame,
                               const CapmOptions& opt, bool blocked_only, int64_t frame_hint) const {
  static const FlatFrame flat_frame;
  const FrameProvider& fp = frame ? *frame : flat_frame;
  if (!(opt.max_steps >= 1) || !capm_segment_in_range(opt.max_segment) || !(opt.max_bend > 0))
    throw std::invalid_argument("CapmOptions: max_steps must be >= 1, max_segment in (0, " +
                                std::to_string(int(kMaxCapmSegment)) + "] and max_bend > 0");
  int64_t hint = frame_hint;  // the march's lookups stay close together (and near the base hit)
  const Vec3 kappa = fp.curvature_near(start.p.x, start.p.y, hint);
  const float kmax = std::max(std::abs(kappa.x), std::abs(kappa.y));
  const float seg = kmax > 0 ? std::min(opt.max_segment, opt.max_bend / kmax) : opt.max_segment;
  const bool flat = fp.is_flat();
  Vec3 t, b, n;
  k::KnitCapm st = start;
  // The start's direction (the caller's, in the frame where the ray met the
  // base) only places the first segment's midpoint, where the frame is
  // fetched and the segment aimed, as knit_capm_march_curved does.
  while (st.state == KNIT_CAPM_MARCHING) {
    if (!flat) {  // midpoint rule: aim the segment with the frame at its middle
      const Vec3 m = k::knit_capm_midpoint(geom_, st, seg);
      fp.frame_near(m.x, m.y, hint, t, b, n);
      st = k::knit_capm_aim(st, k::kv3_to_local(ray_world, t, b, n));
    }
    const k::KnitCapm before = st;
    st = k::knit_capm_step(geom_, codes(), colors(), st, seg, opt.max_steps, kappa.x, kappa.y, blocked_only ? 1 : 0);
    if (st.state == KNIT_CAPM_HIT && !flat && !blocked_only) {
      const Vec3 m = k::knit_capm_hit_midpoint(before, st);
      fp.frame_near(m.x, m.y, hint, t, b, n);
      st = k::knit_capm_correct(geom_, codes(), colors(), before, st, k::kv3_to_local(ray_world, t, b, n),
                                seg, kappa.x, kappa.y);
    }
    if (st.state != KNIT_CAPM_MARCHING || flat) continue;
    fp.frame_near(st.p.x, st.p.y, hint, t, b, n);
    st = k::knit_capm_bend(geom_, st, k::kv3_to_local(ray_world, t, b, n));
  }
  return st;
}

SurfaceHit KnitSurface::to_hit(const k::KnitCapm& st) const {
  SurfaceHit s;
  if (st.state == KNIT_CAPM_HIT) {
    s = from_line_hit(st.hit);
    s.layers = k::knit_vertical_layers(geom_, codes(), colors(), st.hit.p.x, st.hit.p.y);
  }
  s.steps = st.steps;
  return s;
}

}  // namespace knit
