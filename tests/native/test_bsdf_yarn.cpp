// The whole near-field yarn BSDF (native/kernel/yarn_bsdf.h, paper Eq. 1):
// white furnace, reciprocity, eval/pdf/sample agreement, robustness over
// randomised parameters and degenerate directions, delta transmission through
// gaps, and the validated host wrapper (knit/bsdf.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

k::KYarnBsdf make_yarn(float ax, float ay, float tax, float tay, float eta, Vec3 kr, Vec3 kt, float B,
                       float r, float G, float D, int layers) {
  return k::yarn_bsdf_make(k::bsdf_mf_make(ax, ay, eta), k::bsdf_mf_make(tax, tay, eta), kr, kt, B, r, G,
                           k::bsdf_att_make(D, layers));
}

k::KYarnBsdf random_yarn(Rng& rng) {
  auto pick = [&](float lo, float hi) {
    float u = rng.uniform();
    // Hit the ends of the ranges exactly now and then.
    if (u < 0.1f) return lo;
    if (u > 0.9f) return hi;
    return lo + (hi - lo) * rng.uniform();
  };
  Vec3 kr{pick(0, 1), pick(0, 1), pick(0, 1)}, kt{pick(0, 1), pick(0, 1), pick(0, 1)};
  return make_yarn(pick(1e-6f, 1), pick(1e-6f, 1), pick(1e-6f, 1), pick(1e-6f, 1), pick(1, 3), kr, kt,
                   pick(0, 1), pick(0, 1), pick(0, 1), pick(0, 50), int(rng.uniform() * 7));
}

// Directional albedo int eval dw_i by importance sampling (mean weight), with
// its standard error.
struct Albedo {
  double mean, se;
};
Albedo albedo(const k::KYarnBsdf& p, Vec3 wo, int n, uint64_t seed) {
  Rng rng(seed);
  double s = 0, s2 = 0;
  for (int i = 0; i < n; ++i) {
    k::KBsdfSample smp = k::yarn_bsdf_sample(p, wo, rng.uniform(), rng.uniform());
    double w = maxc(smp.weight);
    s += w;
    s2 += w * w;
  }
  double m = s / n;
  return {m, std::sqrt(std::max(0.0, s2 / n - m * m) / n)};
}

TEST(BsdfYarn, WhiteFurnaceAlbedoNeverExceedsOne) {
  // Colours, G and tau all 1 (D = 0). The albedo is linear in B and r, so
  // their extreme combinations bound every other.
  const float rough[][2] = {{0.05f, 0.05f}, {0.3f, 0.3f}, {1.f, 1.f}, {0.1f, 0.8f}};
  const float br[][2] = {{0.f, 0.f}, {1.f, 0.f}, {1.f, 1.f}};
  const Vec3 white{1.f, 1.f, 1.f};
  double worst = 0, worst_se = 0, worst_dielectric = 0;
  std::string where;
  for (float eta : {1.f, 1.33f, 1.55f, 2.f, 3.f})
    for (auto& a : rough)
      for (auto& b : br) {
        k::KYarnBsdf p = make_yarn(a[0], a[1], a[0], a[1], eta, white, white, b[0], b[1], 1.f, 0.f, 1);
        for (double th : {0.0, 20.0, 40.0, 60.0, 75.0, 85.0, 89.0, 89.9}) {
          Albedo e = albedo(p, dir_deg(th, 30.0), 16000, 77);
          EXPECT_LE(e.mean, 1.0 + 4 * e.se + 1e-3)
              << "eta " << eta << " alpha " << a[0] << "," << a[1] << " B " << b[0] << " r " << b[1]
              << " theta " << th;
          if (eta > 1.f) worst_dielectric = std::max(worst_dielectric, e.mean);
          if (e.mean > worst) {
            worst = e.mean;
            worst_se = e.se;
            where = "eta " + std::to_string(eta) + " alpha " + std::to_string(a[0]) + "," +
                    std::to_string(a[1]) + " B " + std::to_string(b[0]) + " r " + std::to_string(b[1]) +
                    " theta " + std::to_string(th);
          }
        }
      }
  std::printf("[furnace] yarn BSDF max directional albedo %.4f +- %.4f at %s; max for eta > 1: %.4f\n",
              worst, worst_se, where.c_str(), worst_dielectric);
  RecordProperty("max_albedo", std::to_string(worst));
}

