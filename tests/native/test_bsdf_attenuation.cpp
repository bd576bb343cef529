// Double-layer attenuation tau (native/kernel/bsdf_attenuation.h): the chord
// formula against a double-precision ray-cylinder intersection, and the
// properties the BSDF relies on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

// Length inside the cylinder y^2 + z^2 <= R^2 (axis x) of the line entering
// at (0, 0, R) travelling along -d, by solving the quadratic in double.
double chord_ref(Vec3 d, double R) {
  double py = 0, pz = R, dy = -d.y, dz = -d.z;
  double a = dy * dy + dz * dz, b = 2 * (py * dy + pz * dz), c = py * py + pz * pz - R * R;
  if (a == 0) return 1e30;
  double disc = std::max(0.0, b * b - 4 * a * c);
  double t1 = (-b + std::sqrt(disc)) / (2 * a), t0 = (-b - std::sqrt(disc)) / (2 * a);
  return std::max(t0, t1);  // the other root is the entry point, t = 0
}

TEST(BsdfAttenuation, ChordMatchesRayCylinderIntersection) {
  Rng rng(12);
  double worst = 0;
  int n = 0;
  for (int i = 0; i < 100000; ++i) {
    Vec3 d = uniform_sphere(rng);
    if (d.z < 0) d.z = -d.z;  // entering: along -d into the tube
    double ref = chord_ref(d, 0.75) / (2 * 0.75);
    if (ref >= KB_CHORD_MAX) {
      EXPECT_FLOAT_EQ(k::bsdf_att_chord(d), KB_CHORD_MAX);
      continue;
    }
    worst = std::max(worst, std::abs(k::bsdf_att_chord(d) - ref) / std::max(ref, 1e-3));
    ++n;
  }
  std::printf("[attenuation] chord vs ray-cylinder: max rel error %.3g over %d directions\n", worst, n);
  EXPECT_LT(worst, 1e-5);
  EXPECT_FLOAT_EQ(k::bsdf_att_chord(v3(0, 0, 1)), 1.f);               // through the centre: 2R
  EXPECT_FLOAT_EQ(k::bsdf_att_chord(v3(1, 0, 0)), KB_CHORD_MAX);      // along the axis
  EXPECT_FLOAT_EQ(k::bsdf_att_chord(v3(0, 1, 0)), 0.f);               // tangent: no chord
}

TEST(BsdfAttenuation, BoundedSymmetricAndCompoundedPerLayer) {
  Rng rng(13);
  for (int i = 0; i < 20000; ++i) {
    Vec3 wo = uniform_sphere(rng), wi = uniform_sphere(rng);
    float D = 5.f * rng.uniform();
    float t1 = k::bsdf_att_tau(k::bsdf_att_make(D, 1), wo, wi);
    float t2 = k::bsdf_att_tau(k::bsdf_att_make(D, 2), wo, wi);
    float t4 = k::bsdf_att_tau(k::bsdf_att_make(D, 4), wo, wi);
    ASSERT_TRUE(std::isfinite(t1));
    EXPECT_GE(t1, 0.f);
    EXPECT_LE(t1, 1.f);
    EXPECT_FLOAT_EQ(t1, k::bsdf_att_tau(k::bsdf_att_make(D, 1), wi, wo));
    EXPECT_NEAR(t2, t1 * t1, 1e-6);           // double layer = tau_1^2
    EXPECT_NEAR(t4, t2 * t2, 1e-6);
    EXPECT_FLOAT_EQ(k::bsdf_att_tau(k::bsdf_att_make(D, 9), wo, wi), t4);  // at most 4 layers
    EXPECT_FLOAT_EQ(k::bsdf_att_tau(k::bsdf_att_make(D, 0), wo, wi), t1);  // at least 1
    EXPECT_FLOAT_EQ(k::bsdf_att_tau(k::bsdf_att_make(0.f, 3), wo, wi), 1.f);
  }
  // Straight down the normal through one yarn: exp(-D).
  EXPECT_NEAR(k::bsdf_att_tau_straight(k::bsdf_att_make(1.f, 1), v3(0, 0, 1)), std::exp(-1.0), 1e-7);
}

}  // namespace
