// Ground truth for tests: ray casts of explicit yarn tubes in double
// precision, written independently of the kernel. A tube is the union of
// capsules around a dense polyline (a round linear curve, the same primitive
// Embree's ROUND_LINEAR_CURVE renders), built into a median-split BVH.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace knit::test {

using D3 = std::array<double, 3>;

inline D3 sub(const D3& a, const D3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline D3 add(const D3& a, const D3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline D3 mul(const D3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const D3& a, const D3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline double norm(const D3& a) { return std::sqrt(dot(a, a)); }
inline D3 normalized(const D3& a) { return mul(a, 1.0 / norm(a)); }

struct TubeHit {
  bool hit = false;
  double t = std::numeric_limits<double>::infinity();  // ray distance
  D3 p{}, normal{};
  int curve = -1;    // which polyline
  int segment = -1;  // which segment of it
  double u = 0;      // position along the segment, [0, 1]
};

class TubeScene {
 public:
  // Adds one polyline tube of radius r. Returns its index.
  int add_curve(std::vector<D3> pts, double r) {
    const int id = int(curves_.size());
    curves_.push_back({std::move(pts), r});
    return id;
  }

  void build() {
    prims_.clear();
    for (int c = 0; c < int(curves_.size()); ++c)
      for (int s = 0; s + 1 < int(curves_[size_t(c)].pts.size()); ++s) prims_.push_back({c, s});
    nodes_.clear();
    nodes_.reserve(prims_.size() * 2);
    build_node(0, int(prims_.size()));
  }

  // First intersection of o + t d (d unit) with t in (tmin, tmax).
  TubeHit intersect(const D3& o, const D3& d, double tmin = 1e-9,
                    double tmax = std::numeric_limits<double>::infinity()) const {
    TubeHit best;
    best.t = tmax;
    if (nodes_.empty()) return best;
    const D3 inv = {1.0 / d[0], 1.0 / d[1], 1.0 / d[2]};
    int stack[128];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
      const Node& n = nodes_[size_t(stack[--sp])];
      if (!box_hit(n, o, inv, tmin, best.t)) continue;
      if (n.count > 0) {
        for (int i = n.first; i < n.first + n.count; ++i) hit_capsule(prims_[size_t(i)], o, d, tmin, best);
      } else {
        stack[sp++] = n.left;
        stack[sp++] = n.right;
      }
    }
    best.hit = best.t < tmax && best.curve >= 0;
    return best;
  }

  // All entries along the ray: the number of separate tube intervals crossed.
  int count_crossings(const D3& o, const D3& d, double tmin, double tmax) const {
    int n = 0;
    double t = tmin;
    for (int guard = 0; guard < 64; ++guard) {
      TubeHit h = intersect(o, d, t, tmax);
      if (!h.hit) break;
      ++n;
      // Walk to the exit of the union containing this entry point.
      t = exit_distance(o, d, h.t + 1e-6) + 1e-7;
    }
    return n;
  }

  const std::vector<D3>& points(int curve) const { return curves_[size_t(curve)].pts; }

 private:
  struct Curve {
    std::vector<D3> pts;
    double r;
  };
  struct Prim {
    int curve, seg;
  };
  struct Node {
    D3 lo, hi;
    int left = -1, right = -1, first = 0, count = 0;
  };

  void prim_box(const Prim& p, D3& lo, D3& hi) const {
    const Curve& c = curves_[size_t(p.curve)];
    const D3& a = c.pts[size_t(p.seg)];
    const D3& b = c.pts[size_t(p.seg + 1)];
    for (int k = 0; k < 3; ++k) {
      lo[size_t(k)] = std::min(a[size_t(k)], b[size_t(k)]) - c.r;
      hi[size_t(k)] = std::max(a[size_t(k)], b[size_t(k)]) + c.r;
    }
  }

  int build_node(int first, int count) {
    const int idx = int(nodes_.size());
    nodes_.push_back({});
    D3 lo = {1e300, 1e300, 1e300}, hi = {-1e300, -1e300, -1e300};
    for (int i = first; i < first + count; ++i) {
      D3 a, b;
      prim_box(prims_[size_t(i)], a, b);
      for (int k = 0; k < 3; ++k) {
        lo[size_t(k)] = std::min(lo[size_t(k)], a[size_t(k)]);
        hi[size_t(k)] = std::max(hi[size_t(k)], b[size_t(k)]);
      }
    }
    nodes_[size_t(idx)].lo = lo;
    nodes_[size_t(idx)].hi = hi;
    if (count <= 4) {
      nodes_[size_t(idx)].first = first;
      nodes_[size_t(idx)].count = count;
      return idx;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
      if (hi[size_t(k)] - lo[size_t(k)] > hi[size_t(axis)] - lo[size_t(axis)]) axis = k;
    const int mid = first + count / 2;
    auto centre = [&](const Prim& p) {
      const Curve& c = curves_[size_t(p.curve)];
      return c.pts[size_t(p.seg)][size_t(axis)] + c.pts[size_t(p.seg + 1)][size_t(axis)];
    };
    std::nth_element(prims_.begin() + first, prims_.begin() + mid, prims_.begin() + first + count,
                     [&](const Prim& a, const Prim& b) { return centre(a) < centre(b); });
    const int left = build_node(first, mid - first);
    const int right = build_node(mid, first + count - mid);
    nodes_[size_t(idx)].left = left;
    nodes_[size_t(idx)].right = right;
    return idx;
  }

  static bool box_hit(const Node& n, const D3& o, const D3& inv, double t0, double t1) {
    for (int k = 0; k < 3; ++k) {
      double a = (n.lo[size_t(k)] - o[size_t(k)]) * inv[size_t(k)];
      double b = (n.hi[size_t(k)] - o[size_t(k)]) * inv[size_t(k)];
      if (std::isnan(a) || std::isnan(b)) {
        if (o[size_t(k)] < n.lo[size_t(k)] || o[size_t(k)] > n.hi[size_t(k)]) return false;
        continue;
      }
      t0 = std::max(t0, std::min(a, b));
      t1 = std::min(t1, std::max(a, b));
      if (t0 > t1) return false;
    }
    return true;
  }

  // Ray against the capsule of segment p: the finite cylinder and the sphere
  // at its first vertex (the last vertex's sphere belongs to the next
  // segment, except at the curve's end).
  void hit_capsule(const Prim& p, const D3& o, const D3& d, double tmin, TubeHit& best) const {
    const Curve& c = curves_[size_t(p.curve)];
    const D3& a = c.pts[size_t(p.seg)];
    const D3& b = c.pts[size_t(p.seg + 1)];
    const double r = c.r;
    hit_sphere(a, r, o, d, tmin, best, p, 0.0);
    if (p.seg + 2 == int(c.pts.size())) hit_sphere(b, r, o, d, tmin, best, p, 1.0);
    const D3 ax = sub(b, a);
    const double L = norm(ax);
    if (L <= 0) return;
    const D3 w = mul(ax, 1.0 / L);
    const D3 oa = sub(o, a);
    const D3 dp = sub(d, mul(w, dot(d, w)));
    const D3 op = sub(oa, mul(w, dot(oa, w)));
    const double A = dot(dp, dp), B = 2 * dot(dp, op), C = dot(op, op) - r * r;
    if (A < 1e-300) return;
    const double disc = B * B - 4 * A * C;
    if (disc < 0) return;
    const double sq = std::sqrt(disc);
    const double q = -0.5 * (B + (B < 0 ? -sq : sq));
    double t1 = q / A, t2 = (q != 0) ? C / q : t1;
    if (t1 > t2) std::swap(t1, t2);
    for (double t : {t1, t2}) {
      if (t <= tmin || t >= best.t) continue;
      const D3 ph = add(o, mul(d, t));
      const double s = dot(sub(ph, a), w);
      if (s < 0 || s > L) continue;
      const D3 foot = add(a, mul(w, s));
      best.t = t;
      best.p = ph;
      best.normal = normalized(sub(ph, foot));
      best.curve = p.curve;
      best.segment = p.seg;
      best.u = s / L;
      break;
    }
  }

  static void hit_sphere(const D3& cen, double r, const D3& o, const D3& d, double tmin, TubeHit& best,
                         const Prim& p, double u) {
    const D3 oc = sub(o, cen);
    const double B = dot(oc, d), C = dot(oc, oc) - r * r;
    const double disc = B * B - C;
    if (disc < 0) return;
    const double sq = std::sqrt(disc);
    for (double t : {-B - sq, -B + sq}) {
      if (t <= tmin || t >= best.t) continue;
      const D3 ph = add(o, mul(d, t));
      best.t = t;
      best.p = ph;
      best.normal = normalized(sub(ph, cen));
      best.curve = p.curve;
      best.segment = p.seg;
      best.u = u;
      break;
    }
  }

  // Distance along the ray where the union of tubes containing o + t d ends:
  // fine steps while inside, then bisection.
  double exit_distance(const D3& o, const D3& d, double t) const {
    const double step = 0.002;
    double lo_t = t, hi_t = t + step;
    while (inside(add(o, mul(d, hi_t)))) {
      lo_t = hi_t;
      hi_t += step;
    }
    for (int i = 0; i < 40; ++i) {
      double m = 0.5 * (lo_t + hi_t);
      if (inside(add(o, mul(d, m)))) lo_t = m;
      else hi_t = m;
    }
    return hi_t;
  }

 public:
  // Whether point x lies in any tube.
  bool inside(const D3& x) const {
    if (nodes_.empty()) return false;
    int stack[128];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
      const Node& n = nodes_[size_t(stack[--sp])];
      bool in = true;
      for (int k = 0; k < 3; ++k) in = in && x[size_t(k)] >= n.lo[size_t(k)] && x[size_t(k)] <= n.hi[size_t(k)];
      if (!in) continue;
      if (n.count == 0) {
        stack[sp++] = n.left;
        stack[sp++] = n.right;
        continue;
      }
      for (int i = n.first; i < n.first + n.count; ++i) {
        const Prim& p = prims_[size_t(i)];
        const Curve& c = curves_[size_t(p.curve)];
        const D3& a = c.pts[size_t(p.seg)];
        const D3 ax = sub(c.pts[size_t(p.seg + 1)], a);
        const double L2 = dot(ax, ax);
        const double s = L2 > 0 ? std::clamp(dot(sub(x, a), ax) / L2, 0.0, 1.0) : 0.0;
        if (norm(sub(x, add(a, mul(ax, s)))) <= c.r) return true;
      }
    }
    return false;
  }

 private:
  std::vector<Curve> curves_;
  std::vector<Prim> prims_;
  std::vector<Node> nodes_;
};

}  // namespace knit::test