TEST(BsdfYarn, FurnaceByQuadratureAgreesWithSampling) {
  // Deterministic cross-check of the sampling-based albedo (no reliance on
  // sample() covering the support) for a few cases.
  const Vec3 white{1.f, 1.f, 1.f};
  struct C {
    float a, eta, B, r;
    double th;
  } cs[] = {{0.3f, 1.55f, 1.f, 0.f, 0.0}, {0.3f, 1.55f, 1.f, 1.f, 60.0}, {0.5f, 3.f, 0.f, 0.f, 30.0},
            {1.f, 1.33f, 1.f, 0.f, 85.0}};
  for (auto& c : cs) {
    k::KYarnBsdf p = make_yarn(c.a, c.a, c.a, c.a, c.eta, white, white, c.B, c.r, 1.f, 0.f, 1);
    Vec3 wo = dir_deg(c.th, 10.0);
    DirFn f = [&](Vec3 wi) { return maxc(k::yarn_bsdf_eval(p, wo, wi)); };
    double quad = integrate_sphere(f, 32, 32, 1e-6);
    Albedo mc = albedo(p, wo, 100000, 5);
    EXPECT_LE(quad, 1.0);
    EXPECT_NEAR(mc.mean, quad, 5 * mc.se + 2e-3) << c.a << " " << c.eta << " " << c.th;
  }
}

TEST(BsdfYarn, EvalIsReciprocal) {
  Rng rng(21);
  double worst = 0;
  for (int i = 0; i < 100000; ++i) {
    k::KYarnBsdf p = random_yarn(rng);
    p.spec_r = k::bsdf_mf_make(std::max(p.spec_r.alpha_x, 0.02f), std::max(p.spec_r.alpha_y, 0.02f), p.spec_r.eta);
    p.spec_t = k::bsdf_mf_make(std::max(p.spec_t.alpha_x, 0.02f), std::max(p.spec_t.alpha_y, 0.02f), p.spec_t.eta);
    p.atten.optical_depth = std::min(p.atten.optical_depth, 5.f);
    Vec3 a = uniform_sphere(rng), b = uniform_sphere(rng);
    if (std::abs(a.z) < 1e-3f || std::abs(b.z) < 1e-3f) continue;
    Vec3 fab = k::yarn_bsdf_eval(p, a, b), fba = k::yarn_bsdf_eval(p, b, a);
    const float* x = &fab.x;
    const float* y = &fba.x;
    for (int c = 0; c < 3; ++c) {
      double u = x[c] / std::abs(b.z), v = y[c] / std::abs(a.z);
      worst = std::max(worst, std::abs(u - v) / std::max({u, v, 1e-4}));
    }
  }
  std::printf("[reciprocity] yarn BSDF max relative asymmetry %.3g\n", worst);
  EXPECT_LT(worst, 2e-4);
}

TEST(BsdfYarn, EvalIsTheSumOfItsLobes) {
  Rng rng(22);
  for (int i = 0; i < 20000; ++i) {
    k::KYarnBsdf p = random_yarn(rng);
    Vec3 wo = uniform_sphere(rng), wi = uniform_sphere(rng);
    Vec3 e = k::yarn_bsdf_eval(p, wo, wi);
    double sum = 0;
    for (int l = 0; l < YB_NUM_LOBES; ++l) sum += k::yarn_bsdf_lobe_eval(p, l, wo, wi).y;
    EXPECT_NEAR(e.y, sum, 1e-5 * std::max(1.0, sum));
  }
}

TEST(BsdfYarn, SampleAgreesWithEvalAndPdf) {
  Rng rng(23);
  double worst_p = 0, worst_w = 0;
  int n = 0, reflect = 0, transmit = 0;
  for (int i = 0; i < 100000; ++i) {
    k::KYarnBsdf p = random_yarn(rng);
    Vec3 wo = uniform_sphere(rng);
    k::KBsdfSample s = k::yarn_bsdf_sample(p, wo, rng.uniform(), rng.uniform());
    if (s.pdf <= 0) {
      EXPECT_EQ(s.flags, 0);
      EXPECT_EQ(maxc(s.weight), 0.0);
      continue;
    }
    ++n;
    bool refl = wo.z * s.wi.z > 0;
    (refl ? reflect : transmit)++;
    EXPECT_EQ(s.flags, refl ? KB_REFLECT : KB_TRANSMIT);
    float pdf = k::yarn_bsdf_pdf(p, wo, s.wi);
    Vec3 e = k::yarn_bsdf_eval(p, wo, s.wi);
    worst_p = std::max(worst_p, double(std::abs(s.pdf - pdf) / pdf));
    worst_w = std::max(worst_w, std::abs(s.weight.x - e.x / pdf) / (e.x / pdf + 1e-3));
  }
  std::printf("[consistency] yarn: %d samples (%d R, %d T), max rel |pdf - pdf()| %.3g, |w - eval/pdf| %.3g\n",
              n, reflect, transmit, worst_p, worst_w);
  EXPECT_GT(reflect, 10000);
  EXPECT_GT(transmit, 10000);
  EXPECT_LT(worst_p, 1e-6);
  EXPECT_LT(worst_w, 1e-5);
}

