// The rough dielectric lobes (native/kernel/bsdf_microfacet.h): Fresnel and
// the GGX distribution against double-precision references, reciprocity,
// eval/pdf/sample agreement, the smooth limit, and the LEAN conversion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

// Fresnel reflectance of unpolarised light entering a medium of index eta,
// from the s and p amplitude coefficients (an independent form), in double.
double fresnel_ref(double ci, double eta) {
  double si2 = std::max(0.0, 1.0 - ci * ci);
  double ct = std::sqrt(std::max(0.0, 1.0 - si2 / (eta * eta)));
  double rs = (ci - eta * ct) / (ci + eta * ct);
  double rp = (eta * ci - ct) / (eta * ci + ct);
  return 0.5 * (rs * rs + rp * rp);
}

TEST(BsdfMicrofacet, FresnelMatchesDoubleReference) {
  double worst = 0;
  for (double eta : {1.0, 1.0001, 1.1, 1.33, 1.55, 2.0, 2.5, 3.0}) {
    for (int i = 0; i <= 2000; ++i) {
      double c = i / 2000.0;
      if (eta == 1.0 && c == 0.0) continue;  // 0/0: the limit depends on the path
      // The reference sees the same float-rounded inputs as the kernel.
      double cf = double(float(c)), ef = double(float(eta));
      double ref = cf == 0.0 ? 1.0 : fresnel_ref(cf, ef);
      double got = k::kb_fresnel_dielectric(float(c), float(eta));
      worst = std::max(worst, std::abs(got - ref));
    }
  }
  std::printf("[fresnel] max |F_float - F_double| = %.3g\n", worst);
  EXPECT_LT(worst, 2e-6);
  // Normal incidence: ((eta - 1)/(eta + 1))^2.
  EXPECT_NEAR(k::kb_fresnel_dielectric(1.f, 1.5f), 0.04f, 1e-7);
  EXPECT_EQ(k::kb_fresnel_dielectric(0.5f, 1.f), 0.f);
}

TEST(BsdfMicrofacet, GgxDistributionIsNormalised) {
  // int D(h) h.z dw_h = 1 (projected area of the microsurface = 1).
  const float alphas[][2] = {{0.05f, 0.05f}, {0.1f, 0.4f}, {0.3f, 0.3f}, {0.7f, 0.2f}, {1.f, 1.f}};
  double worst = 0;
  for (auto& a : alphas) {
    DirFn f = [&](Vec3 h) { return double(k::mf_ggx_d(a[0], a[1], h)) * std::max(0.f, h.z); };
    double integral = integrate_sphere(f, 32, 32, 1e-7);
    worst = std::max(worst, std::abs(integral - 1.0));
    EXPECT_NEAR(integral, 1.0, 1e-3) << "alpha " << a[0] << " " << a[1];
  }
  std::printf("[ggx] max |int D cos - 1| = %.3g\n", worst);
}

TEST(BsdfMicrofacet, VisibleNormalsAreNormalised) {
  // int D_wo(h) dw_h = 1 for every wo: checks the Smith G1 (Lambda) against D.
  const float alphas[][2] = {{0.1f, 0.1f}, {0.2f, 0.8f}, {0.6f, 0.6f}, {1.f, 0.3f}};
  double worst = 0;
  for (auto& a : alphas) {
    for (double th : {0.0, 40.0, 75.0, 85.0, 89.0}) {
      Vec3 wo = dir_deg(th, 30.0);
      // Integrate in a frame whose pole is wo, so that the cut-off wo.h = 0
      // of D_wo lies on cell edges instead of inside the peak of D.
      Vec3 e1 = normalized(std::abs(wo.z) < 0.9f ? v3(-wo.y, wo.x, 0) : v3(1, 0, 0));
      Vec3 e2 = v3(wo.y * e1.z - wo.z * e1.y, wo.z * e1.x - wo.x * e1.z, wo.x * e1.y - wo.y * e1.x);
      DirFn f = [&](Vec3 d) {
        Vec3 h = v3(d.x * e1.x + d.y * e2.x + d.z * wo.x, d.x * e1.y + d.y * e2.y + d.z * wo.y,
                    d.x * e1.z + d.y * e2.z + d.z * wo.z);
        return double(k::mf_ggx_vndf(a[0], a[1], wo, h));
      };
      double integral = integrate_sphere(f, 32, 32, 1e-7);
      worst = std::max(worst, std::abs(integral - 1.0));
      EXPECT_NEAR(integral, 1.0, 2e-3) << "alpha " << a[0] << " " << a[1] << " theta " << th;
    }
  }
  std::printf("[ggx] max |int D_wo - 1| = %.3g\n", worst);
}

