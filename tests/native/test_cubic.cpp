// The kernel's closed-form quadratic and cubic solvers against a
// double-precision reference (roots built from known factors).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "knit/kernel.h"

namespace {

std::vector<float> roots_of(const knit::k::KRoots& r) {
  std::vector<float> v;
  if (r.n > 0) v.push_back(r.r0);
  if (r.n > 1) v.push_back(r.r1);
  if (r.n > 2) v.push_back(r.r2);
  return v;
}

// Residual of the monic cubic in double, relative to the polynomial's scale.
double rel_residual(double a3, double a2, double a1, double a0, double x) {
  double f = ((a3 * x + a2) * x + a1) * x + a0;
  double s = std::abs(a3 * x * x * x) + std::abs(a2 * x * x) + std::abs(a1 * x) + std::abs(a0);
  return s > 0 ? std::abs(f) / s : 0.0;
}

TEST(Cubic, ThreeKnownRootsRecovered) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-3.0, 3.0);
  double worst = 0.0;
  int n = 0;
  for (int i = 0; i < 20000; ++i) {
    double r[3] = {U(rng), U(rng), U(rng)};
    std::sort(r, r + 3);
    if (r[1] - r[0] < 0.05 || r[2] - r[1] < 0.05) continue;  // well separated
    double s = 0.5 + std::abs(U(rng));
    double a3 = s, a2 = -s * (r[0] + r[1] + r[2]);
    double a1 = s * (r[0] * r[1] + r[0] * r[2] + r[1] * r[2]), a0 = -s * r[0] * r[1] * r[2];
    auto got = roots_of(knit::k::solve_cubic(float(a3), float(a2), float(a1), float(a0)));
    ASSERT_EQ(got.size(), 3u) << "roots " << r[0] << " " << r[1] << " " << r[2];
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs(double(got[k]) - r[k]));
    ++n;
  }
  EXPECT_GT(n, 10000);
  // Float coefficients perturb the roots by ~ eps * condition; separated roots in [-3,3].
  EXPECT_LT(worst, 2e-3) << "worst absolute root error " << worst;
}

TEST(Cubic, OneRealRootResidualIsTiny) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> U(-10.0, 10.0);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    // (x - r)(x^2 + p x + q) with p^2 < 4q: exactly one real root r.
    double r = U(rng), p = U(rng), q = p * p / 4 + 0.1 + std::abs(U(rng));
    double a3 = 1, a2 = p - r, a1 = q - r * p, a0 = -r * q;
    auto got = roots_of(knit::k::solve_cubic(float(a3), float(a2), float(a1), float(a0)));
    ASSERT_EQ(got.size(), 1u);
    worst = std::max(worst, std::abs(double(got[0]) - r) / std::max(1.0, std::abs(r)));
    EXPECT_LT(rel_residual(a3, a2, a1, a0, got[0]), 1e-5);
  }
  EXPECT_LT(worst, 1e-4);
}

TEST(Cubic, DegeneratesToQuadraticAndLinear) {
  auto q = roots_of(knit::k::solve_cubic(0.f, 1.f, -3.f, 2.f));  // (x-1)(x-2)
  ASSERT_EQ(q.size(), 2u);
  EXPECT_NEAR(q[0], 1.f, 1e-6);
  EXPECT_NEAR(q[1], 2.f, 1e-6);
  auto l = roots_of(knit::k::solve_cubic(0.f, 0.f, 2.f, -1.f));
  ASSERT_EQ(l.size(), 1u);
  EXPECT_NEAR(l[0], 0.5f, 1e-7);
  EXPECT_EQ(knit::k::solve_cubic(0.f, 0.f, 0.f, 0.f).n, 0);
  EXPECT_EQ(knit::k::solve_quadratic(1.f, 0.f, 1.f).n, 0);  // x^2 + 1
}

TEST(Cubic, StableQuadraticAvoidsCancellation) {
  // x^2 - 1e4 x + 1: roots 1e4 and 1e-4; the naive formula loses the small one.
  auto r = roots_of(knit::k::solve_quadratic(1.f, -1e4f, 1.f));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_NEAR(r[0], 1e-4f, 1e-9f);
  EXPECT_NEAR(r[1], 1e4f, 1e-1f);
}

TEST(Cubic, TripleAndDoubleRoots) {
  auto t = roots_of(knit::k::solve_cubic(1.f, -3.f, 3.f, -1.f));  // (x-1)^3
  ASSERT_GE(t.size(), 1u);
  for (float x : t) EXPECT_NEAR(x, 1.f, 2e-2f);
  auto d = roots_of(knit::k::solve_cubic(1.f, -4.f, 5.f, -2.f));  // (x-1)^2 (x-2)
  ASSERT_GE(d.size(), 1u);
  EXPECT_NEAR(d.back(), 2.f, 1e-4f);
  for (float x : d) EXPECT_LT(rel_residual(1, -4, 5, -2, x), 1e-5);
}

// The host's cube root (bit-level guess and Newton steps) against double
// precision over the whole float range, and its special values.
TEST(Cubic, HostCubeRootIsAccurate) {
  double worst = 0;
  for (double e = -37; e <= 38; e += 0.01) {
    for (double sgn : {1.0, -1.0}) {
      const float x = float(sgn * std::pow(10.0, e));
      const double ref = std::cbrt(double(x));
      const float y = knit::k::knit_host_cbrt(x);
      ASSERT_TRUE(std::isfinite(y)) << "x = " << x;
      worst = std::max(worst, std::abs(double(y) - ref) / std::abs(ref));
    }
  }
  EXPECT_LT(worst, 4e-7) << "max relative error of knit_host_cbrt";
  EXPECT_EQ(knit::k::knit_host_cbrt(0.f), 0.f);
  EXPECT_EQ(knit::k::knit_host_cbrt(-8.f), -2.f);
  EXPECT_TRUE(std::isinf(knit::k::knit_host_cbrt(INFINITY)));
  EXPECT_TRUE(std::isnan(knit::k::knit_host_cbrt(NAN)));
}

// knit_sincos (kmath.h) replaces libm's sinf/cosf in the stitch curve: against
// double precision over the range it is documented for, and at the quadrant
// boundaries where its reduction switches polynomials.
TEST(KernelMath, SincosAgreesWithDoublePrecision) {
  double worst = 0;
  std::vector<float> xs;
  for (int i = -1600000; i <= 1600000; ++i) xs.push_back(float(i) * 1e-5f);
  for (int q = -10; q <= 10; ++q)
    for (int ulp = -4; ulp <= 4; ++ulp) {
      float x = float(q * 1.5707963267948966);
      for (int u = 0; u < std::abs(ulp); ++u) x = std::nextafter(x, ulp > 0 ? 100.f : -100.f);
      xs.push_back(x);
    }
  for (float x : xs) {
    const knit::k::kvec3 sc = knit::k::knit_sincos(x);
    ASSERT_TRUE(std::isfinite(sc.x) && std::isfinite(sc.y)) << "x = " << x;
    worst = std::max(worst, std::abs(double(sc.x) - std::sin(double(x))));
    worst = std::max(worst, std::abs(double(sc.y) - std::cos(double(x))));
  }
  // float's unit roundoff is 6e-8: a couple of roundings in the reduction
  // and the polynomial
  EXPECT_LT(worst, 2.5e-7) << "max absolute error of knit_sincos on [-16, 16]";
  EXPECT_EQ(knit::k::knit_sincos(0.f).x, 0.f);
  EXPECT_EQ(knit::k::knit_sincos(0.f).y, 1.f);
}

}  // namespace