// The sampler's one-pass eval and pdf (yarn_bsdf_eval_pdf_with) and its
// direction-only microfacet sample (mf_sample_dir_up) are shortcuts: they
// must give what the separate functions give, bit for bit, grazing and
// degenerate directions included.
TEST(BsdfYarn, OnePassEvalPdfAndDirectionOnlySampleAreTheSeparateFunctions) {
  Rng rng(41);
  int compared = 0, refl = 0, trans = 0, zero = 0, dir_ok = 0, dir_fail = 0;
  for (int i = 0; i < 200000; ++i) {
    k::KYarnBsdf p = random_yarn(rng);
    Vec3 wo = uniform_sphere(rng), wi = uniform_sphere(rng);
    if (i % 10 == 1) wo.z = (rng.uniform() - 0.5f) * 1e-6f;  // grazing
    if (i % 10 == 2) wi.z = 0;                              // in the tangent plane
    if (i % 10 == 3) wi = Vec3{-wo.x, -wo.y, -wo.z};        // straight through
    const k::KYarnLobeProbs q = k::yarn_bsdf_lobe_probs(p, wo);
    const k::KYarnEvalPdf e = k::yarn_bsdf_eval_pdf_with(p, q, wo, wi);
    const Vec3 f = k::yarn_bsdf_eval(p, wo, wi);
    const float pdf = k::yarn_bsdf_pdf_with(p, q, wo, wi);
    ASSERT_EQ(std::memcmp(&e.f, &f, sizeof f), 0) << "eval at sample " << i;
    ASSERT_EQ(std::memcmp(&e.pdf, &pdf, sizeof pdf), 0) << "pdf at sample " << i;
    ++compared;
    (pdf == 0 ? zero : (wo.z * wi.z > 0 ? refl : trans))++;

    // The microfacet lobes' samples from the upper side: the same direction,
    // failing in the same cases.
    const k::KMicrofacet m = rng.uniform() < 0.5f ? p.spec_r : p.spec_t;
    const Vec3 o{wo.x, wo.y, std::fabs(wo.z)};
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const k::KBsdfSample full = k::mf_sample_up(m, o, u1, u2, 0);
    const k::KBsdfSample dir = k::mf_sample_dir_up(m, o, u1, u2);
    ASSERT_EQ(full.pdf > 0, dir.pdf > 0) << "sample " << i;
    if (full.pdf > 0) {
      ASSERT_EQ(std::memcmp(&full.wi, &dir.wi, sizeof full.wi), 0) << "direction at sample " << i;
      ++dir_ok;
    } else {
      ++dir_fail;
    }
  }
  std::printf("[one pass] %d eval/pdf pairs identical (%d R, %d T, %d zero); %d microfacet samples the same "
              "direction, %d failing in both\n",
              compared, refl, trans, zero, dir_ok, dir_fail);
  EXPECT_GT(refl, 50000);
  EXPECT_GT(trans, 50000);
  EXPECT_GT(zero, 10000);
  EXPECT_GT(dir_fail, 100);  // the failure cases were reached
}

