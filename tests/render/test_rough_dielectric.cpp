// The rough dielectric (materials.h, RoughDielectricMaterial): its BSDF
// against an independent double-precision evaluation of Walter et al. 2007
// (the textbook tan-theta forms of GGX D and Smith Lambda, a Fresnel of its
// own), generalised reciprocity, sampling against eval and pdf, the pdf's
// and the albedo's integrals against quadrature over the sphere, and the
// smooth limit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "render/fresnel.h"
#include "render/materials.h"
#include "render/rng.h"

namespace knit::render {
namespace {

constexpr double kPiD = 3.14159265358979323846;

struct D3 {
  double x, y, z;
};
D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(D3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dotd(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 normd(D3 a) { return a * (1.0 / std::sqrt(dotd(a, a))); }

// Unpolarised Fresnel reflectance for light meeting the interface at cos_i
// from the side of index n1 into n2.
double fresnel_ref(double cos_i, double n1, double n2) {
  cos_i = std::fabs(cos_i);
  const double sin_t = n1 / n2 * std::sqrt(std::max(0.0, 1 - cos_i * cos_i));
  if (sin_t >= 1) return 1;
  const double cos_t = std::sqrt(1 - sin_t * sin_t);
  const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

// GGX with alpha a: D(h) = a^2 / (pi cos^4 (a^2 + tan^2)^2) and
// Lambda(w) = (sqrt(1 + a^2 tan^2) - 1) / 2.
double ggx_d_ref(double a, D3 h) {
  if (h.z <= 0) return 0;
  const double c2 = h.z * h.z, t2 = (1 - c2) / c2;
  return a * a / (kPiD * c2 * c2 * (a * a + t2) * (a * a + t2));
}
double lambda_ref(double a, D3 w) {
  const double c2 = w.z * w.z, t2 = (1 - c2) / c2;
  return 0.5 * (std::sqrt(1 + a * a * t2) - 1);
}

// f(wo, wi) of a rough interface, normal +z outside, index eta inside and 1
// outside, for radiance (Walter et al. 2007, Eq. 20 and 21).
double walter_ref(double a, double eta, D3 wo, D3 wi) {
  const double no = wo.z > 0 ? 1 : eta, ni = wi.z > 0 ? 1 : eta;
  const bool reflect = wo.z * wi.z > 0;
  D3 h = reflect ? normd(wo + wi) : normd((wo * no + wi * ni) * -1.0);
  if (h.z < 0) h = h * -1.0;
  if (dotd(wo, h) * wo.z <= 0 || dotd(wi, h) * wi.z <= 0) return 0;
  const double g2 = 1 / (1 + lambda_ref(a, wo) + lambda_ref(a, wi));
  const double f = fresnel_ref(dotd(wo, h), no, no == 1 ? eta : 1);
  if (reflect) return f * ggx_d_ref(a, h) * g2 / (4 * std::fabs(wo.z) * std::fabs(wi.z));
  const double den = ni * dotd(wi, h) + no * dotd(wo, h);
  return std::fabs(dotd(wi, h) * dotd(wo, h)) / (std::fabs(wi.z) * std::fabs(wo.z)) * no * no * (1 - f) *
         g2 * ggx_d_ref(a, h) / (den * den);
}

Vec3 direction(double theta, double phi) {
  return Vec3(float(std::sin(theta) * std::cos(phi)), float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
}

RoughDielectricMaterial glass(float roughness, float eta, Rgb tint = Rgb(1.0f)) {
  DielectricDesc d;
  d.roughness = roughness;
  d.eta = eta;
  d.tint = tint;
  return RoughDielectricMaterial(d);
}

// Quadrature of g(w) over the sphere: a midpoint rule in (cos theta, phi),
// n x 2n cells per hemisphere, refined near the poles' lobes by the count.
template <class G>
double sphere_integral(int n, G g) {
  double sum = 0;
  for (int hemi = 0; hemi < 2; ++hemi)
    for (int i = 0; i < n; ++i) {
      const double z = (i + 0.5) / n, st = std::sqrt(1 - z * z);
      for (int j = 0; j < 2 * n; ++j) {
        const double phi = (j + 0.5) * kPiD / n;
        const Vec3 w(float(st * std::cos(phi)), float(st * std::sin(phi)), float(hemi ? -z : z));
        sum += g(w);
      }
    }
  return sum * (2 * kPiD / (2.0 * n * n));
}

TEST(RoughDielectric, MatchesADoublePrecisionWalterEvaluation) {
  SurfaceInteraction si;
  Pcg32 rng(3, 5);
  double worst = 0;
  int compared = 0;
  for (float roughness : {0.05f, 0.3f, 0.8f})
    for (float eta : {1.5f, 1.33f, 0.75f, 1.05f}) {
      const RoughDielectricMaterial m = glass(roughness, eta);
      const double a = double(roughness) * roughness;
      for (int k = 0; k < 4000; ++k) {
        // Pairs over the whole sphere, both sides of the interface.
        const double to = std::acos(2 * rng.next_float() - 1.0), ti = std::acos(2 * rng.next_float() - 1.0);
        const Vec3 wo = direction(to, 2 * kPiD * rng.next_float()), wi = direction(ti, 2 * kPiD * rng.next_float());
        if (std::fabs(wo.z) < 0.02f || std::fabs(wi.z) < 0.02f) continue;
        const double ref = walter_ref(a, eta, d3(wo), d3(wi));
        const double got = m.eval(si, wo, wi).r;
        if (ref < 1e-6 && got < 1e-6) continue;
        const double rel = std::fabs(got - ref) / std::max(ref, 1e-3);
        worst = std::max(worst, rel);
        ++compared;
        ASSERT_LT(rel, 2e-3) << "roughness " << roughness << " eta " << eta << " wo " << wo.x << " " << wo.y << " "
                             << wo.z << " wi " << wi.x << " " << wi.y << " " << wi.z << ": " << got << " vs " << ref;
      }
    }
  std::printf("[rough dielectric] eval vs double-precision Walter: %d pairs, worst relative error %.2e\n", compared,
              worst);
  EXPECT_GT(compared, 10000);
}

// f(wo, wi) eta_i^2 = f(wi, wo) eta_o^2 (radiance; eta_o, eta_i the indices
// on wo's and wi's sides), and plain reciprocity for reflection.
TEST(RoughDielectric, IsReciprocalUpToTheRadianceScaling) {
  SurfaceInteraction si;
  const float eta = 1.5f;
  const RoughDielectricMaterial m = glass(0.4f, eta);
  Pcg32 rng(9, 1);
  int tested = 0;
  for (int k = 0; k < 2000; ++k) {
    const Vec3 wo = direction(std::acos(2 * rng.next_float() - 1.0), 2 * kPiD * rng.next_float());
    const Vec3 wi = direction(std::acos(2 * rng.next_float() - 1.0), 2 * kPiD * rng.next_float());
    const float fo = m.eval(si, wo, wi).r, fi = m.eval(si, wi, wo).r;
    if (fo <= 1e-6f && fi <= 1e-6f) continue;
    const float no = wo.z > 0 ? 1 : eta, ni = wi.z > 0 ? 1 : eta;
    EXPECT_NEAR(fo * ni * ni, fi * no * no, 2e-4f * std::max(fo * ni * ni, 1.0f));
    ++tested;
  }
  EXPECT_GT(tested, 1000);
}

// sample() against eval() and pdf(): the pdf it reports is pdf() at its
// direction, its weight is f |cos| / pdf, and the lobe it reports is the
// side wi lies on. Views from outside and inside, with and without total
// internal reflection.
TEST(RoughDielectric, SamplesAgreeWithEvalAndPdf) {
  SurfaceInteraction si;
  const Rgb tint(0.9f, 0.7f, 0.5f);
  int samples = 0, transmitted = 0;
  for (float roughness : {0.01f, 0.1f, 0.5f, 1.0f})
    for (float eta : {1.5f, 0.7f, 1.02f})
      for (float theta : {0.1f, 0.8f, 1.4f, 2.0f, 2.9f}) {
        const RoughDielectricMaterial m = glass(roughness, eta, tint);
        const Vec3 wo = direction(theta, 0.4);
        Pcg32 rng(17, uint64_t(theta * 100));
        for (int k = 0; k < 2000; ++k) {
          BsdfSample s;
          if (!m.sample(si, wo, rng.next_float(), {rng.next_float(), rng.next_float()}, s)) continue;
          ++samples;
          ASSERT_FALSE(s.is_delta());
          const bool reflect = (s.flags & kReflection) != 0;
          ASSERT_EQ(reflect, s.wi.z * wo.z > 0);
          transmitted += !reflect;
          const float p = m.pdf(si, wo, s.wi);
          ASSERT_NEAR(s.pdf, p, 1e-5f * p);
          const Rgb f = m.eval(si, wo, s.wi);
          // (the closed-form weight against eval / pdf: the sampled and the
          // recomputed half vectors differ by rounding, which matters at
          // alpha = 1e-4, where D changes by 1% over 1e-6 radians)
          const float tol = roughness < 0.05f ? 0.05f : 2e-3f;
          const float wc[3] = {s.weight.r, s.weight.g, s.weight.b}, fc[3] = {f.r, f.g, f.b};
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(wc[c], fc[c] * std::fabs(s.wi.z) / p, tol * std::max(1.0f, wc[c]))
                << "roughness " << roughness << " eta " << eta << " theta " << theta << " channel " << c;
        }
      }
  EXPECT_GT(samples, 60000);
  EXPECT_GT(transmitted, 10000);
}

// The pdf integrates over the sphere to the fraction of samples sample()
// returns (it drops the few reflections below the surface), and the mean
// sample weight is the albedo, the integral of f |cos| (quadrature). With
// tint 1 the albedo is at most 1; at low roughness little is lost to
// shadowing, the reflected share is near the smooth Fresnel term, and the
// refracted share carries the 1 / eta^2 radiance scaling.
TEST(RoughDielectric, PdfAndAlbedoIntegrateAsSampled) {
  SurfaceInteraction si;
  for (float roughness : {0.2f, 0.5f, 0.9f})
    for (float theta : {0.3f, 1.2f, 2.5f}) {
      const float eta = 1.5f;
      const RoughDielectricMaterial m = glass(roughness, eta);
      const Vec3 wo = direction(theta, 1.0);
      const int n = roughness < 0.3f ? 1400 : 500;
      const double pdf_int = sphere_integral(n, [&](Vec3 w) { return double(m.pdf(si, wo, w)); });
      const double refl = sphere_integral(
          n, [&](Vec3 w) { return w.z * wo.z > 0 ? double(m.eval(si, wo, w).r) * std::fabs(w.z) : 0.0; });
      const double refr = sphere_integral(
          n, [&](Vec3 w) { return w.z * wo.z < 0 ? double(m.eval(si, wo, w).r) * std::fabs(w.z) : 0.0; });
      Pcg32 rng(41, uint64_t(theta * 10 + roughness * 1000));
      const int count = 400000;
      double ok = 0, wr = 0, wt = 0;
      for (int k = 0; k < count; ++k) {
        BsdfSample s;
        if (!m.sample(si, wo, rng.next_float(), {rng.next_float(), rng.next_float()}, s)) continue;
        ok += 1;
        ((s.flags & kReflection) ? wr : wt) += s.weight.r;
      }
      ok /= count;
      wr /= count;
      wt /= count;
      std::printf("[rough dielectric] roughness %.1f theta %.1f: pdf integral %.4f (sampled %.4f), reflected %.4f "
                  "(sampled %.4f), refracted %.4f (sampled %.4f)\n",
                  roughness, theta, pdf_int, ok, refl, wr, refr, wt);
      EXPECT_NEAR(pdf_int, ok, 0.01);
      EXPECT_NEAR(refl, wr, 0.01);
      EXPECT_NEAR(refr, wt, 0.01);
      // Energy: refracted radiance is scaled by 1 / eta_rel^2; undo it.
      const double etap2 = wo.z > 0 ? double(eta) * eta : 1.0 / (double(eta) * eta);
      EXPECT_LE(refl + refr * etap2, 1.005);
      if (roughness <= 0.2f) EXPECT_GT(refl + refr * etap2, 0.95);
    }
}

// A nearly smooth interface reflects the smooth Fresnel share of the light
// and sends the rest near Snell's direction (GGX's long tails put a few
// samples farther off: the 99th percentile is checked).
TEST(RoughDielectric, ApproachesTheSmoothInterface) {
  SurfaceInteraction si;
  const RoughDielectricMaterial m = glass(0.02f, 1.5f);
  const float theta = 0.7f;
  const Vec3 wo = direction(theta, 0);
  Pcg32 rng(5, 6);
  int reflected = 0, n = 200000, ok = 0;
  std::vector<double> off;
  for (int k = 0; k < n; ++k) {
    BsdfSample s;
    if (!m.sample(si, wo, rng.next_float(), {rng.next_float(), rng.next_float()}, s)) continue;
    ++ok;
    if (s.flags & kReflection) {
      ++reflected;
    } else {
      const double sin_t = std::sqrt(double(s.wi.x) * s.wi.x + double(s.wi.y) * s.wi.y);
      off.push_back(std::fabs(std::asin(sin_t) - std::asin(std::sin(theta) / 1.5)));
    }
  }
  EXPECT_NEAR(reflected / double(ok), fresnel_dielectric(std::cos(theta), 1.5f), 0.003);
  EXPECT_GT(ok, n * 0.999);
  std::sort(off.begin(), off.end());
  const double p50 = off[off.size() / 2], p99 = off[off.size() * 99 / 100];
  std::printf("[rough dielectric] roughness 0.02: reflected %.4f (smooth Fresnel %.4f), refraction off Snell's "
              "direction: median %.5f rad, 99th percentile %.5f rad\n",
              reflected / double(ok), fresnel_dielectric(std::cos(theta), 1.5f), p50, p99);
  EXPECT_LT(p99, 0.01);
}

}  // namespace
}  // namespace knit::render
