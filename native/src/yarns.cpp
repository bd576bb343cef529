// Explicit yarn centre curves of a tiled pattern (the ground truth geometry).
#include <cmath>
#include <stdexcept>
#include <string>

#include "knit/yarns.h"

namespace knit {

ExplicitYarns explicit_yarns(const Pattern& pattern, const StitchParams& params, int tiles_u,
                             int tiles_v, int samples_per_stitch) {
  params.validate();
  if (tiles_u < 1 || tiles_v < 1 || tiles_u > 4096 || tiles_v > 4096)
    throw std::invalid_argument("explicit_yarns: tiles must be in [1, 4096], got " +
                                std::to_string(tiles_u) + " x " + std::to_string(tiles_v));
  if (samples_per_stitch < 4 || samples_per_stitch > 4096)
    throw std::invalid_argument("explicit_yarns: samples_per_stitch must be in [4, 4096], got " +
                                std::to_string(samples_per_stitch));
  const long long cols = (long long)pattern.cols() * tiles_u;
  const long long rows = (long long)pattern.rows() * tiles_v;
  const long long points = rows * (cols * samples_per_stitch + 1);
  if (points > 200'000'000LL)
    throw std::invalid_argument("explicit_yarns: " + std::to_string(points) +
                                " curve points requested; reduce tiles or samples_per_stitch");
  constexpr double kTwoPi = 6.28318530717958647692;
  ExplicitYarns out;
  out.radius = params.r;
  out.width = kTwoPi * double(cols);
  out.height = double(params.row_spacing()) * double(rows);
  out.t_step = kTwoPi / samples_per_stitch;
  out.curves.resize(size_t(rows));
  const auto mod = [](long long a, long long n) { return int(((a % n) + n) % n); };
  for (long long k = 0; k < rows; ++k) {
    YarnCurve& yc = out.curves[size_t(k)];
    yc.row = int(k);
    const long long n = cols * samples_per_stitch;
    yc.points.reserve(size_t(n + 1));
    yc.color.reserve(size_t(n + 1));
    for (long long i = 0; i <= n; ++i) {
      const double t = out.t_step * double(i);
      yc.points.push_back(yarn_curve_exact(pattern, params, int(k), t).p);
      const long long c = std::min<long long>(i / samples_per_stitch, cols - 1);
      const int pr = pattern.rows() - 1 - mod(k, pattern.rows());
      yc.color.push_back(pattern.colors_or_zero()[size_t(pr) * pattern.cols() + mod(c, pattern.cols())]);
    }
  }
  return out;
}

}  // namespace knit
