// Sampling building blocks: distributions, warps, the environment map's
// importance sampling, Fresnel and the smooth dielectric.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "render/distribution.h"
#include "render/fresnel.h"
#include "render/light.h"
#include "render/materials.h"
#include "render/rng.h"
#include "render/sampling.h"

namespace knit::render {
namespace {

TEST(Distribution, OneDimensionalMatchesTheFunction) {
  const std::vector<float> f = {0, 1, 3, 0, 4};
  const Distribution1D d(f);
  EXPECT_DOUBLE_EQ(d.integral(), 8.0 / 5.0);
  std::vector<int> count(f.size(), 0);
  Pcg32 rng(1, 2);
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    float pdf = 0;
    size_t idx = 0;
    const float x = d.sample(rng.next_float(), pdf, idx);
    ASSERT_GE(x, 0.0f);
    ASSERT_LT(x, 1.0f);
    ASSERT_EQ(idx, static_cast<size_t>(x * 5));
    ASSERT_GT(f[idx], 0.0f) << "sampled a zero-probability step";
    ASSERT_FLOAT_EQ(pdf, d.pdf(idx));
    ++count[idx];
  }
  for (size_t i = 0; i < f.size(); ++i) EXPECT_NEAR(count[i] / double(n), f[i] / 8.0, 0.005) << i;
  EXPECT_FLOAT_EQ(d.discrete_pdf(2), 3.0f / 8.0f);
}

// The guide table only shortens the search: every u must land on the step
// a binary search over the same CDF (the definition: the last step whose
// cumulative start is <= u) finds, for smooth functions, runs of zeros, a
// spike, and u on and beside the guide's bucket edges.
TEST(Distribution, GuidedSearchFindsTheStepABinarySearchFinds) {
  Pcg32 rng(3, 4);
  std::vector<std::vector<float>> fs;
  std::vector<float> smooth(300), zeros(257, 0.0f), spike(1024, 1e-3f);
  for (size_t i = 0; i < smooth.size(); ++i) smooth[i] = 1.0f + std::sin(0.05f * float(i));
  for (size_t i = 100; i < 120; ++i) zeros[i] = float(i % 3);
  zeros[256] = 2.0f;
  spike[700] = 5000.0f;
  fs = {smooth, zeros, spike, {0, 1, 3, 0, 4}, {7}};
  for (const auto& f : fs) {
    const Distribution1D d(f);
    // The CDF as the class builds it, searched with std::upper_bound.
    std::vector<double> cdf(f.size() + 1, 0.0);
    for (size_t i = 0; i < f.size(); ++i) cdf[i + 1] = cdf[i] + double(f[i]) / double(f.size());
    const double total = cdf.back();
    for (double& c : cdf) c /= total;
    cdf.back() = 1.0;
    const auto reference = [&](double u) {
      const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
      return std::min<size_t>(size_t(std::max<std::ptrdiff_t>(0, (it - cdf.begin()) - 1)), f.size() - 1);
    };
    std::vector<float> us;
    for (int i = 0; i < 20000; ++i) us.push_back(rng.next_float());
    for (size_t b = 0; b < f.size(); ++b) {
      const float edge = float(double(b) / double(f.size()));
      us.insert(us.end(), {edge, std::nextafter(edge, 0.0f), std::nextafter(edge, 1.0f)});
    }
    for (size_t i = 0; i + 1 < cdf.size(); ++i) us.push_back(float(cdf[i]));
    for (const float u : us) {
      if (!(u >= 0.0f && u < 1.0f)) continue;
      float prob = 0;
      ASSERT_EQ(d.sample_discrete(u, prob), reference(u)) << "u " << u << ", " << f.size() << " steps";
    }
  }
}

TEST(Distribution, AllZeroFallsBackToUniform) {
  const Distribution1D d(std::vector<float>{0, 0, 0, 0});
  EXPECT_EQ(d.integral(), 0.0);
  float pdf = 0;
  size_t idx = 0;
  d.sample(0.6f, pdf, idx);
  EXPECT_EQ(idx, 2u);
  EXPECT_FLOAT_EQ(pdf, 1.0f);
  EXPECT_THROW(Distribution1D(std::vector<float>{1, -1}), std::invalid_argument);
  EXPECT_THROW(Distribution1D(std::vector<float>{1, NAN}), std::invalid_argument);
}

TEST(Distribution, TwoDimensionalPdfIntegratesToOne) {
  std::vector<float> f(8 * 4);
  for (size_t i = 0; i < f.size(); ++i) f[i] = static_cast<float>((i * 7) % 5);
  const Distribution2D d(f, 8, 4);
  double integral = 0;
  for (int v = 0; v < 4; ++v)
    for (int u = 0; u < 8; ++u) integral += d.pdf({(u + 0.5f) / 8, (v + 0.5f) / 4}) / 32.0;
  EXPECT_NEAR(integral, 1.0, 1e-6);
  Pcg32 rng(3, 4);
  for (int i = 0; i < 1000; ++i) {
    float pdf = 0;
    const Vec2 p = d.sample({rng.next_float(), rng.next_float()}, pdf);
    ASSERT_NEAR(pdf, d.pdf(p), 1e-5f * pdf);
    ASSERT_GT(pdf, 0.0f);
  }
}

TEST(Warps, CosineHemisphereHistogram) {
  // Histogram over cos(theta) in 10 bins against the exact cos-weighted mass.
  Pcg32 rng(5, 6);
  const int n = 200000;
  std::vector<int> bins(10, 0);
  for (int i = 0; i < n; ++i) {
    const Vec3 w = sample_cosine_hemisphere({rng.next_float(), rng.next_float()});
    ASSERT_NEAR(length(w), 1.0f, 1e-5f);
    ASSERT_GE(w.z, 0.0f);
    ++bins[std::min(9, static_cast<int>(w.z * 10))];
  }
  for (int b = 0; b < 10; ++b) {
    const double lo = b / 10.0, hi = (b + 1) / 10.0;
    const double expected = hi * hi - lo * lo;  // P(cos < c) = c^2
    EXPECT_NEAR(bins[b] / double(n), expected, 0.004) << b;
  }
}

TEST(Rng, FloatsStayBelowOneAndStreamsDiffer) {
  Pcg32 a(1, 1), b(1, 2);
  int same = 0;
  for (int i = 0; i < 1000; ++i) {
    const float x = a.next_float(), y = b.next_float();
    ASSERT_GE(x, 0.0f);
    ASSERT_LT(x, 1.0f);
    same += x == y;
  }
  EXPECT_LT(same, 5);
  Sampler s1(7, 100, 3), s2(7, 100, 3), s3(7, 100, 4);
  EXPECT_EQ(s1.get1d(), s2.get1d());
  EXPECT_NE(s1.get1d(), s3.get1d());
}

// The first 2^m samples of a pixel, in any draw of the stream, form a
// (0, m, 2)-net: every box of 2^-k x 2^-(m-k) (k = 0..m) holds one point.
// The 1D draws are stratified the same way, one point per 2^-m interval.
TEST(Sampler, EveryDrawOfAPixelsSamplesIsANet) {
  for (const uint64_t pixel : {0ull, 1ull, 12345ull, 999999ull})
    for (const int m : {2, 4, 6}) {
      const int n = 1 << m;
      for (int draw = 0; draw < 8; ++draw) {
        std::vector<Vec2> pts;
        std::vector<float> ones;
        for (int i = 0; i < n; ++i) {
          Sampler s(3, pixel, uint64_t(i), uint32_t(n)), t(3, pixel, uint64_t(i), uint32_t(n));
          Vec2 p;
          float q = 0;
          for (int d = 0; d <= draw; ++d) p = s.get2d();
          for (int d = 0; d <= draw; ++d) q = t.get1d();
          ASSERT_TRUE(p.x >= 0 && p.x < 1 && p.y >= 0 && p.y < 1);
          pts.push_back(p);
          ones.push_back(q);
        }
        for (int k = 0; k <= m; ++k) {
          const int nx = 1 << k, ny = 1 << (m - k);
          std::vector<int> count(size_t(n), 0);
          for (const Vec2& p : pts) ++count[size_t(int(p.y * float(ny)) * nx + int(p.x * float(nx)))];
          for (int c : count) ASSERT_EQ(c, 1) << "pixel " << pixel << ", 2^" << m << " samples, draw " << draw
                                              << ", boxes " << nx << " x " << ny;
        }
        std::vector<int> count(size_t(n), 0);
        for (float q : ones) ++count[size_t(int(q * float(n)))];
        for (int c : count) ASSERT_EQ(c, 1) << "1D, pixel " << pixel << ", draw " << draw;
      }
    }
}

// The sample-order permutation is a bijection of [0, 2^bits) for every
// width and seed, and not the identity.
TEST(Sampler, IndexPermutationIsABijection) {
  for (int bits = 0; bits <= 12; ++bits)
    for (uint64_t seed : {1ull, 77ull, 0xdeadbeefull}) {
      const uint32_t n = 1u << bits;
      std::vector<int> seen(n, 0);
      int moved = 0;
      for (uint32_t i = 0; i < n; ++i) {
        const uint32_t j = permute_index(i, bits, seed, mix64(seed));
        ASSERT_LT(j, n) << bits << " bits";
        ++seen[j];
        moved += j != i;
      }
      for (int c : seen) ASSERT_EQ(c, 1) << bits << " bits, seed " << seed;
      if (bits >= 3) EXPECT_GT(moved, int(n / 2)) << bits << " bits, seed " << seed;
    }
}

// Different draws of a pixel are independent: draw 0's x against draw 1's
// x fill a 16 x 16 grid of cells as independent points do (a shuffle of the
// sample order by a xor would tie them onto 16 lines, one by an Owen
// scramble of the index fills about 130 of the 162 cells), and their
// correlation over many pixels is nil.
TEST(Sampler, DrawsAreIndependentOfEachOther) {
  const int n = 256;
  double worst_fill = 1;
  for (uint64_t pixel = 0; pixel < 16; ++pixel) {
    std::vector<int> cell(256, 0);
    for (int i = 0; i < n; ++i) {
      Sampler s(5, pixel, uint64_t(i), uint32_t(n));
      const Vec2 a = s.get2d(), b = s.get2d();
      ++cell[size_t(int(b.x * 16) * 16 + int(a.x * 16))];
    }
    int filled = 0;
    for (int c : cell) filled += c > 0;
    // 256 independent points fill 256 (1 - (255/256)^256) = 162 cells on average (sd about 6).
    worst_fill = std::min(worst_fill, filled / 162.0);
    EXPECT_GT(filled, 145) << "pixel " << pixel;
  }
  double sxy = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
  const int pixels = 4096, spp = 16;
  for (uint64_t pixel = 0; pixel < uint64_t(pixels); ++pixel)
    for (int i = 0; i < spp; ++i) {
      Sampler s(5, pixel, uint64_t(i), uint32_t(spp));
      const double x = s.get2d().x, y = s.get1d();
      sx += x; sy += y; sxx += x * x; syy += y * y; sxy += x * y;
    }
  const double N = double(pixels) * spp;
  const double r = (sxy / N - sx / N * sy / N) / std::sqrt((sxx / N - sx / N * sx / N) * (syy / N - sy / N * sy / N));
  EXPECT_LT(std::abs(r), 0.02);
  std::printf("[ sampler ] draws 0 x 1 x: worst cell fill %.2f of independent points'; correlation %.4f\n",
              worst_fill, r);
}

// What the stratification buys: a pixel's estimate of a smooth integral
// (the mean of f over the unit square) from 64 samples, over 256 pixels,
// against the same from independent random numbers.
TEST(Sampler, SmoothIntegralsConvergeFasterThanWithIndependentSamples) {
  auto f = [](Vec2 p) { return std::exp(-2.0 * p.x) * (1 + std::sin(3.0 * p.y)) + p.x * p.y; };
  // exact: (1 - e^-2)/2 * (1 + (1 - cos 3)/3) + 1/4
  const double exact = (1 - std::exp(-2.0)) / 2 * (1 + (1 - std::cos(3.0)) / 3) + 0.25;
  const int pixels = 256, spp = 64;
  double e2_sobol = 0, e2_random = 0;
  Pcg32 rng(11, 12);
  for (uint64_t pixel = 0; pixel < uint64_t(pixels); ++pixel) {
    double a = 0, b = 0;
    for (int i = 0; i < spp; ++i) {
      Sampler s(9, pixel, uint64_t(i), uint32_t(spp));
      s.get1d();  // a later draw: the shuffles and scrambles of draw 1
      a += f(s.get2d());
      const float u = rng.next_float();
      b += f(Vec2(u, rng.next_float()));
    }
    e2_sobol += (a / spp - exact) * (a / spp - exact);
    e2_random += (b / spp - exact) * (b / spp - exact);
  }
  const double rs = std::sqrt(e2_sobol / pixels), rr = std::sqrt(e2_random / pixels);
  std::printf("[ sampler ] 64 samples, smooth integrand: RMSE %.2e scrambled Sobol', %.2e independent (%.1fx)\n",
              rs, rr, rr / rs);
  EXPECT_LT(rs, 0.25 * rr);
}

TEST(EnvironmentMap, DirectionMappingRoundTripsAndFollowsTheConvention) {
  const Vec3 centre = EnvironmentMapLight::direction_of({0.5f, 0.5f});
  EXPECT_NEAR(centre.z, -1.0f, 1e-6f);  // image centre looks toward -z
  const Vec3 right = EnvironmentMapLight::direction_of({0.75f, 0.5f});
  EXPECT_NEAR(right.x, 1.0f, 1e-6f);  // u grows toward +x
  EXPECT_NEAR(EnvironmentMapLight::direction_of({0.3f, 0.0f}).y, 1.0f, 1e-6f);  // top row is +y
  Pcg32 rng(8, 9);
  for (int i = 0; i < 1000; ++i) {
    const Vec2 uv = {rng.next_float(), 0.01f + 0.98f * rng.next_float()};
    const Vec2 back = EnvironmentMapLight::uv_of(EnvironmentMapLight::direction_of(uv));
    ASSERT_NEAR(back.x, uv.x, 1e-4f);
    ASSERT_NEAR(back.y, uv.y, 1e-4f);
  }
}

// The solid-angle density of sample() integrates to one over the sphere,
// matches pdf() at the sampled directions, and the histogram of samples
// matches it; radiance / pdf stays bounded next to a one-texel bright spot.
TEST(EnvironmentMap, ImportanceSamplingIsConsistent) {
  const int w = 32, h = 16;
  std::vector<Rgb> px(w * h, Rgb(0.1f));
  px[5 * w + 20] = Rgb(500.0f);  // a tiny sun
  for (int x = 0; x < w; ++x) px[12 * w + x] = Rgb(2.0f, 1.0f, 0.5f);
  const EnvironmentMapLight env(px, w, h, 1.0f, 37.0f);

  // Integral of the pdf over the sphere (quadrature in uv, solid angle = 2 pi^2 sin(theta) du dv).
  double integral = 0;
  const int n = 512;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < 2 * n; ++i) {
      const float u = (i + 0.5f) / (2 * n), v = (j + 0.5f) / n;
      const Vec3 d = EnvironmentMapLight::direction_of({u, v});
      integral += env.pdf({}, d, nullptr) * 2 * kPi * kPi * std::sin(kPi * v) / (2.0 * n * n);
    }
  EXPECT_NEAR(integral, 1.0, 2e-3);

