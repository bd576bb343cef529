// Cheap stand-ins for libm's inverse trigonometry where a direction only
// has to find its bin or texel.
#pragma once

#include <algorithm>
#include <cmath>

namespace knit {

namespace detail {
// atan2(y, x) in [-pi, pi] from an odd polynomial for atan on [0, 1],
// t (c[0] + c[1] t^2 + ...), and the octant identities.
template <int N>
inline float atan2_odd(float y, float x, const float (&c)[N]) {
  constexpr float pi = 3.14159265358979f;
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  if (!(hi > 0)) return 0;
  const float t = lo / hi, s = t * t;
  float p = c[N - 1];
  for (int i = N - 2; i >= 0; --i) p = p * s + c[i];
  float r = t * p;
  if (ay > ax) r = 0.5f * pi - r;
  if (x < 0) r = pi - r;
  return y < 0 ? -r : r;
}
}  // namespace detail

// atan2(y, x) to within 4e-7 rad (polynomial fitted minimax on [0, 1]), a
// fraction of libm's cost: environment-map texels, where a bilinear lookup
// next to a sun 5000 times its surroundings shows an error of 2e-6 rad.
inline float atan2_approx(float y, float x) {
  static constexpr float c[] = {0.99999934f, -0.33329859f, 0.19946565f, -0.13908628f,
                                0.09642194f, -0.05591227f, 0.02186292f, -0.00405456f};
  return detail::atan2_odd(y, x, c);
}

// atan2(y, x) to within 1e-4 rad, in half the polynomial: where a direction
// only finds its bins and their bilinear weights (the class table's and
// the tabulated BSDF's bins are 0.14 to 0.52 rad wide). (acosf and atan2f
// from libm took a fifth of the class table's aggregate; the lookups'
// polynomial, a dependency chain, is still a few percent of a multi-scale
// render.)
inline float atan2_coarse(float y, float x) {
  static constexpr float c[] = {0.99921381f, -0.32117492f, 0.14626436f, -0.03898645f};
  return detail::atan2_odd(y, x, c);
}

// acos(c) for c in [-1, 1] (clamped), to the same accuracy.
inline float acos_approx(float c) {
  c = std::clamp(c, -1.0f, 1.0f);
  return atan2_approx(std::sqrt(std::max(0.0f, 1 - c * c)), c);
}

}  // namespace knit
