// Chi-square goodness of fit of every lobe's sample() against its pdf(), and
// of the whole yarn BSDF mixture, over roughness (isotropic and anisotropic),
// eta, the body parameters and incidence angles up to 85 degrees (and views
// from below the surface). Significance 0.01 overall, Sidak-corrected over all
// the cases of this file. On failure the observed and expected histograms are
// written to $build/test-output/bsdf_chi2/ (CSV and a PGM image).
#include <gtest/gtest.h>

#include <cstdio>
#include <ostream>
#include <string>
#include <vector>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

enum class Kind { SpecR, SpecT, BodyR, BodyT, Yarn };

struct Case {
  std::string name;
  Kind kind = Kind::Yarn;
  float ax = 0.3f, ay = 0.3f;    // roughness of the sampled specular lobe (f_R for Yarn)
  float tax = 0.3f, tay = 0.6f;  // f_T roughness (Yarn)
  float eta = 1.55f;
  double theta_o = 0, phi_o = 0;  // degrees
  float B = 0.7f, r = 0.6f, D = 1.0f, shadow = 1.0f;
  int layers = 1;
};

// gtest prints test parameters in test names and listings: print the name.
void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

std::string angle_tag(double t) { return "th" + std::to_string(int(t)); }

std::vector<Case> make_cases() {
  std::vector<Case> v;
  const float rough[][2] = {{0.1f, 0.1f}, {0.3f, 0.3f}, {0.7f, 0.7f},
                            {1.0f, 1.0f}, {0.1f, 0.5f}, {0.6f, 0.15f}};
  const double thetas[] = {0.0, 30.0, 60.0, 85.0};
  for (int kind = 0; kind < 2; ++kind) {
    for (auto& a : rough) {
      for (double t : thetas) {
        Case c;
        c.kind = kind == 0 ? Kind::SpecR : Kind::SpecT;
        c.ax = a[0];
        c.ay = a[1];
        c.theta_o = t;
        c.phi_o = 35.0;
        c.name = std::string(kind == 0 ? "SpecR" : "SpecT") + "_a" +
                 std::to_string(int(a[0] * 100)) + "x" + std::to_string(int(a[1] * 100)) + "_" +
                 angle_tag(t);
        v.push_back(c);
      }
    }
  }
  // Views from below the surface (two-sided lobes).
  for (int kind = 0; kind < 2; ++kind) {
    Case c;
    c.kind = kind == 0 ? Kind::SpecR : Kind::SpecT;
    c.ax = 0.25f;
    c.ay = 0.5f;
    c.theta_o = 130.0;
    c.phi_o = -60.0;
    c.name = std::string(kind == 0 ? "SpecR" : "SpecT") + "_a25x50_below_th130";
    v.push_back(c);
  }
  for (int kind = 0; kind < 2; ++kind) {
    for (double t : {0.0, 45.0, 85.0, 150.0}) {
      Case c;
      c.kind = kind == 0 ? Kind::BodyR : Kind::BodyT;
      c.theta_o = t;
      c.phi_o = 10.0;
      c.name = std::string(kind == 0 ? "BodyR_LS" : "BodyT_Lambert") + "_" + angle_tag(t);
      v.push_back(c);
    }
  }
  // The mixture: default-ish, index-matched (no f_R), opaque body with eta 3
  // (no f_T), rough anisotropic with two layers and ply shadow.
  struct Mix {
    const char* tag;
    float ax, ay, tax, tay, eta, B, r, D, shadow;
    int layers;
  };
  const Mix mixes[] = {
      {"default", 0.15f, 0.45f, 0.3f, 0.6f, 1.55f, 0.7f, 0.6f, 1.0f, 1.0f, 1},
      {"eta1", 0.3f, 0.3f, 0.2f, 0.2f, 1.0f, 0.2f, 0.3f, 0.5f, 1.0f, 1},
      {"eta3_B1", 0.5f, 0.2f, 0.5f, 0.5f, 3.0f, 1.0f, 1.0f, 1.0f, 0.8f, 1},
      {"layers2", 0.8f, 1.0f, 1.0f, 0.7f, 1.33f, 0.4f, 0.5f, 2.0f, 0.5f, 2},
  };
  for (auto& m : mixes) {
    for (double t : {0.0, 45.0, 70.0, 85.0, 120.0}) {
      Case c;
      c.kind = Kind::Yarn;
      c.ax = m.ax;
      c.ay = m.ay;
      c.tax = m.tax;
      c.tay = m.tay;
      c.eta = m.eta;
      c.B = m.B;
      c.r = m.r;
      c.D = m.D;
      c.shadow = m.shadow;
      c.layers = m.layers;
      c.theta_o = t;
      c.phi_o = 75.0;
      c.name = std::string("Yarn_") + m.tag + "_" + angle_tag(t);
      v.push_back(c);
    }
  }
  return v;
}

const std::vector<Case>& cases() {
  static const std::vector<Case> v = make_cases();
  return v;
}