TEST(BsdfYarn, LobeProbabilitiesFollowTheParameters) {
  const Vec3 grey{0.5f, 0.5f, 0.5f};
  Vec3 wo = dir_deg(30, 0);
  k::KYarnLobeProbs q = k::yarn_bsdf_lobe_probs(make_yarn(0.3f, 0.3f, 0.3f, 0.3f, 1.5f, grey, grey, 0.7f, 0.6f, 1, 1, 1), wo);
  EXPECT_NEAR(q.p0 + q.p1 + q.p2 + q.p3, 1.0, 1e-6);
  EXPECT_GT(std::min({q.p0, q.p1, q.p2, q.p3}), 0.f);
  // Index-matched: no specular reflection lobe. B = 1: no specular transmission.
  q = k::yarn_bsdf_lobe_probs(make_yarn(0.3f, 0.3f, 0.3f, 0.3f, 1.f, grey, grey, 1.f, 0.6f, 1, 1, 1), wo);
  EXPECT_EQ(q.p0, 0.f);
  EXPECT_EQ(q.p1, 0.f);
  // r = 1 with black colours: no body lobes; everything on the specular lobes.
  q = k::yarn_bsdf_lobe_probs(make_yarn(0.3f, 0.3f, 0.3f, 0.3f, 1.5f, Vec3{0, 0, 0}, grey, 0.5f, 1.f, 1, 1, 1), wo);
  EXPECT_EQ(q.p2, 0.f);
  EXPECT_EQ(q.p3, 0.f);
  // Nothing at all: sampling fails cleanly.
  k::KYarnBsdf none = make_yarn(0.3f, 0.3f, 0.3f, 0.3f, 1.f, Vec3{0, 0, 0}, Vec3{0, 0, 0}, 1.f, 0.5f, 1, 1, 1);
  k::KBsdfSample s = k::yarn_bsdf_sample(none, wo, 0.5f, 0.5f);
  EXPECT_EQ(s.pdf, 0.f);
  EXPECT_EQ(s.flags, 0);
}

TEST(BsdfYarn, NoNanInfOrNegativeValuesAnywhere) {
  Rng rng(24);
  std::vector<Vec3> dirs = {v3(0, 0, 1), v3(0, 0, -1), v3(1, 0, 0), v3(0, 1, 0), v3(0, -1, 0),
                            normalized(v3(1, 0, 1e-6)), normalized(v3(0, 1, -1e-6)),
                            normalized(v3(-0.6, 0.8, 1e-6)), normalized(v3(0.3, -0.2, -1e-6)),
                            normalized(v3(1, 1, 1)), normalized(v3(1, -1, -1))};
  for (int i = 0; i < 40; ++i) dirs.push_back(uniform_sphere(rng));
  long checked = 0;
  for (int t = 0; t < 400; ++t) {
    k::KYarnBsdf p = random_yarn(rng);
    for (Vec3 wo : dirs) {
      Vec3 cand[] = {dirs[size_t(rng.next() % dirs.size())], v3(-wo.x, -wo.y, -wo.z), wo,
                     v3(-wo.x, -wo.y, wo.z), v3(wo.x, wo.y, -wo.z)};
      for (Vec3 wi : cand) {
        Vec3 e = k::yarn_bsdf_eval(p, wo, wi);
        float pdf = k::yarn_bsdf_pdf(p, wo, wi);
        ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z) && std::isfinite(pdf));
        ASSERT_TRUE(e.x >= 0 && e.y >= 0 && e.z >= 0 && pdf >= 0);
        ++checked;
      }
      for (float u1 : {0.f, 0.3f, 0.99999994f}) {
        for (float u2 : {0.f, 0.7f, 0.99999994f}) {
          k::KBsdfSample s = k::yarn_bsdf_sample_gaps(p, rng.uniform() < 0.5f ? 0.f : rng.uniform(), wo,
                                                      rng.uniform(), u1, u2);
          ASSERT_TRUE(std::isfinite(s.weight.x) && std::isfinite(s.weight.y) && std::isfinite(s.weight.z) &&
                      std::isfinite(s.pdf) && std::isfinite(s.wi.x) && std::isfinite(s.wi.y) &&
                      std::isfinite(s.wi.z));
          ASSERT_TRUE(s.weight.x >= 0 && s.weight.y >= 0 && s.weight.z >= 0 && s.pdf >= 0);
          if (maxc(s.weight) > 0) ASSERT_GT(s.pdf, 0.f);
          if (s.pdf > 0) ASSERT_NEAR(double(s.wi.x) * s.wi.x + double(s.wi.y) * s.wi.y + double(s.wi.z) * s.wi.z, 1.0, 1e-5);
          ++checked;
        }
      }
    }
  }
  std::printf("[robustness] %ld evaluations and samples, all finite and non-negative\n", checked);
}

