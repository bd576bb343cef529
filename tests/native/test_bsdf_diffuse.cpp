// The body lobes: Lommel-Seeliger reflection (bsdf_lommel_seeliger.h) and
// Lambertian transmission (bsdf_lambert_transmission.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

// A(mu) = 1 - mu ln(1 + 1/mu), in double.
double ls_albedo_ref(double mu) { return mu == 0 ? 1.0 : 1.0 - mu * std::log1p(1.0 / mu); }

TEST(BsdfLommelSeeliger, AlbedoMatchesClosedFormAndStaysBelowOne) {
  const k::KLommelSeeliger ls = k::bsdf_ls_make(Vec3{1.f, 1.f, 1.f});
  double worst = 0, largest = 0;
  for (double mu : {1.0, 0.8, 0.5, 0.3, 0.1, 0.03, 0.01, 1e-3, 1e-5}) {
    Vec3 wo = dir_zphi(mu, 0.4);
    DirFn f = [&](Vec3 wi) { return double(k::bsdf_ls_eval(ls, wo, wi).x); };
    double a = integrate_sphere(f, 32, 16, 1e-8);
    worst = std::max(worst, std::abs(a - ls_albedo_ref(mu)));
    largest = std::max(largest, a);
    EXPECT_NEAR(k::bsdf_ls_albedo(float(mu)), ls_albedo_ref(mu), 2e-6) << mu;
    EXPECT_LE(a, 1.0 + 1e-6) << mu;
  }
  std::printf("[ls] max |numeric albedo - closed form| = %.3g, largest albedo %.6f\n", worst, largest);
  EXPECT_LT(worst, 1e-4);
  // Normal view: 1 - ln 2.
  EXPECT_NEAR(ls_albedo_ref(1.0), 1.0 - std::log(2.0), 1e-15);
  EXPECT_FLOAT_EQ(k::bsdf_ls_albedo(0.f), 1.f);
}

TEST(BsdfLommelSeeliger, ReciprocalColouredAndOneSided) {
  const k::KLommelSeeliger ls = k::bsdf_ls_make(Vec3{0.9f, 0.5f, 0.1f});
  Rng rng(3);
  for (int i = 0; i < 20000; ++i) {
    Vec3 a = uniform_sphere(rng), b = uniform_sphere(rng);
    Vec3 fab = k::bsdf_ls_eval(ls, a, b), fba = k::bsdf_ls_eval(ls, b, a);
    if (a.z * b.z <= 0) {
      EXPECT_EQ(fab.x, 0.f);
      EXPECT_EQ(k::bsdf_ls_pdf(ls, a, b), 0.f);
      continue;
    }
    EXPECT_NEAR(fab.x / std::abs(b.z), fba.x / std::abs(a.z), 1e-5 * fab.x / std::abs(b.z));
    EXPECT_NEAR(fab.y / fab.x, 0.5 / 0.9, 1e-5);
    EXPECT_NEAR(fab.z / fab.x, 0.1 / 0.9, 1e-5);
  }
}

TEST(BsdfLommelSeeliger, SampleWeightIsEvalOverPdf) {
  const k::KLommelSeeliger ls = k::bsdf_ls_make(Vec3{0.9f, 0.5f, 0.1f});
  Rng rng(4);
  for (int i = 0; i < 20000; ++i) {
    Vec3 wo = uniform_sphere(rng);
    k::KBsdfSample s = k::bsdf_ls_sample(ls, wo, rng.uniform(), rng.uniform());
    ASSERT_GT(s.pdf, 0.f);
    EXPECT_EQ(s.flags, KB_REFLECT);
    EXPECT_GT(wo.z * s.wi.z, 0.f);
    EXPECT_NEAR(s.pdf, k::bsdf_ls_pdf(ls, wo, s.wi), 1e-6 * s.pdf);
    Vec3 e = k::bsdf_ls_eval(ls, wo, s.wi);
    EXPECT_NEAR(s.weight.x, e.x / s.pdf, 1e-5 * s.weight.x);
    EXPECT_NEAR(s.weight.z, e.z / s.pdf, 1e-5 * s.weight.z);
  }
}

TEST(BsdfLommelSeeliger, LambertEquivalentHasTheSameAlbedo) {
  // The OSL approximation A(mu_o) k diffuse(N) reflects what LS reflects at wo.
  for (double mu : {1.0, 0.5, 0.1, 0.01}) {
    Vec3 wo = dir_zphi(mu, 0);
    double w = k::bsdf_ls_lambert_equivalent(wo);
    DirFn lam = [&](Vec3 wi) { return wi.z > 0 ? w * wi.z / kPi : 0.0; };
    EXPECT_NEAR(integrate_sphere(lam, 16, 16), ls_albedo_ref(mu), 1e-5);
  }
}

TEST(BsdfLambertTransmission, AlbedoIsTheColourOnTheOtherSide) {
  const k::KLambertTransmission lt = k::bsdf_lt_make(Vec3{0.9f, 0.5f, 0.1f});
  for (double mu : {1.0, 0.5, 1e-3, -0.7}) {
    Vec3 wo = dir_zphi(mu, 1.0);
    DirFn f = [&](Vec3 wi) { return double(k::bsdf_lt_eval(lt, wo, wi).x); };
    EXPECT_NEAR(integrate_sphere(f, 16, 16), 0.9, 1e-6) << mu;
  }
  Rng rng(6);
  for (int i = 0; i < 20000; ++i) {
    Vec3 wo = uniform_sphere(rng);
    k::KBsdfSample s = k::bsdf_lt_sample(lt, wo, rng.uniform(), rng.uniform());
    ASSERT_GT(s.pdf, 0.f);
    EXPECT_EQ(s.flags, KB_TRANSMIT);
    EXPECT_LT(wo.z * s.wi.z, 0.f);
    EXPECT_NEAR(s.pdf, k::bsdf_lt_pdf(lt, wo, s.wi), 1e-6 * s.pdf);
    EXPECT_NEAR(s.weight.y, k::bsdf_lt_eval(lt, wo, s.wi).y / s.pdf, 1e-5);
    // Reciprocity: f = k / pi both ways.
    EXPECT_NEAR(k::bsdf_lt_eval(lt, wo, s.wi).x / std::abs(s.wi.z),
                k::bsdf_lt_eval(lt, s.wi, wo).x / std::abs(wo.z), 1e-6);
  }
}

}  // namespace