  Pcg32 rng(10, 11);
  const int samples = 200000;
  std::vector<double> hist(8 * 4, 0);
  double max_ratio = 0;
  int pdf_mismatch = 0;
  for (int i = 0; i < samples; ++i) {
    LightSample s;
    ASSERT_TRUE(env.sample({}, {rng.next_float(), rng.next_float()}, s));
    ASSERT_NEAR(length(s.wi), 1.0f, 1e-5f);
    // The density is constant per texel; a sample on a texel border may be
    // assigned to the neighbour when its direction is mapped back.
    if (std::fabs(s.pdf - env.pdf({}, s.wi, nullptr)) > 1e-3f * s.pdf) ++pdf_mismatch;
    const Rgb le = env.environment(s.wi);
    ASSERT_NEAR(le.r, s.li.r, 1e-3f * (1 + le.r));
    max_ratio = std::max(max_ratio, static_cast<double>(le.luminance() / s.pdf));
    const Vec2 uv = EnvironmentMapLight::uv_of(s.wi);
    hist[std::min(3, static_cast<int>(uv.y * 4)) * 8 + std::min(7, static_cast<int>(uv.x * 8))] += 1;
  }
  EXPECT_LT(pdf_mismatch, samples / 1000);
  // Expected mass per coarse bin by quadrature of the pdf.
  for (int by = 0; by < 4; ++by)
    for (int bx = 0; bx < 8; ++bx) {
      // Fine in u: the rotated sun texels cut bins into slivers.
      double mass = 0;
      const int qu = 512, qv = 64;
      for (int j = 0; j < qv; ++j)
        for (int i = 0; i < qu; ++i) {
          const float u = (bx + (i + 0.5f) / qu) / 8, v = (by + (j + 0.5f) / qv) / 4;
          mass += env.pdf({}, EnvironmentMapLight::direction_of({u, v}), nullptr) * 2 * kPi * kPi *
                  std::sin(kPi * v) / (8.0 * 4.0 * qu * qv);
        }
      const double observed = hist[by * 8 + bx] / samples;
      EXPECT_NEAR(observed, mass, 4 * std::sqrt(mass / samples) + 1e-3) << "bin " << bx << ", " << by;
    }
  // Bounded: radiance / pdf <= 2 pi^2 mean(weights) times the largest
  // sin(theta) ratio within a texel row (about 300 here, reached near the
  // poles). Sampling texels by their own luminance would give ratios of
  // order 1e4 to 1e5 next to the sun, where the bilinear lookup leaks its radiance.
  EXPECT_LT(max_ratio, 1000.0);
}