TEST(BsdfMicrofacet, ReflectionAndTransmissionAreReciprocal) {
  // f = eval / |wi.z| must be symmetric. For the thin-slab transmission the
  // eta^2 radiance factors of entering and leaving cancel, so plain symmetry
  // (no eta^2) is the correct relation.
  Rng rng(5);
  double worst_r = 0, worst_t = 0;
  int nr = 0, nt = 0;
  for (int i = 0; i < 200000; ++i) {
    k::KMicrofacet m = k::bsdf_mf_make(0.05f + 0.95f * rng.uniform(), 0.05f + 0.95f * rng.uniform(),
                                       1.f + 2.f * rng.uniform());
    Vec3 a = uniform_sphere(rng), b = uniform_sphere(rng);
    if (std::abs(a.z) < 1e-3f || std::abs(b.z) < 1e-3f) continue;
    bool refl = a.z * b.z > 0;
    double fab = refl ? k::bsdf_mf_reflect_eval(m, a, b).x : k::bsdf_mf_transmit_eval(m, a, b).x;
    double fba = refl ? k::bsdf_mf_reflect_eval(m, b, a).x : k::bsdf_mf_transmit_eval(m, b, a).x;
    fab /= std::abs(b.z);
    fba /= std::abs(a.z);
    double rel = std::abs(fab - fba) / std::max({fab, fba, 1e-6});
    (refl ? worst_r : worst_t) = std::max(refl ? worst_r : worst_t, rel);
    ++(refl ? nr : nt);
  }
  std::printf("[reciprocity] microfacet R max rel %.3g (%d pairs), T max rel %.3g (%d pairs)\n",
              worst_r, nr, worst_t, nt);
  EXPECT_LT(worst_r, 1e-4);
  EXPECT_LT(worst_t, 1e-4);
}

TEST(BsdfMicrofacet, SampleWeightAndPdfAgreeWithEvalAndPdf) {
  Rng rng(9);
  double worst_w = 0, worst_p = 0;
  int n = 0;
  for (int i = 0; i < 200000; ++i) {
    k::KMicrofacet m = k::bsdf_mf_make(0.02f + 0.98f * rng.uniform(), 0.02f + 0.98f * rng.uniform(),
                                       1.f + 2.f * rng.uniform());
    Vec3 wo = uniform_sphere(rng);
    if (std::abs(wo.z) < 1e-4f) continue;
    bool trans = (i % 2) == 1;
    k::KBsdfSample s = trans ? k::bsdf_mf_transmit_sample(m, wo, rng.uniform(), rng.uniform())
                             : k::bsdf_mf_reflect_sample(m, wo, rng.uniform(), rng.uniform());
    if (s.pdf <= 0) continue;
    EXPECT_EQ(s.flags, trans ? KB_TRANSMIT : KB_REFLECT);
    EXPECT_EQ(trans, wo.z * s.wi.z < 0);
    double pdf = trans ? k::bsdf_mf_transmit_pdf(m, wo, s.wi) : k::bsdf_mf_reflect_pdf(m, wo, s.wi);
    double ev = trans ? k::bsdf_mf_transmit_eval(m, wo, s.wi).x : k::bsdf_mf_reflect_eval(m, wo, s.wi).x;
    worst_p = std::max(worst_p, std::abs(s.pdf - pdf) / pdf);
    // Relative 2e-3, or 1e-5 absolute: at grazing wo the half vector
    // recomputed from (wo, wi) in float moves F(wo.h) visibly while the
    // weight itself is ~1e-5.
    worst_w = std::max(worst_w, std::abs(s.weight.x - ev / pdf) / (ev / pdf + 5e-3));
    ++n;
  }
  std::printf("[consistency] microfacet: %d samples, max rel |pdf - pdf()| %.3g, |w - eval/pdf| %.3g\n",
              n, worst_p, worst_w);
  EXPECT_GT(n, 100000);
  EXPECT_LT(worst_p, 2e-3);
  EXPECT_LT(worst_w, 2e-3);
}