k::KYarnBsdf yarn_of(const Case& c) {
  return k::yarn_bsdf_make(k::bsdf_mf_make(c.ax, c.ay, c.eta), k::bsdf_mf_make(c.tax, c.tay, c.eta),
                           Vec3{0.9f, 0.6f, 0.3f}, Vec3{0.5f, 0.7f, 0.9f}, c.B, c.r, c.shadow,
                           k::bsdf_att_make(c.D, c.layers));
}

class BsdfChi2 : public ::testing::TestWithParam<Case> {};

TEST_P(BsdfChi2, SampleMatchesPdf) {
  const Case& c = GetParam();
  const Vec3 wo = dir_deg(c.theta_o, c.phi_o);
  const k::KMicrofacet mf = k::bsdf_mf_make(c.ax, c.ay, c.eta);
  const k::KLommelSeeliger ls = k::bsdf_ls_make(Vec3{0.8f, 0.8f, 0.8f});
  const k::KLambertTransmission lt = k::bsdf_lt_make(Vec3{0.8f, 0.8f, 0.8f});
  const k::KYarnBsdf yb = yarn_of(c);
  SampleFn sample;
  DirFn pdf;
  auto wrap = [](k::KBsdfSample s, Vec3* wi) {
    *wi = s.wi;
    return s.pdf > 0.f;
  };
  switch (c.kind) {
    case Kind::SpecR:
      sample = [&](float a, float b, Vec3* wi) { return wrap(k::bsdf_mf_reflect_sample(mf, wo, a, b), wi); };
      pdf = [&](Vec3 wi) { return double(k::bsdf_mf_reflect_pdf(mf, wo, wi)); };
      break;
    case Kind::SpecT:
      sample = [&](float a, float b, Vec3* wi) { return wrap(k::bsdf_mf_transmit_sample(mf, wo, a, b), wi); };
      pdf = [&](Vec3 wi) { return double(k::bsdf_mf_transmit_pdf(mf, wo, wi)); };
      break;
    case Kind::BodyR:
      sample = [&](float a, float b, Vec3* wi) { return wrap(k::bsdf_ls_sample(ls, wo, a, b), wi); };
      pdf = [&](Vec3 wi) { return double(k::bsdf_ls_pdf(ls, wo, wi)); };
      break;
    case Kind::BodyT:
      sample = [&](float a, float b, Vec3* wi) { return wrap(k::bsdf_lt_sample(lt, wo, a, b), wi); };
      pdf = [&](Vec3 wi) { return double(k::bsdf_lt_pdf(lt, wo, wi)); };
      break;
    case Kind::Yarn:
      sample = [&](float a, float b, Vec3* wi) { return wrap(k::yarn_bsdf_sample(yb, wo, a, b), wi); };
      pdf = [&](Vec3 wi) { return double(k::yarn_bsdf_pdf(yb, wo, wi)); };
      break;
  }
  Chi2Options opt;
  opt.significance = sidak(0.01, int(cases().size()));
  opt.seed = std::hash<std::string>{}(c.name);
  Chi2Outcome r = chi2_test(c.name, sample, pdf, opt);
  std::printf("[chi2] %-32s p = %.4f  chi2 = %8.1f  dof = %4d  int(pdf) = %.5f  failed = %.5f\n",
              c.name.c_str(), r.p_value, r.stat, r.dof, r.pdf_integral, r.fail_fraction);
  RecordProperty("p_value", std::to_string(r.p_value));
  EXPECT_TRUE(r.pass) << r.message << " (per-test significance " << opt.significance << ")";
  // The integral of the pdf and the observed share of failed samples agree.
  EXPECT_NEAR(r.pdf_integral + r.fail_fraction, 1.0, 5e-3) << c.name;
}

INSTANTIATE_TEST_SUITE_P(AllLobes, BsdfChi2, ::testing::ValuesIn(cases()),
                         [](const ::testing::TestParamInfo<Case>& info) { return info.param.name; });

// The chi-square machinery itself, against closed forms.
TEST(BsdfChi2Support, IncompleteGammaMatchesClosedForms) {
  for (double x : {0.01, 0.5, 1.0, 3.0, 10.0, 40.0}) {
    EXPECT_NEAR(gamma_q(1.0, x), std::exp(-x), 1e-12 * std::max(1.0, std::exp(-x)) + 1e-15);
    EXPECT_NEAR(gamma_q(0.5, x), std::erfc(std::sqrt(x)), 1e-12);
    // Q(2, x) = (1 + x) e^-x
    EXPECT_NEAR(gamma_q(2.0, x), (1.0 + x) * std::exp(-x), 1e-12);
  }
  // Large dof: the chi2 median is close to dof (1 - 2/(9 dof))^3.
  for (int dof : {100, 1000, 3000}) {
    double med = dof * std::pow(1.0 - 2.0 / (9.0 * dof), 3.0);
    EXPECT_NEAR(chi2_pvalue(med, dof), 0.5, 2e-3) << dof;
  }
  EXPECT_NEAR(sidak(0.01, 1), 0.01, 1e-15);
  EXPECT_LT(sidak(0.01, 80), 0.01 / 80 * 1.01);
}

}  // namespace