TEST(Fresnel, KnownValues) {
  EXPECT_NEAR(fresnel_dielectric(1.0f, 1.5f), 0.04f, 1e-6f);
  EXPECT_NEAR(fresnel_dielectric(-1.0f, 1.5f), 0.04f, 1e-6f);
  EXPECT_NEAR(fresnel_dielectric(1e-6f, 1.5f), 1.0f, 1e-4f);  // grazing
  // From inside beyond the critical angle (asin(1/1.5) = 41.8 deg): total reflection.
  EXPECT_EQ(fresnel_dielectric(-std::cos(0.8f), 1.5f), 1.0f);
  // Brewster angle: the parallel component vanishes, R = r_perp^2 / 2.
  const float tb = std::atan(1.5f);
  const float ci = std::cos(tb), ct = std::cos(std::asin(std::sin(tb) / 1.5f));
  const float rs = (ci - 1.5f * ct) / (ci + 1.5f * ct);
  EXPECT_NEAR(fresnel_dielectric(ci, 1.5f), 0.5f * rs * rs, 1e-6f);
}

TEST(SmoothDielectric, SamplesObeySnellAndFresnel) {
  DielectricDesc d;
  d.eta = 1.5f;
  d.tint = Rgb(0.9f, 0.8f, 0.7f);
  const SmoothDielectricMaterial glass(d);
  SurfaceInteraction si;
  const float theta = 0.6f;
  const Vec3 wo(std::sin(theta), 0, std::cos(theta));
  const float f = fresnel_dielectric(std::cos(theta), 1.5f);
  int reflected = 0;
  Pcg32 rng(12, 13);
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    BsdfSample s;
    ASSERT_TRUE(glass.sample(si, wo, rng.next_float(), {0, 0}, s));
    ASSERT_TRUE(s.is_delta());
    if (s.flags & kReflection) {
      ++reflected;
      EXPECT_NEAR(s.wi.x, -wo.x, 1e-6f);
      EXPECT_NEAR(s.wi.z, wo.z, 1e-6f);
      EXPECT_FLOAT_EQ(s.weight.r, 1.0f);
    } else {
      EXPECT_LT(s.wi.z, 0.0f);
      EXPECT_NEAR(std::sqrt(s.wi.x * s.wi.x + s.wi.y * s.wi.y) * 1.5f, std::sin(theta), 1e-5f);  // Snell
      EXPECT_NEAR(s.weight.g, 0.8f / (1.5f * 1.5f), 1e-6f);  // tint / eta^2
      EXPECT_NEAR(s.eta, 1.5f, 1e-6f);
    }
  }
  EXPECT_NEAR(reflected / double(n), f, 0.003);
  EXPECT_EQ(glass.eval(si, wo, {0, 0, 1}).max(), 0.0f);
  EXPECT_EQ(glass.pdf(si, wo, {0, 0, 1}), 0.0f);
}