TEST(BsdfYarn, DeltaTransmissionThroughGaps) {
  const Vec3 grey{0.6f, 0.6f, 0.6f};
  k::KYarnBsdf p = make_yarn(0.2f, 0.4f, 0.3f, 0.5f, 1.55f, grey, grey, 0.7f, 0.6f, 0.9f, 1.f, 1);
  Vec3 wo = dir_deg(40, 15);
  Rng rng(31);
  const float pd = 0.3f;
  const int n = 200000;
  int pass = 0;
  for (int i = 0; i < n; ++i) {
    k::KBsdfSample s = k::yarn_bsdf_sample_gaps(p, pd, wo, rng.uniform(), rng.uniform(), rng.uniform());
    if (s.flags == KB_TRANSMIT + KB_DELTA) {
      ++pass;
      EXPECT_EQ(s.wi.x, -wo.x);
      EXPECT_EQ(s.wi.y, -wo.y);
      EXPECT_EQ(s.wi.z, -wo.z);
      EXPECT_EQ(s.weight.x, 1.f);
      EXPECT_FLOAT_EQ(s.pdf, pd);
    } else if (s.pdf > 0) {
      // The BSDF branch: weight is eval/pdf of the yarn, its pdf scaled by 1 - p_delta.
      EXPECT_NEAR(s.pdf, (1 - pd) * k::yarn_bsdf_pdf(p, wo, s.wi), 1e-6 * s.pdf);
      EXPECT_NEAR(s.weight.x, k::yarn_bsdf_eval_gaps(p, pd, wo, s.wi).x / k::yarn_bsdf_pdf_gaps(p, pd, wo, s.wi),
                  1e-5 * (1 + s.weight.x));
    }
  }
  double frac = double(pass) / n, sd = std::sqrt(pd * (1 - pd) / n);
  std::printf("[delta] pass-through fraction %.4f for p_delta %.2f (sd %.4f)\n", frac, pd, sd);
  EXPECT_NEAR(frac, pd, 5 * sd);
  // The limits: always / never through.
  EXPECT_EQ(k::yarn_bsdf_sample_gaps(p, 1.f, wo, 0.99999994f, 0.5f, 0.5f).flags, KB_TRANSMIT + KB_DELTA);
  EXPECT_NE(k::kb_has_flag(k::yarn_bsdf_sample_gaps(p, 0.f, wo, 0.f, 0.5f, 0.5f).flags, KB_DELTA), 1);
  EXPECT_EQ(k::yarn_bsdf_eval_gaps(p, 1.f, wo, dir_deg(150, 0)).x, 0.f);
  // The rescaled random number of the choice stays in [0, 1).
  for (float u : {0.f, 0.1f, 0.29999998f, 0.3f, 0.5f, 0.99999994f}) {
    k::KDeltaChoice c = k::bsdf_delta_choose(pd, u);
    EXPECT_GE(c.u, 0.f);
    EXPECT_LT(c.u, 1.f);
    EXPECT_FLOAT_EQ(c.prob, c.pass ? pd : 1 - pd);
  }
  EXPECT_EQ(k::kb_has_flag(KB_TRANSMIT + KB_DELTA, KB_DELTA), 1);
  EXPECT_EQ(k::kb_has_flag(KB_TRANSMIT + KB_DELTA, KB_REFLECT), 0);
  EXPECT_EQ(k::kb_has_flag(KB_TRANSMIT + KB_DELTA, KB_TRANSMIT), 1);
}

// ---- Host wrapper ------------------------------------------------------------