// Directional albedo by importance sampling: mean of the weights.
double albedo_mc(bool trans, const k::KMicrofacet& m, Vec3 wo, int n, uint64_t seed) {
  Rng rng(seed);
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    k::KBsdfSample s = trans ? k::bsdf_mf_transmit_sample(m, wo, rng.uniform(), rng.uniform())
                             : k::bsdf_mf_reflect_sample(m, wo, rng.uniform(), rng.uniform());
    sum += s.weight.x;
  }
  return sum / n;
}

TEST(BsdfMicrofacet, SmoothLimitIsTheFresnelSlab) {
  // Nearly smooth faces: reflection carries F(mu_o), the ballistic transmission
  // through both faces (1 - F(mu_o))^2.
  for (double eta : {1.33, 1.55, 2.4}) {
    for (double th : {0.0, 45.0, 70.0}) {
      Vec3 wo = dir_deg(th, 20.0);
      k::KMicrofacet m = k::bsdf_mf_make(0.01f, 0.01f, float(eta));
      double f = fresnel_ref(std::cos(th * kPi / 180.0), eta);
      EXPECT_NEAR(albedo_mc(false, m, wo, 20000, 3), f, 0.01 * f + 1e-4) << eta << " " << th;
      EXPECT_NEAR(albedo_mc(true, m, wo, 20000, 4), (1 - f) * (1 - f), 0.01) << eta << " " << th;
    }
  }
  // Index-matched slab: no reflection at all.
  k::KMicrofacet m1 = k::bsdf_mf_make(0.3f, 0.3f, 1.f);
  EXPECT_EQ(albedo_mc(false, m1, dir_deg(30, 0), 1000, 5), 0.0);
}

TEST(BsdfMicrofacet, SpecularAlbedoNeverExceedsOne) {
  // E_R + E_T <= E[F + (1 - F)^2] <= 1 for every wo.
  double worst = 0;
  for (double eta : {1.0, 1.55, 3.0})
    for (float a : {0.05f, 0.4f, 1.f})
      for (double th : {0.0, 60.0, 85.0, 89.9}) {
        k::KMicrofacet m = k::bsdf_mf_make(a, a, float(eta));
        Vec3 wo = dir_deg(th, 0);
        double e = albedo_mc(false, m, wo, 20000, 7) + albedo_mc(true, m, wo, 20000, 8);
        worst = std::max(worst, e);
      }
  std::printf("[furnace] microfacet R + T max albedo %.4f\n", worst);
  EXPECT_LE(worst, 1.0 + 1e-3);
}

TEST(BsdfMicrofacet, GrazingAndDegenerateDirectionsStayFinite) {
  const Vec3 dirs[] = {v3(0, 0, 1), v3(0, 0, -1), v3(1, 0, 0), v3(0, 1, 0),
                       normalized(v3(1, 0, 1e-6)), normalized(v3(0, 1, -1e-6)),
                       normalized(v3(0.6, 0.8, 1e-7)), normalized(v3(1, 1, 1))};
  for (float a : {1e-6f, 1e-3f, 0.3f, 1.f}) {
    k::KMicrofacet m = k::bsdf_mf_make(a, 1.f - 0.9f * a, 1.7f);
    for (Vec3 wo : dirs) {
      for (Vec3 wi : dirs) {
        for (int t = 0; t < 2; ++t) {
          float e = t ? k::bsdf_mf_transmit_eval(m, wo, wi).x : k::bsdf_mf_reflect_eval(m, wo, wi).x;
          float p = t ? k::bsdf_mf_transmit_pdf(m, wo, wi) : k::bsdf_mf_reflect_pdf(m, wo, wi);
          EXPECT_TRUE(std::isfinite(e) && e >= 0) << e;
          EXPECT_TRUE(std::isfinite(p) && p >= 0) << p;
        }
      }
      for (float u : {0.f, 0.25f, 0.5f, 0.99999994f}) {
        k::KBsdfSample s = k::bsdf_mf_reflect_sample(m, wo, u, 1.f - u);
        EXPECT_TRUE(std::isfinite(s.weight.x) && s.weight.x >= 0 && std::isfinite(s.pdf) && s.pdf >= 0);
        s = k::bsdf_mf_transmit_sample(m, wo, u, u);
        EXPECT_TRUE(std::isfinite(s.weight.x) && s.weight.x >= 0 && std::isfinite(s.pdf) && s.pdf >= 0);
      }
    }
  }
}