TEST(Diffuse, IsTwoSidedAndReciprocal) {
  const DiffuseMaterial m(Rgb(0.5f));
  SurfaceInteraction si;
  const Vec3 a = normalize(Vec3(0.3f, 0.2f, 0.9f)), b = normalize(Vec3(-0.5f, 0.1f, 0.4f));
  EXPECT_FLOAT_EQ(m.eval(si, a, b).r, 0.5f * kInvPi);
  EXPECT_FLOAT_EQ(m.eval(si, b, a).r, m.eval(si, a, b).r);
  EXPECT_FLOAT_EQ(m.eval(si, -a, -b).r, 0.5f * kInvPi);  // back side
  EXPECT_EQ(m.eval(si, a, -b).r, 0.0f);                  // no transmission
  BsdfSample s;
  ASSERT_TRUE(m.sample(si, -a, 0.5f, {0.3f, 0.7f}, s));
  EXPECT_LT(s.wi.z, 0.0f);
  EXPECT_NEAR(s.pdf, m.pdf(si, -a, s.wi), 1e-6f);
}

TEST(Mis, PowerHeuristic) {
  EXPECT_FLOAT_EQ(power_heuristic(1, 1), 0.5f);
  EXPECT_FLOAT_EQ(power_heuristic(3, 1), 0.9f);
  EXPECT_FLOAT_EQ(power_heuristic(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(power_heuristic(INFINITY, 2), 1.0f);
}

}  // namespace
}  // namespace knit::render
