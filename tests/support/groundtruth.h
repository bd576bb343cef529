// Model-versus-explicit-yarn comparisons shared by the ground-truth tests:
// a knit surface and the same pattern's explicit tubes over a flat patch or
// a cylinder, view rays through both, and error statistics.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "knit/surface.h"
#include "knit/yarns.h"
#include "tube_raycast.h"

namespace knit::test {

constexpr double kPiD = 3.14159265358979323846;

// Where the knit surface lives: flat (radius 0) or a cylinder of radius R
// around the y axis, x being arc length at the yarn centre surface z = 0.
struct Base {
  double radius = 0;
  D3 world(double x, double y, double z) const {
    if (radius <= 0) return {x, y, z};
    const double phi = x / radius;
    return {(radius + z) * std::sin(phi), y, (radius + z) * std::cos(phi)};
  }
  void frame(double x, D3& t, D3& b, D3& n) const {
    const double phi = radius > 0 ? x / radius : 0;
    t = {std::cos(phi), 0, -std::sin(phi)};
    b = {0, 1, 0};
    n = {std::sin(phi), 0, std::cos(phi)};
  }
};

struct GroundTruthScene {
  Base base;
  KnitSurface surface;
  TubeScene tubes;
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // window of entry points (pattern space)

  GroundTruthScene(const Pattern& p, const StitchParams& sp, double radius, double margin,
                   int samples_per_stitch = 256)
      : surface(p, sp) {
    base.radius = radius;
    const double px = surface.period_x(), py = surface.period_y();
    // Flat: the window covers a whole pattern repeat. Cylinder: 4 stitches
    // (the tiled yarns must not wrap around into themselves).
    const double wx = radius > 0 ? 4 * 2 * kPiD : std::max(px, 4 * 2 * kPiD);
    const double wy = std::max(py, 8.0 * sp.row_spacing());
    x0 = std::ceil(margin / px) * px;
    y0 = std::ceil(margin / py) * py;
    x1 = x0 + wx;
    y1 = y0 + wy;
    const int tu = int(std::ceil((x1 + margin) / px)), tv = int(std::ceil((y1 + margin) / py));
    if (radius > 0 && tu * px >= 2 * kPiD * radius)
      throw std::invalid_argument("ground truth: tiled yarns would wrap around the cylinder");
    ExplicitYarns y = explicit_yarns(p, sp, tu, tv, samples_per_stitch);
    for (const YarnCurve& c : y.curves) {
      std::vector<D3> pts;
      pts.reserve(c.points.size());
      for (const auto& q : c.points) pts.push_back(base.world(q[0], q[1], q[2]));
      tubes.add_curve(std::move(pts), y.radius);
    }
    tubes.build();
  }

  // Ray entering the shell at pattern (x, y) along -wi_local: world origin and direction.
  void entry_ray(double x, double y, const D3& wi_local, D3& o, D3& d) const {
    D3 t, b, n;
    base.frame(x, t, b, n);
    o = base.world(x, y, surface.shell_top());
    d = mul(add(add(mul(t, wi_local[0]), mul(b, wi_local[1])), mul(n, wi_local[2])), -1.0);
  }

  // Largest ray distance that stays inside the shell |z| <= shell_top.
  double shell_exit(const D3& o, const D3& d) const {
    const double top = surface.shell_top();
    if (base.radius <= 0) return d[2] < 0 ? (o[2] + top) / -d[2] : 0.0;
    // Inner cylinder first, else the outer one on the way out.
    auto hit = [&](double R, bool far) {
      const double A = d[0] * d[0] + d[2] * d[2], B = 2 * (o[0] * d[0] + o[2] * d[2]),
                   C = o[0] * o[0] + o[2] * o[2] - R * R;
      const double disc = B * B - 4 * A * C;
      if (disc < 0 || A <= 0) return -1.0;
      const double s = std::sqrt(disc);
      return far ? (-B + s) / (2 * A) : (-B - s) / (2 * A);
    };
    double tin = hit(base.radius - top, false);
    if (tin > 0) return tin;
    return std::max(0.0, hit(base.radius + top, true));
  }
};

struct Stats {
  long rays = 0, edge = 0, agree = 0, both_hit = 0, same_row = 0;
  long model_only = 0, truth_only = 0;
  std::vector<double> pos_err, normal_err;  // pos in units of r, normal in degrees
  long steps_sum = 0;
  int steps_max = 0;
  long steps_n = 0;

