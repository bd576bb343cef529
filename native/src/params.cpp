// StitchParams validation and the yarn clearance behind it.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "knit/params.h"
#include "knit/pattern.h"
#include "knit/yarns.h"

namespace knit {
namespace {

constexpr double kPi = 3.14159265358979323846;

using P3 = std::array<double, 3>;

double dist(const P3& p, const P3& q) {
  return std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                   (p[2] - q[2]) * (p[2] - q[2]));
}

// Smallest distance between two different yarn pieces, over the knit/purl
// neighbourhoods that occur in patterns (stockinette, garter, 1x1 rib, seed):
// rows one and two apart, and within a row the doubly critical pairs (local
// minima of the distance more than ~1/4 stitch apart along the curve); and
// twice the smallest radius of curvature (a thicker tube folds over itself).
double compute_clearance(float a, float h, float d) {
  StitchParams sp;
  sp.a = a;
  sp.h = h;
  sp.d = d;
  const std::vector<Pattern> cases = {Pattern::from_rows({{0}}), Pattern::from_rows({{0}, {1}}),
                                      Pattern::from_rows({{0, 1}}), Pattern::from_rows({{0, 1}, {1, 0}})};
  const int per_stitch = 96, stitches = 4, n = per_stitch * stitches;
  const double dt = 2 * kPi / per_stitch;
  const int gap = int(std::ceil(0.8 / dt));
  double best = 1e300, min_rc = 1e300;
  for (const Pattern& pat : cases) {
    std::vector<std::vector<P3>> rows(4, std::vector<P3>(static_cast<size_t>(n)));
    for (int k = 0; k < 4; ++k)
      for (int i = 0; i < n; ++i) {
        const CurvePoint c = yarn_curve_exact(pat, sp, k, dt * i);
        rows[size_t(k)][size_t(i)] = c.p;
        const double* d1 = c.dp.data();
        const double* d2 = c.ddp.data();
        const double cx = d1[1] * d2[2] - d1[2] * d2[1], cy = d1[2] * d2[0] - d1[0] * d2[2],
                     cz = d1[0] * d2[1] - d1[1] * d2[0];
        const double sp3 = std::pow(d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2], 1.5);
        const double cr = std::sqrt(cx * cx + cy * cy + cz * cz);
        if (cr > 0) min_rc = std::min(min_rc, sp3 / cr);
      }
    // Points of each row in order of x: a pair farther apart in x than the
    // best distance so far cannot improve it, so only a window is visited
    // (the same minimum as comparing every pair).
    std::vector<std::vector<P3>> by_x = rows;
    for (auto& r : by_x) std::sort(r.begin(), r.end(), [](const P3& p, const P3& q) { return p[0] < q[0]; });
    for (int k = 0; k < 4; ++k) {
      const auto& R = rows[size_t(k)];
      auto D = [&](int i, int j) { return dist(R[size_t(i)], R[size_t(j)]); };
      for (int i = 1; i + 1 < n; ++i)
        for (int j = i + gap; j + 1 < n; ++j) {
          if (std::abs(R[size_t(i)][0] - R[size_t(j)][0]) >= best) continue;  // then D(i, j) >= best
          const double v = D(i, j);
          if (v < best && v <= D(i - 1, j) && v <= D(i + 1, j) && v <= D(i, j - 1) && v <= D(i, j + 1))
            best = v;
        }
      for (int k2 = k + 1; k2 < 4 && k2 <= k + 2; ++k2) {
        const auto& Q = by_x[size_t(k2)];
        for (const P3& p : R) {
          auto it = std::lower_bound(Q.begin(), Q.end(), p[0] - best,
                                     [](const P3& q, double x) { return q[0] < x; });
          for (; it != Q.end() && (*it)[0] <= p[0] + best; ++it) best = std::min(best, dist(p, *it));
        }
      }
    }
  }
  return std::min(best, 2 * min_rc);
}

}  // namespace

double StitchParams::clearance() const {
  static std::mutex mu;
  static std::map<std::tuple<float, float, float>, double> cache;
  const auto key = std::make_tuple(a, h, std::abs(d));
  {
    std::lock_guard<std::mutex> lock(mu);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
  }
  const double c = compute_clearance(a, h, std::abs(d));
  std::lock_guard<std::mutex> lock(mu);
  if (cache.size() > 256) cache.clear();
  cache[key] = c;
  return c;
}

static std::string fmt(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void StitchParams::validate() const {
  const struct {
    const char* name;
    float v;
  } fields[] = {{"a", a}, {"h", h}, {"d", d}, {"r", r}};
  for (const auto& f : fields) {
    if (!std::isfinite(f.v))
      throw std::invalid_argument(std::string("stitch parameter ") + f.name + " must be finite, got " +
                                  fmt(f.v));
    if (std::abs(f.v) > 1e3f)
      throw std::invalid_argument(std::string("stitch parameter ") + f.name +
                                  " must be at most 1000 in magnitude, got " + fmt(f.v));
  }
  if (!(a > 0)) throw std::invalid_argument("stitch parameter a (loop roundness) must be > 0, got " + fmt(a));
  if (!(h > 0)) throw std::invalid_argument("stitch parameter h (loop height) must be > 0, got " + fmt(h));
  if (d == 0) throw std::invalid_argument("stitch parameter d (loop depth) must be non-zero, got 0");
  if (!(r > 0)) throw std::invalid_argument("stitch parameter r (yarn radius) must be > 0, got " + fmt(r));
  const double c = clearance();
  if (2.0 * r > c * (1 + 1e-6))
    throw std::invalid_argument("stitch parameter r = " + fmt(r) +
                                " makes yarn tubes pass through each other: with a = " + fmt(a) +
                                ", h = " + fmt(h) + ", d = " + fmt(d) +
                                " the yarn centre lines come within " + fmt(c) +
                                " of each other, so r must be <= " + fmt(c / 2));
}

std::string StitchParams::to_string() const {
  std::ostringstream o;
  o << "StitchParams(a=" << a << ", h=" << h << ", d=" << d << ", r=" << r << ")";
  return o.str();
}

}  // namespace knit