void expect_invalid(const YarnBsdfParams& p, const std::string& needle) {
  try {
    p.validate();
    ADD_FAILURE() << "accepted invalid parameters, expected an error naming " << needle;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(BsdfHost, ValidationNamesTheFieldAndValue) {
  YarnBsdfParams ok;
  EXPECT_NO_THROW(ok.validate());
  auto with = [&](auto change) {
    YarnBsdfParams p = ok;
    change(p);
    return p;
  };
  expect_invalid(with([](auto& p) { p.roughness_x = 0.f; }), "roughness_x = 0");
  expect_invalid(with([](auto& p) { p.roughness_y = 1.5f; }), "roughness_y = 1.5");
  expect_invalid(with([](auto& p) { p.trans_roughness_x = NAN; }), "trans_roughness_x = nan");
  expect_invalid(with([](auto& p) { p.trans_roughness_y = -1.f; }), "trans_roughness_y = -1");
  expect_invalid(with([](auto& p) { p.eta = 0.9f; }), "eta = 0.9");
  expect_invalid(with([](auto& p) { p.eta = 3.5f; }), "eta = 3.5");
  expect_invalid(with([](auto& p) { p.body_energy = 1.25f; }), "body_energy = 1.25");
  expect_invalid(with([](auto& p) { p.body_reflect = -0.5f; }), "body_reflect = -0.5");
  expect_invalid(with([](auto& p) { p.optical_depth = INFINITY; }), "optical_depth = inf");
  expect_invalid(with([](auto& p) { p.reflect_colors = {Rgb{0.5f, 1.5f, 0.f}}; }), "reflect_colors[0].g = 1.5");
  expect_invalid(with([](auto& p) {
                   p.reflect_colors = {Rgb{}, Rgb{}};
                   p.transmit_colors = {Rgb{}, Rgb{0.f, 0.f, -0.25f}};
                 }),
                 "transmit_colors[1].b = -0.25");
  expect_invalid(with([](auto& p) { p.transmit_colors = {Rgb{}, Rgb{}}; }), "transmit_colors.size() = 2");
  expect_invalid(with([](auto& p) { p.reflect_colors.clear(); }), "reflect_colors.size() = 0");
  EXPECT_THROW(YarnBsdf(with([](auto& p) { p.eta = 0.f; })), std::invalid_argument);
}

TEST(BsdfHost, PointAndDirectionsAreChecked) {
  YarnBsdfParams p;
  p.reflect_colors = {Rgb{1, 0, 0}, Rgb{0, 1, 0}};
  p.transmit_colors = {Rgb{0.5f, 0, 0}, Rgb{0, 0.5f, 0}};
  YarnBsdf b(p);
  Vec3 wo = dir_deg(30, 0), wi = dir_deg(40, 180);
  EXPECT_THROW(b.eval(wo, wi, BsdfPoint{2, 1, 1.f, 0.f}), std::invalid_argument);   // colour
  EXPECT_THROW(b.eval(wo, wi, BsdfPoint{0, 0, 1.f, 0.f}), std::invalid_argument);   // layers
  EXPECT_THROW(b.eval(wo, wi, BsdfPoint{0, 1, 1.5f, 0.f}), std::invalid_argument);  // shadow
  EXPECT_THROW(b.eval(wo, wi, BsdfPoint{0, 1, 1.f, -0.1f}), std::invalid_argument); // p_delta
  EXPECT_THROW(b.eval(v3(0, 0, 2), wi), std::invalid_argument);
  EXPECT_THROW(b.pdf(wo, v3(NAN, 0, 1)), std::invalid_argument);
  EXPECT_THROW(b.sample(wo, {0.5f, 1.f, 0.5f}), std::invalid_argument);
  try {
    b.eval(wo, wi, BsdfPoint{5, 1, 1.f, 0.f});
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("BsdfPoint.color = 5"), std::string::npos) << e.what();
  }
  // The colour index selects the body colours: red reflects, green does not.
  Rgb e0 = b.eval(wo, wi, BsdfPoint{0, 1, 1.f, 0.f});
  Rgb e1 = b.eval(wo, wi, BsdfPoint{1, 1, 1.f, 0.f});
  EXPECT_GT(e0.r, e1.r);
  EXPECT_GT(e1.g, e0.g);
  // Host and kernel agree; p_delta scales eval and pdf.
  BsdfPoint pt{1, 2, 0.7f, 0.25f};
  Vec3 ke = k::yarn_bsdf_eval(b.kernel(pt), wo, wi);
  Rgb he = b.eval(wo, wi, pt);
  EXPECT_FLOAT_EQ(he.g, 0.75f * ke.y);
  EXPECT_FLOAT_EQ(b.pdf(wo, wi, pt), 0.75f * k::yarn_bsdf_pdf(b.kernel(pt), wo, wi));
  BsdfSample s = b.sample(wo, {0.9f, 0.3f, 0.6f}, pt);
  EXPECT_TRUE(s.valid());
  auto probs = b.lobe_probabilities(wo, pt);
  EXPECT_NEAR(probs[0] + probs[1] + probs[2] + probs[3], 1.f, 1e-6);
  Rgb sum{0, 0, 0};
  for (Lobe l : {Lobe::SpecularReflection, Lobe::SpecularTransmission, Lobe::BodyReflection,
                 Lobe::BodyTransmission}) {
    Rgb c = b.eval_lobe(l, wo, wi, pt);
    sum.g += c.g;
  }
  EXPECT_NEAR(sum.g * 0.75f, he.g, 1e-6);
}

}  // namespace