  double agreement() const { return rays - edge > 0 ? double(agree) / double(rays - edge) : 1.0; }
  static double mean(const std::vector<double>& v) {
    double s = 0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
  }
  static double pct(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
  }
  static double maxv(const std::vector<double>& v) {
    return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  }
  static long over(const std::vector<double>& v, double x) {
    return long(std::count_if(v.begin(), v.end(), [x](double e) { return e > x; }));
  }
  void merge(const Stats& o) {
    rays += o.rays;
    edge += o.edge;
    agree += o.agree;
    both_hit += o.both_hit;
    same_row += o.same_row;
    model_only += o.model_only;
    truth_only += o.truth_only;
    pos_err.insert(pos_err.end(), o.pos_err.begin(), o.pos_err.end());
    normal_err.insert(normal_err.end(), o.normal_err.begin(), o.normal_err.end());
    steps_sum += o.steps_sum;
    steps_n += o.steps_n;
    steps_max = std::max(steps_max, o.steps_max);
  }
  std::string line() const {
    char buf[512];
    std::snprintf(buf, sizeof buf,
                  "rays %5ld edge %4ld agree %7.3f%% (model-only %ld, truth-only %ld) | pos/r mean %.4f "
                  "p95 %.4f max %.3f, over 0.01 r %ld | normal deg mean %.3f p95 %.3f max %.2f | steps mean %.2f max %d",
                  rays, edge, 100 * agreement(), model_only, truth_only, mean(pos_err), pct(pos_err, 0.95),
                  maxv(pos_err), over(pos_err, 0.01), mean(normal_err), pct(normal_err, 0.95), maxv(normal_err),
                  steps_n ? double(steps_sum) / double(steps_n) : 0.0, steps_max);
    return buf;
  }
};

inline double angle_deg(const D3& a, const D3& b) {
  const double c = std::clamp(dot(normalized(a), normalized(b)), -1.0, 1.0);
  return std::acos(c) * 180.0 / kPiD;
}

// Compares CAPM with explicit-tube ray casts for rays entering at random
// points of the window at polar angle theta (degrees) from the normal.
// A ray is an "edge" ray when the ground truth changes (hit/miss or which
// yarn) under an offset of `edge_eps` * r of its entry point.
inline Stats compare_capm(const GroundTruthScene& sc, double theta_deg, int n, unsigned seed,
                          const CapmOptions& opt, double edge_eps = 0.03) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const double r = sc.surface.params().r;
  const double th = theta_deg * kPiD / 180;
  CylinderFrame cyl(float(sc.base.radius > 0 ? sc.base.radius : 1));
  const FrameProvider* fp = sc.base.radius > 0 ? static_cast<const FrameProvider*>(&cyl) : nullptr;
  Stats st;
  for (int i = 0; i < n; ++i) {
    const double x = sc.x0 + (sc.x1 - sc.x0) * U(rng), y = sc.y0 + (sc.y1 - sc.y0) * U(rng);
    const double ph = 2 * kPiD * U(rng);
    const D3 wi = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
    D3 o, d;
    sc.entry_ray(x, y, wi, o, d);
    const double tmax = sc.shell_exit(o, d);
    const TubeHit gt = sc.tubes.intersect(o, d, 0.0, tmax);
    ++st.rays;
    bool edge = false;
    const double e = edge_eps * r;
    const double offs[4][2] = {{e, 0}, {-e, 0}, {0, e}, {0, -e}};
    for (const auto& of : offs) {
      D3 o2, d2;
      sc.entry_ray(x + of[0], y + of[1], wi, o2, d2);
      const TubeHit g2 = sc.tubes.intersect(o2, d2, 0.0, sc.shell_exit(o2, d2));
      if (g2.hit != gt.hit || (gt.hit && g2.curve != gt.curve)) edge = true;
    }
    const SurfaceHit m = sc.surface.capm(float(x), float(y), k::kv3(float(wi[0]), float(wi[1]), float(wi[2])),
                                         fp, opt);
    st.steps_sum += m.steps;
    st.steps_n += 1;
    st.steps_max = std::max(st.steps_max, m.steps);
    if (edge) {
      ++st.edge;
      continue;
    }
    if (m.hit == gt.hit) ++st.agree;
    else if (m.hit) ++st.model_only;
    else ++st.truth_only;
    if (m.hit && gt.hit) {
      ++st.both_hit;
      if (m.row == gt.curve) ++st.same_row;
      const D3 pm = sc.base.world(m.position.x, m.position.y, m.position.z);
      st.pos_err.push_back(norm(sub(pm, gt.p)) / r);
      // Model normal is in the local frame at the hit's (x, y).
      D3 t, b, nn;
      sc.base.frame(m.position.x, t, b, nn);
      const D3 nw = add(add(mul(t, m.normal.x), mul(b, m.normal.y)), mul(nn, m.normal.z));
      st.normal_err.push_back(angle_deg(nw, gt.normal));
    }
  }
  return st;
}

}  // namespace knit::test