TEST(BsdfMicrofacet, LeanCovarianceWidensRoughness) {
  // No extra covariance: the roughness is unchanged.
  k::KLeanRoughness r = k::bsdf_lean_to_ggx(0.2f, 0.5f, 0.f, 0.f, 0.f);
  EXPECT_NEAR(std::min(r.alpha_u, r.alpha_v), 0.2f, 1e-6);
  EXPECT_NEAR(std::max(r.alpha_u, r.alpha_v), 0.5f, 1e-6);
  // Beckmann slope variance alpha^2 / 2 adds: sqrt(alpha^2 + beta^2).
  r = k::bsdf_lean_to_ggx(0.3f, 0.3f, 0.5f * 0.4f * 0.4f, 0.f, 0.5f * 0.4f * 0.4f);
  EXPECT_NEAR(r.alpha_u, 0.5f, 1e-6);
  EXPECT_NEAR(r.alpha_v, 0.5f, 1e-6);
  // A covariance along a rotated axis: eigen-decomposition in double.
  Rng rng(2);
  for (int i = 0; i < 1000; ++i) {
    double ax = 0.05 + rng.uniform_d(), ay = 0.05 + rng.uniform_d();
    double l1 = 0.3 * rng.uniform_d(), l2 = 0.3 * rng.uniform_d(), th = kPi * (rng.uniform_d() - 0.5);
    double c = std::cos(th), s = std::sin(th);
    double sxx = l1 * c * c + l2 * s * s, syy = l1 * s * s + l2 * c * c, sxy = (l1 - l2) * c * s;
    r = k::bsdf_lean_to_ggx(float(ax), float(ay), float(sxx), float(sxy), float(syy));
    double cxx = ax * ax / 2 + sxx, cyy = ay * ay / 2 + syy;
    // The u axis is an eigenvector of C with eigenvalue alpha_u^2 / 2.
    double cu = r.cos_u, su = r.sin_u;
    EXPECT_NEAR(cu * cu + su * su, 1.0, 1e-6);
    EXPECT_GE(cu, 0.0);
    double lu = cxx * cu * cu + 2 * sxy * cu * su + cyy * su * su;
    double lv = cxx * su * su - 2 * sxy * cu * su + cyy * cu * cu;
    double off = (cyy - cxx) * cu * su + sxy * (cu * cu - su * su);
    EXPECT_NEAR(off, 0.0, 1e-5);
    EXPECT_NEAR(r.alpha_u, std::sqrt(2 * lu), 1e-4);
    EXPECT_NEAR(r.alpha_v, std::sqrt(2 * lv), 1e-4);
    EXPECT_GE(r.alpha_u, r.alpha_v - 1e-6);
  }
}

TEST(BsdfMicrofacet, SlabRoughnessRelation) {
  EXPECT_NEAR(k::bsdf_mf_slab_alpha(0.4f, 1.5f), 0.4 * (1 - 1 / 1.5) / std::sqrt(2.0), 1e-6);
  EXPECT_EQ(k::bsdf_mf_slab_alpha(0.4f, 1.f), KB_ALPHA_MIN);
}

}  // namespace
