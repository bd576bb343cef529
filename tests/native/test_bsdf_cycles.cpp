// The yarn BSDF as Cycles' closures render it (native/kernel/bsdf_cycles.h):
// the closure weights against double-precision integrals of the exact lobes
// they stand for, the mixture's directional albedo against its weights, the
// chi-square test of its sampling (with and without the delta lobe), eval /
// pdf / sample agreement, a white furnace, no NaN or Inf at grazing and
// degenerate inputs, and the isotropic footprint of multiscale.h.
//
// Reciprocity is not tested: the closure weights depend on wo alone, so
// f(wo, wi) |wi.z|-symmetry does not hold, and is not meant to (Cycles
// weighs its closures per shading point).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bsdf_test_util.h"

namespace {

using namespace knit;
using namespace knit::test;

// ---- Double-precision references (independent forms) ------------------------

// Unpolarised Fresnel reflectance from the s and p amplitudes; 0 for eta 1.
double fresnel_ref(double ci, double eta) {
  if (eta <= 1.0) return 0.0;
  ci = std::clamp(ci, 0.0, 1.0);
  if (ci == 0.0) return 1.0;
  const double si2 = 1.0 - ci * ci;
  const double ct = std::sqrt(std::max(0.0, 1.0 - si2 / (eta * eta)));
  const double rs = (ci - eta * ct) / (ci + eta * ct);
  const double rp = (eta * ci - ct) / (eta * ci + ct);
  return 0.5 * (rs * rs + rp * rp);
}

struct D3 {
  double x, y, z;
};
D3 d3(Vec3 v) { return {v.x, v.y, v.z}; }
double dot3(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Anisotropic GGX: D(h), Smith Lambda, height-correlated G2 (Heitz 2014).
double ggx_d(double ax, double ay, D3 h) {
  if (h.z <= 0) return 0;
  const double s = h.x * h.x / (ax * ax) + h.y * h.y / (ay * ay) + h.z * h.z;
  return 1.0 / (kPi * ax * ay * s * s);
}
double ggx_lambda(double ax, double ay, D3 v) {
  const double z2 = v.z * v.z;
  const double t2 = (ax * ax * v.x * v.x + ay * ay * v.y * v.y) / z2;
  return 0.5 * (std::sqrt(1.0 + t2) - 1.0);
}
// f |wi.z| of GGX reflection without Fresnel for o, i on the upper side.
double ggx_eval(double ax, double ay, D3 o, D3 i) {
  if (o.z <= 0 || i.z <= 0) return 0;
  D3 h{o.x + i.x, o.y + i.y, o.z + i.z};
  const double l = std::sqrt(dot3(h, h));
  h = {h.x / l, h.y / l, h.z / l};
  const double g2 = 1.0 / (1.0 + ggx_lambda(ax, ay, o) + ggx_lambda(ax, ay, i));
  return ggx_d(ax, ay, h) * g2 / (4.0 * o.z);
}
// The tube chord l(d) of bsdf_attenuation.h, clamped at 8.
double chord_ref(D3 d) {
  const double p = d.y * d.y + d.z * d.z;
  return p > 0 ? std::min(std::fabs(d.z) / p, 8.0) : 8.0;
}

struct Params {
  float ax = 0.15f, ay = 0.45f, tax = 0.3f, tay = 0.6f, eta = 1.55f;
  float B = 0.7f, r = 0.6f, G = 1.0f, D = 1.0f;
  int layers = 1;
  Vec3 kr{0.9f, 0.6f, 0.3f}, kt{0.5f, 0.7f, 0.9f};
  std::string tag = "default";
};

k::KYarnBsdf yarn_of(const Params& p) {
  return k::yarn_bsdf_make(k::bsdf_mf_make(p.ax, p.ay, p.eta), k::bsdf_mf_make(p.tax, p.tay, p.eta), p.kr, p.kt,
                           p.B, p.r, p.G, k::bsdf_att_make(p.D, p.layers));
}

// The exact lobes' directional albedos at wo (mean over the colour channels
// folded out: per unit colour), in double, by adaptive quadrature.
struct ExactAlbedos {
  double spec, body_r, body_t, thin;  // f_R; body R and T per unit colour; f_T
  double e_ggx;                       // GGX without Fresnel (the closure's own albedo)
};
ExactAlbedos exact_albedos(const Params& p, Vec3 wo_f) {
  ExactAlbedos e{};
  D3 wo = d3(wo_f);
  const double mo = wo.z;  // (wo on the upper side)
  const double n = std::clamp(p.layers, 1, 4);
  const double fo = fresnel_ref(mo, p.eta);
  const double lo = chord_ref(wo);
  auto tau = [&](D3 wi) { return std::exp(-p.D * n * 0.5 * (lo + chord_ref(wi))); };
  auto half = [&](D3 wi) {
    D3 h{wo.x + wi.x, wo.y + wi.y, wo.z + wi.z};
    const double l = std::sqrt(dot3(h, h));
    return D3{h.x / l, h.y / l, h.z / l};
  };
  DirFn fr = [&](Vec3 v) {
    const D3 wi = d3(v);
    return wi.z > 0 ? fresnel_ref(dot3(wo, half(wi)), p.eta) * ggx_eval(p.ax, p.ay, wo, wi) : 0.0;
  };
  DirFn fg = [&](Vec3 v) { return ggx_eval(p.ax, p.ay, wo, d3(v)); };
  DirFn ft = [&](Vec3 v) {
    const D3 wi = d3(v);
    if (wi.z >= 0) return 0.0;
    const D3 m{wi.x, wi.y, -wi.z};  // mirrored into wo's side (the thin slab)
    const double t = 1.0 - fresnel_ref(dot3(wo, half(m)), p.eta);
    return (1.0 - p.B) * t * t * ggx_eval(p.tax, p.tay, wo, m) * tau(wi);
  };
  DirFn fbt = [&](Vec3 v) {
    const D3 wi = d3(v);
    if (wi.z >= 0) return 0.0;
    return (1.0 - p.r) * p.B * p.G * (1.0 - fo) * (1.0 - fresnel_ref(-wi.z, p.eta)) * tau(wi) * (-wi.z) / kPi;
  };
  e.spec = integrate_sphere(fr, 32, 32, 1e-8);
  e.e_ggx = integrate_sphere(fg, 32, 32, 1e-8);
  e.thin = integrate_sphere(ft, 32, 32, 1e-8);
  e.body_t = integrate_sphere(fbt, 32, 16, 1e-8);
  // Lommel-Seeliger with Fresnel: a 1D integral in mu, by the midpoint rule
  // on a fine grid in t with mu = t^2 (dense towards grazing, where F varies).
  double s = 0;
  const int m = 200000;
  for (int i = 0; i < m; ++i) {
    const double t = (i + 0.5) / m, mu = t * t;
    s += 2 * t * mu * (1.0 - fresnel_ref(mu, p.eta)) / (mu + mo);
  }
  e.body_r = p.r * p.B * p.G * (1.0 - fo) * s / m;
  return e;
}

double comp(Vec3 c, int ch) { return ch == 0 ? c.x : (ch == 1 ? c.y : c.z); }

std::vector<Params> param_sets() {
  std::vector<Params> v;
  v.push_back(Params{});
  Params p;
  p.ax = 0.05f, p.ay = 0.05f, p.tax = 0.1f, p.tay = 0.1f, p.tag = "smooth";  // (transparent() takes 0.37 of f_T)
  v.push_back(p);
  p = Params{};
  p.ax = 0.6f, p.ay = 0.9f, p.tax = 0.8f, p.tay = 1.0f, p.eta = 1.33f, p.D = 2.0f, p.layers = 2, p.tag = "rough_2layers";
  v.push_back(p);
  p = Params{};
  p.eta = 3.0f, p.B = 0.2f, p.r = 0.3f, p.G = 0.6f, p.D = 0.3f, p.tag = "eta3_thin";
  v.push_back(p);
  p = Params{};
  p.tax = 0.03f, p.tay = 0.05f, p.B = 0.4f, p.tag = "clear_slab";  // (0.86 of f_T on transparent())
  v.push_back(p);
  return v;
}

// ---- The weights against the exact lobes -------------------------------------

// Each closure weight times its closure's albedo is the exact lobe's albedo
// at wo (docs/cycles.md gives the measured figures). The tolerances hold
// the quadratures' errors: 21 visible normals for spec and through, 8-point
// Gauss-Legendre rules for body_r and body_t.
TEST(BsdfCycles, WeightsGiveTheExactLobesAlbedos) {
  double worst[4] = {0, 0, 0, 0};
  std::string where[4];
  for (const Params& p : param_sets()) {
    const k::KYarnBsdf yb = yarn_of(p);
    for (double th : {0.0, 30.0, 60.0, 75.0, 85.0, 89.0}) {
      for (double ph : {0.0, 45.0, 90.0}) {
        const Vec3 wo = dir_deg(th, ph);
        const ExactAlbedos e = exact_albedos(p, wo);
        const k::KCyclesLobes w = k::yarn_cycles_lobes(yb, wo);
        // body_t holds the body transmission (coloured, kt) and the share of
        // the thin-slab lobe f_T that transparent() does not take (white):
        // the two apart from the channels' difference. The whole of f_T is
        // then through plus that share.
        const double body_t = (double(w.body_t.x) - w.body_t.z) / (double(p.kt.x) - p.kt.z);
        const double rest = w.body_t.x - p.kt.x * body_t;
        const double share = std::exp(-double(std::max(p.tax, 1e-3f)) * std::max(p.tay, 1e-3f) / 0.01);
        EXPECT_NEAR(w.through, share * (w.through + rest), 1e-5 + 1e-4 * w.through) << p.tag << " theta " << th;
        // (body_r per unit colour: linear in its colour)
        const double got[4] = {w.spec * e.e_ggx, w.body_r.x / p.kr.x, body_t, w.through + rest};
        const double want[4] = {e.spec, e.body_r, e.body_t, e.thin};
        for (int l = 0; l < 4; ++l) {
          // relative, with a floor of 0.01 of the incident light (lobes that
          // carry nearly nothing at grazing angles)
          const double err = std::fabs(got[l] - want[l]) / std::max(want[l], 0.01);
          if (err > worst[l]) {
            worst[l] = err;
            where[l] = p.tag + " theta " + std::to_string(int(th)) + " phi " + std::to_string(int(ph)) +
                       ": " + std::to_string(got[l]) + " for " + std::to_string(want[l]);
          }
        }
      }
    }
  }
  const char* names[4] = {"spec", "body_r", "body_t", "f_T"};
  for (int l = 0; l < 4; ++l)
    std::printf("[cycles weights] %-7s worst error %.4f (%s)\n", names[l], worst[l], where[l].c_str());
  EXPECT_LT(worst[0], 0.12) << where[0];
  EXPECT_LT(worst[1], 0.005) << where[1];
  EXPECT_LT(worst[2], 0.005) << where[2];
  EXPECT_LT(worst[3], 0.12) << where[3];
}

// The lobes the weights' quadratures are built on.
TEST(BsdfCycles, QuadraturesMatchDoubleReferences) {
  // Gauss-Legendre on [0, 1]: exact for polynomials up to degree 15.
  for (int deg = 0; deg <= 15; ++deg) {
    double s = 0;
    for (int i = 0; i < 8; ++i) {
      const k::kvec3 g = k::bsdf_cycles_gl8(i);
      s += double(g.y) * std::pow(double(g.x), deg);
    }
    EXPECT_NEAR(s, 1.0 / (deg + 1), 2e-7) << "degree " << deg;
  }
  // C(k, eta): the cosine-weighted mean of exp(-k l) (1 - F).
  double worst = 0;
  for (float eta : {1.0f, 1.55f, 3.0f}) {
    for (float kk : {0.0f, 0.25f, 0.5f, 1.0f, 2.0f, 4.0f}) {
      DirFn f = [&](Vec3 v) {
        const D3 w = d3(v);
        return w.z > 0 ? std::exp(-kk * chord_ref(w)) * (1.0 - fresnel_ref(w.z, eta)) * w.z / kPi : 0.0;
      };
      const double ref = integrate_sphere(f, 32, 16, 1e-9);
      const double got = k::bsdf_cycles_transmit_mean(kk, eta);
      worst = std::max(worst, std::fabs(got - ref) / ref);
      EXPECT_NEAR(got, ref, 3e-4 * ref) << "k " << kk << " eta " << eta;
    }
  }
  std::printf("[cycles] C(k, eta) worst relative error %.2g (k <= 4)\n", worst);
  EXPECT_NEAR(k::bsdf_cycles_transmit_mean(0.f, 1.f), 1.0, 3e-5);
  // The Lommel-Seeliger albedo with Fresnel, without it the closed form.
  EXPECT_EQ(k::bsdf_cycles_ls_albedo(0.3f, 1.f), k::bsdf_ls_albedo(0.3f));
  EXPECT_LT(k::bsdf_cycles_ls_albedo(0.3f, 1.55f), k::bsdf_ls_albedo(0.3f));
}

// ---- The mixture as a BSDF ----------------------------------------------------

// The mixture's directional albedo at wo, integrated over the sphere, plus
// the delta, is spec E_ggx(wo) + body_r + body_t + through (per channel),
// with E_ggx from the double-precision GGX.
TEST(BsdfCycles, AlbedoIsTheWeightedSumOfTheClosures) {
  double worst = 0;
  for (const Params& p : param_sets()) {
    const k::KYarnBsdf yb = yarn_of(p);
    for (double th : {0.0, 40.0, 70.0, 85.0, 130.0}) {
      const Vec3 wo = dir_deg(th, 20.0);
      const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
      const Vec3 wo_up = v3(wo.x, wo.y, std::fabs(wo.z));
      DirFn fg = [&](Vec3 v) {
        return ggx_eval(c.alpha_x, c.alpha_y, d3(wo_up), D3{v.x, v.y, wo.z < 0 ? -double(v.z) : double(v.z)});
      };
      const double e_ggx = integrate_sphere(fg, 32, 32, 1e-8);
      for (int ch = 0; ch < 3; ++ch) {
        DirFn f = [&](Vec3 wi) {
          return comp(k::yarn_cycles_eval(c, wo, wi), ch);
        };
        const double got = integrate_sphere(f, 32, 32, 1e-8) + c.w.through;
        const double want =
            c.w.spec * e_ggx + comp(c.w.body_r, ch) + comp(c.w.body_t, ch) + c.w.through;
        worst = std::max(worst, std::fabs(got - want));
        EXPECT_NEAR(got, want, 1e-3 * std::max(want, 0.1)) << p.tag << " theta " << th << " channel " << ch;
      }
      // ... and by sampling: the mean weight of yarn_cycles_sample, the delta included.
      Rng rng(uint64_t(th * 10) + 1);
      double s = 0, s2 = 0;
      const int n = 200000;
      for (int i = 0; i < n; ++i) {
        const k::KBsdfSample smp = k::yarn_cycles_sample(c, wo, rng.uniform(), rng.uniform());
        s += smp.weight.y;
        s2 += double(smp.weight.y) * smp.weight.y;
      }
      const double mean = s / n, se = std::sqrt(std::max(0.0, s2 / n - mean * mean) / n);
      const double want = c.w.spec * e_ggx + c.w.body_r.y + c.w.body_t.y + c.w.through;
      EXPECT_NEAR(mean, want, 5 * se + 1e-3) << p.tag << " theta " << th;
    }
  }
  std::printf("[cycles] mixture albedo by quadrature vs the closures' weights: worst |difference| %.2g\n", worst);
}

// White colours, no ply shadow, no attenuation: the mixture's albedo (the
// closures' weights summed with the GGX albedo) stays at or below 1, as the
// exact BSDF's does (it stands for the exact lobes' albedos), and is 1 for
// an index-matched yarn that scatters everything through.
TEST(BsdfCycles, WhiteFurnaceAlbedoNeverExceedsOne) {
  const Vec3 white{1.f, 1.f, 1.f};
  double worst = 0;
  std::string at;
  for (float eta : {1.f, 1.33f, 1.55f, 2.f, 3.f})
    for (float a : {0.05f, 0.3f, 1.0f})
      for (float B : {0.f, 1.f})
        for (float r : {0.f, 1.f}) {
          const k::KYarnBsdf yb = k::yarn_bsdf_make(k::bsdf_mf_make(a, a, eta), k::bsdf_mf_make(a, a, eta), white,
                                                    white, B, r, 1.f, k::bsdf_att_make(0.f, 1));
          for (double th : {0.0, 30.0, 60.0, 80.0, 89.0, 89.9}) {
            const Vec3 wo = dir_deg(th, 30.0);
            const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
            Rng rng(uint64_t(th) + 7);
            double s = 0;
            const int n = 20000;
            for (int i = 0; i < n; ++i) s += k::yarn_cycles_sample(c, wo, rng.uniform(), rng.uniform()).weight.x;
            const double alb = s / n;
            if (alb > worst) {
              worst = alb;
              at = "eta " + std::to_string(eta) + " alpha " + std::to_string(a) + " B " + std::to_string(B) +
                   " r " + std::to_string(r) + " theta " + std::to_string(th);
            }
            EXPECT_LE(alb, 1.0 + 0.01) << at;
            if (eta == 1.f && B == 1.f && r == 0.f) EXPECT_NEAR(alb, 1.0, 1e-3) << "theta " << th;
          }
        }
  std::printf("[cycles furnace] max directional albedo %.4f at %s\n", worst, at.c_str());
}

// The yarn of the side-test checks below: rough, white, translucent, one
// layer.
k::KYarnBsdf side_test_yarn() {
  const Vec3 white{1.f, 1.f, 1.f};
  return k::yarn_bsdf_make(k::bsdf_mf_make(0.2f, 0.4f, 1.55f), k::bsdf_mf_make(0.3f, 0.6f, 1.55f), white, white,
                           0.8f, 0.6f, 1.f, k::bsdf_att_make(0.5f, 1));
}

// Cycles' side test (yarn_cycles_side_ok): with the mesh's normal along the
// yarn's, nothing is dropped; tilted, eval and pdf are exactly zero for the
// directions (ns.wi)(ns.n)(n.wi) < 0 and unchanged elsewhere, sampling never
// returns a dropped direction, and the albedo only falls.
TEST(BsdfCycles, SideTestDropsWhatCyclesDropsAndNothingElse) {
  const k::KYarnBsdf yb = side_test_yarn();
  const Vec3 wo = dir_deg(35.0, 10.0);
  const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
  const k::KYarnCycles same = k::yarn_cycles_with_base(c, v3(0.f, 0.f, 1.f));
  const Vec3 ns = k::kv3_normalize(v3(0.6f, 0.1f, 0.4f));  // the mesh's normal, 53 degrees from the yarn's
  const k::KYarnCycles tilted = k::yarn_cycles_with_base(c, ns);
  Rng rng(5);
  int dropped = 0, kept = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 wi = k::kv3_normalize(v3(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1));
    const Vec3 e = k::yarn_cycles_eval(c, wo, wi), es = k::yarn_cycles_eval(same, wo, wi),
               et = k::yarn_cycles_eval(tilted, wo, wi);
    EXPECT_EQ(e.x, es.x);
    EXPECT_EQ(k::yarn_cycles_pdf(c, wo, wi), k::yarn_cycles_pdf(same, wo, wi));
    const double test = double(k::kv3_dot(ns, wi)) * ns.z * wi.z;
    if (test < 0) {
      ++dropped;
      EXPECT_EQ(et.x, 0.f);
      EXPECT_EQ(k::yarn_cycles_pdf(tilted, wo, wi), 0.f);
    } else {
      ++kept;
      EXPECT_EQ(et.x, e.x);
      EXPECT_EQ(k::yarn_cycles_pdf(tilted, wo, wi), k::yarn_cycles_pdf(c, wo, wi));
    }
  }
  EXPECT_GT(dropped, 400);
  EXPECT_GT(kept, 400);
  double a = 0, at = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const k::KBsdfSample s = k::yarn_cycles_sample(c, wo, u1, u2), st = k::yarn_cycles_sample(tilted, wo, u1, u2);
    a += s.weight.x;
    at += st.weight.x;
    if (st.pdf > 0 && !k::kb_has_flag(st.flags, KB_DELTA)) EXPECT_EQ(k::yarn_cycles_side_ok(ns, st.wi), 1.f);
  }
  std::printf("[cycles side test] albedo %.4f without, %.4f with the mesh's normal 53 degrees off the yarn's\n",
              a / n, at / n);
  EXPECT_LT(at / n, a / n - 0.01);
}

// Cycles' samplers also drop a drawn direction on the wrong side of the
// surface (yarn_cycles_sample_side_ok), where its evaluation may keep it: a
// closure normal tilted below the surface reflects light from below when
// light is sampled, never when the closure is. Sampling then estimates less
// than the integral of eval (what light sampling alone gives), which is how
// Cycles renders it under a sky; with the surface's normal above the
// yarn's hemisphere the two agree.
TEST(BsdfCycles, SamplingDropsWhatCyclesSamplersDrop) {
  const k::KYarnBsdf yb = side_test_yarn();
  const Vec3 wo = dir_deg(70.0, 0.0);
  const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
  Rng rng(11);
  const int n = 200000;
  for (const Vec3 ns_in : {v3(0.6f, 0.1f, 0.4f), v3(0.9f, 0.f, -0.3f)}) {
    const Vec3 ns = k::kv3_normalize(ns_in);
    const bool below = ns.z < 0;  // the surface's normal below the closure's hemisphere
    ASSERT_GT(k::kv3_dot(ns, wo), 0.f);  // the viewer on the surface's front
    const k::KYarnCycles t = k::yarn_cycles_with_base(c, ns);
    double sampled = 0, integral = 0;
    int unreachable = 0;
    for (int i = 0; i < n; ++i) {
      const k::KBsdfSample s = k::yarn_cycles_sample(t, wo, rng.uniform(), rng.uniform());
      if (s.pdf > 0 && !k::kb_has_flag(s.flags, KB_DELTA)) {
        const float g = k::kv3_dot(ns, s.wi);
        if (s.wi.z > 0) EXPECT_GT(g, 0.f);
        else EXPECT_LT(g, 0.f);
        sampled += s.weight.x;
      }
      // eval |wi.z| over the sphere, uniformly: the smooth lobes' albedo
      const float z = 2 * rng.uniform() - 1, p = 6.2831853f * rng.uniform(), r = std::sqrt(1 - z * z);
      const Vec3 wi = v3(r * std::cos(p), r * std::sin(p), z);
      const float e = k::yarn_cycles_eval(t, wo, wi).x;
      integral += 4 * M_PI * e;
      if (e > 0 && k::yarn_cycles_sample_side_ok(ns, wo, wi, wi.z < 0) == 0.f) ++unreachable;
    }
    sampled /= n;
    integral /= n;
    std::printf("[cycles sampling side] surface normal %s the yarn's hemisphere: albedo sampled %.4f, eval's "
                "integral %.4f, %d of %d uniform directions lit only through light sampling\n",
                below ? "below" : "inside", sampled, integral, unreachable, n);
    if (below) {
      EXPECT_GT(unreachable, n / 50);
      EXPECT_LT(sampled, integral - 0.02);
    } else {
      EXPECT_EQ(unreachable, 0);
      EXPECT_NEAR(sampled, integral, 0.01);
    }
  }
}

// Cycles before 5.0 (yarn_cycles_as_cycles4): its GGX closure keeps light
// on the viewer's side of the surface (the samplers' rule,
// yarn_cycles_sample_side_ok) where Cycles 5 applies the side test; the
// diffuse() and translucent() values take the side test in both, but Cycles
// 4 keeps their density. Checked lobe by lobe against the closures without
// a base, with the surface's normal inside and below the yarn's hemisphere.
TEST(BsdfCycles, Cycles4GgxFollowsTheViewersSideAndKeepsTheDensity) {
  const k::KYarnBsdf yb = side_test_yarn();
  const Vec3 wo = dir_deg(70.0, 0.0);
  const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
  ASSERT_GT(c.w.spec, 0.f);
  ASSERT_GT(c.p1, 0.f);
  // The lobes apart: GGX alone (no body), the body alone (no GGX).
  auto ggx_only = [](k::KYarnCycles t) {
    t.w.body_r = v3(0, 0, 0);
    t.w.body_t = v3(0, 0, 0);
    t.p1 = t.p2 = 0;
    return t;
  };
  auto body_only = [](k::KYarnCycles t) {
    t.w.spec = 0;
    t.p0 = 0;
    return t;
  };
  Rng rng(23);
  for (const Vec3 ns_in : {v3(0.6f, 0.1f, 0.4f), v3(0.9f, 0.f, -0.3f)}) {
    const Vec3 ns = k::kv3_normalize(ns_in);
    ASSERT_GT(k::kv3_dot(ns, wo), 0.f);
    const k::KYarnCycles v5 = k::yarn_cycles_with_base(c, ns), v4 = k::yarn_cycles_as_cycles4(v5);
    int ggx_differs = 0, body_kept = 0;
    for (int i = 0; i < 20000; ++i) {
      const Vec3 wi = uniform_sphere(rng);
      const bool refl = wi.z * wo.z > 0;
      const float side = k::yarn_cycles_side_ok(ns, wi), samp = k::yarn_cycles_sample_side_ok(ns, wo, wi, 0);
      const float g = k::yarn_cycles_eval(ggx_only(c), wo, wi).x, gp = k::yarn_cycles_pdf(ggx_only(c), wo, wi);
      const float b = k::yarn_cycles_eval(body_only(c), wo, wi).x, bp = k::yarn_cycles_pdf(body_only(c), wo, wi);
      // GGX: the viewer's side in 4, the side test in 5.
      EXPECT_EQ(k::yarn_cycles_eval(ggx_only(v4), wo, wi).x, refl ? g * samp : 0.f);
      EXPECT_EQ(k::yarn_cycles_eval(ggx_only(v5), wo, wi).x, g * side);
      EXPECT_EQ(k::yarn_cycles_pdf(ggx_only(v4), wo, wi), refl ? gp * samp : 0.f);
      EXPECT_EQ(k::yarn_cycles_pdf(ggx_only(v5), wo, wi), gp * side);
      if (refl && g > 0 && side != samp) ++ggx_differs;
      // Body: the side test's value in both; the density kept in 4.
      EXPECT_EQ(k::yarn_cycles_eval(body_only(v4), wo, wi).x, b * side);
      EXPECT_EQ(k::yarn_cycles_eval(body_only(v5), wo, wi).x, b * side);
      EXPECT_EQ(k::yarn_cycles_pdf(body_only(v4), wo, wi), bp);
      EXPECT_EQ(k::yarn_cycles_pdf(body_only(v5), wo, wi), bp * side);
      if (bp > 0 && side == 0) ++body_kept;
    }
    std::printf("[cycles 4] surface normal %s the yarn's hemisphere: %d of 20000 directions where 4's GGX and "
                "5's differ, %d with the body's density kept\n",
                ns.z < 0 ? "below" : "inside", ggx_differs, body_kept);
    // The two rules agree while the surface's normal is inside the yarn's
    // hemisphere (on the viewer's side the side test passes); below it,
    // they part.
    if (ns.z > 0) EXPECT_EQ(ggx_differs, 0);
    else EXPECT_GT(ggx_differs, 1000);
    EXPECT_GT(body_kept, 1000);
  }
}

// Cycles 5 (the default): a drawn direction that the side test drops keeps
// its own closure's density, and its value when that closure is the GGX
// one (bump_shadowing_term zeroes a drawn diffuse() or translucent() alone);
// the other closures give it nothing.
TEST(BsdfCycles, Cycles5DrawnGgxSkipsTheSideTest) {
  const k::KYarnBsdf yb = side_test_yarn();
  const Vec3 wo = dir_deg(70.0, 0.0);
  const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
  const Vec3 ns = k::kv3_normalize(v3(0.9f, 0.f, -0.3f));  // below the yarn's hemisphere
  const k::KYarnCycles v5 = k::yarn_cycles_with_base(c, ns);
  const float total = c.p0 + c.p1 + c.p2 + c.p3;
  Rng rng(31);
  int ggx = 0, body = 0;
  for (int i = 0; i < 100000; ++i) {
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const k::KBsdfSample s = k::yarn_cycles_sample(v5, wo, u1, u2);
    if (!(s.pdf > 0) || k::kb_has_flag(s.flags, KB_DELTA) || k::yarn_cycles_side_ok(ns, s.wi) != 0.f) continue;
    // The closures alone, without the side test.
    k::KYarnCycles g = c, d = c;
    g.p1 = g.p2 = 0;
    g.w.body_r = g.w.body_t = v3(0, 0, 0);
    d.p0 = 0;
    d.w.spec = 0;
    (s.wi.z > 0 ? d.p2 : d.p1) = 0;
    const float pg = k::yarn_cycles_pdf(g, wo, s.wi) / total, pd = k::yarn_cycles_pdf(d, wo, s.wi) / total;
    if (std::fabs(s.pdf - pg) <= 1e-5f * pg) {
      ++ggx;
      EXPECT_NEAR(s.weight.x * s.pdf, k::yarn_cycles_eval(g, wo, s.wi).x, 1e-4f * k::yarn_cycles_eval(g, wo, s.wi).x);
      EXPECT_GT(s.weight.x, 0.f);
    } else {
      ++body;
      EXPECT_NEAR(s.pdf, pd, 1e-5f * pd);
      EXPECT_EQ(s.weight.x, 0.f);
    }
  }
  std::printf("[cycles 5 draws] %d GGX and %d diffuse/translucent draws the side test drops\n", ggx, body);
  EXPECT_GT(ggx, 100);
  EXPECT_GT(body, 100);
}

k::KYarnBsdf random_yarn(Rng& rng) {
  auto pick = [&](float lo, float hi) {
    const float u = rng.uniform();
    if (u < 0.1f) return lo;
    if (u > 0.9f) return hi;
    return lo + (hi - lo) * rng.uniform();
  };
  const Vec3 kr{pick(0, 1), pick(0, 1), pick(0, 1)}, kt{pick(0, 1), pick(0, 1), pick(0, 1)};
  return k::yarn_bsdf_make(k::bsdf_mf_make(pick(1e-6f, 1), pick(1e-6f, 1), pick(1, 3)),
                           k::bsdf_mf_make(pick(1e-6f, 1), pick(1e-6f, 1), 1.f), kr, kt, pick(0, 1), pick(0, 1),
                           pick(0, 1), k::bsdf_att_make(pick(0, 50), int(rng.uniform() * 7)));
}

TEST(BsdfCycles, SampleAgreesWithEvalAndPdf) {
  Rng rng(11);
  double worst_p = 0, worst_w = 0, worst_ps = 0, worst_ws = 0;
  int refl = 0, trans = 0, delta = 0;
  for (int i = 0; i < 100000; ++i) {
    k::KYarnBsdf yb = random_yarn(rng);
    const Vec3 wo = uniform_sphere(rng);
    const k::KYarnCycles c = k::yarn_cycles_make(yb, wo);
    EXPECT_NEAR(c.p0 + c.p1 + c.p2 + c.p3, (c.p0 + c.p1 + c.p2 + c.p3) > 0 ? 1.0 : 0.0, 1e-6);
    const float u1 = rng.uniform(), u2 = rng.uniform();
    const k::KBsdfSample s = k::yarn_cycles_sample(c, wo, u1, u2);
    if (s.pdf <= 0) {
      EXPECT_EQ(s.flags, 0);
      EXPECT_EQ(maxc(s.weight), 0.0);
    } else if (k::kb_has_flag(s.flags, KB_DELTA)) {
      ++delta;
      EXPECT_EQ(s.flags, KB_TRANSMIT + KB_DELTA);
      EXPECT_EQ(s.wi.x, -wo.x);
      EXPECT_EQ(s.wi.z, -wo.z);
      EXPECT_FLOAT_EQ(s.pdf, c.p3);
      EXPECT_NEAR(s.weight.y, c.w.through / c.p3, 1e-6 * s.weight.y);
    } else {
      const bool r = wo.z * s.wi.z > 0;
      (r ? refl : trans)++;
      EXPECT_EQ(s.flags, r ? KB_REFLECT : KB_TRANSMIT);
      const float pdf = k::yarn_cycles_pdf(c, wo, s.wi);
      const Vec3 e = k::yarn_cycles_eval(c, wo, s.wi);
      worst_p = std::max(worst_p, double(std::fabs(s.pdf - pdf) / pdf));
      worst_w = std::max(worst_w, std::fabs(s.weight.y - e.y / pdf) / (e.y / pdf + 1e-3));
    }
    // The smooth lobes alone, given that the delta was not chosen.
    const k::KBsdfSample t = k::yarn_cycles_sample_smooth(c, wo, u1, u2);
    EXPECT_FALSE(k::kb_has_flag(t.flags, KB_DELTA));
    if (t.pdf > 0) {
      const float ps = k::yarn_cycles_pdf_smooth(c, wo, t.wi);
      const Vec3 e = k::yarn_cycles_eval(c, wo, t.wi);
      worst_ps = std::max(worst_ps, double(std::fabs(t.pdf - ps) / ps));
      worst_ws = std::max(worst_ws, std::fabs(t.weight.y - e.y / ps) / (e.y / ps + 1e-3));
      EXPECT_NEAR(ps * (c.p0 + c.p1 + c.p2), k::yarn_cycles_pdf(c, wo, t.wi), 1e-6 * ps);
    }
  }
  std::printf("[cycles consistency] %d R, %d T, %d delta samples; max rel |pdf - pdf()| %.3g (smooth %.3g), "
              "|w - eval/pdf| %.3g (smooth %.3g)\n",
              refl, trans, delta, worst_p, worst_ps, worst_w, worst_ws);
  // (random optical depths up to 50 leave the translucent lobe little)
  EXPECT_GT(refl, 10000);
  EXPECT_GT(trans, 2000);
  EXPECT_GT(delta, 2000);
  EXPECT_LT(worst_p, 1e-6);
  EXPECT_LT(worst_ps, 1e-6);
  EXPECT_LT(worst_w, 1e-5);
  EXPECT_LT(worst_ws, 1e-5);
}

TEST(BsdfCycles, LobesVanishWhereTheExactOnesDo) {
  const Vec3 grey{0.5f, 0.5f, 0.5f}, black{0, 0, 0};
  const Vec3 wo = dir_deg(35, 10);
  auto make = [&](float eta, Vec3 kr, Vec3 kt, float B, float r) {
    return k::yarn_cycles_make(k::yarn_bsdf_make(k::bsdf_mf_make(0.3f, 0.3f, eta), k::bsdf_mf_make(0.3f, 0.5f, eta),
                                                 kr, kt, B, r, 1.f, k::bsdf_att_make(1.f, 1)),
                               wo);
  };
  k::KYarnCycles c = make(1.5f, grey, grey, 0.7f, 0.6f);
  EXPECT_GT(std::min({c.p0, c.p1, c.p2, c.p3}), 0.f);
  c = make(1.f, grey, grey, 1.f, 0.6f);  // index-matched, all light scattered: no GGX, no delta
  EXPECT_EQ(c.w.spec, 0.f);
  EXPECT_EQ(c.w.through, 0.f);
  EXPECT_EQ(c.p0, 0.f);
  EXPECT_EQ(c.p3, 0.f);
  c = make(1.5f, black, black, 0.5f, 0.5f);  // black body: no diffuse(); translucent() has f_T's share alone
  EXPECT_EQ(c.p1, 0.f);
  EXPECT_GT(c.p2, 0.f);
  EXPECT_EQ(c.w.body_t.x, c.w.body_t.z);
  EXPECT_NEAR(c.w.through / (c.w.through + c.w.body_t.x), std::exp(-0.3 * 0.5 / 0.01), 1e-6);
  c = make(1.f, black, black, 1.f, 0.5f);  // nothing: sampling fails cleanly
  const k::KBsdfSample s = k::yarn_cycles_sample(c, wo, 0.5f, 0.5f);
  EXPECT_EQ(s.pdf, 0.f);
  EXPECT_EQ(s.flags, 0);
  EXPECT_EQ(k::yarn_cycles_sample_smooth(c, wo, 0.5f, 0.5f).pdf, 0.f);
  // Exactly grazing: black, like the exact BSDF.
  c = make(1.5f, grey, grey, 0.7f, 0.6f);
  const k::KYarnCycles g = k::yarn_cycles_make(yarn_of(Params{}), v3(1, 0, 0));
  EXPECT_EQ(g.w.spec + g.w.through + g.w.body_r.x + g.w.body_t.x, 0.f);
  // yarn_cycles_lobes is the made mixture's weights.
  const k::KCyclesLobes l = k::yarn_cycles_lobes(yarn_of(Params{}), wo);
  const k::KYarnCycles m = k::yarn_cycles_make(yarn_of(Params{}), wo);
  EXPECT_EQ(l.spec, m.w.spec);
  EXPECT_EQ(l.through, m.w.through);
  EXPECT_EQ(l.body_t.z, m.w.body_t.z);
}

TEST(BsdfCycles, NoNanInfOrNegativeValuesAnywhere) {
  Rng rng(24);
  std::vector<Vec3> dirs = {v3(0, 0, 1), v3(0, 0, -1), v3(1, 0, 0), v3(0, 1, 0), v3(0, -1, 0),
                            normalized(v3(1, 0, 1e-6)), normalized(v3(0, 1, -1e-6)),
                            normalized(v3(-0.6, 0.8, 1e-6)), normalized(v3(0.3, -0.2, -1e-6)),
                            normalized(v3(1, 1, 1)), normalized(v3(1, -1, -1))};
  for (int i = 0; i < 40; ++i) dirs.push_back(uniform_sphere(rng));
  long checked = 0;
  for (int t = 0; t < 300; ++t) {
    const k::KYarnBsdf p = random_yarn(rng);
    for (Vec3 wo : dirs) {
      const k::KYarnCycles c = k::yarn_cycles_make(p, wo);
      const float ws[] = {c.w.spec, c.w.through, c.w.body_r.x, c.w.body_r.y, c.w.body_r.z, c.w.body_t.x,
                          c.w.body_t.y, c.w.body_t.z, c.p0, c.p1, c.p2, c.p3};
      for (float w : ws) ASSERT_TRUE(std::isfinite(w) && w >= 0) << w;
      ASSERT_LE(c.w.spec, 1.f + 1e-6f);
      ASSERT_LE(c.w.through, 1.f + 1e-6f);
      const Vec3 cand[] = {dirs[size_t(rng.next() % dirs.size())], v3(-wo.x, -wo.y, -wo.z), wo,
                           v3(-wo.x, -wo.y, wo.z), v3(wo.x, wo.y, -wo.z)};
      for (Vec3 wi : cand) {
        const Vec3 e = k::yarn_cycles_eval(c, wo, wi);
        const float pdf = k::yarn_cycles_pdf(c, wo, wi), ps = k::yarn_cycles_pdf_smooth(c, wo, wi);
        ASSERT_TRUE(std::isfinite(e.x) && std::isfinite(e.y) && std::isfinite(e.z) && std::isfinite(pdf) &&
                    std::isfinite(ps));
        ASSERT_TRUE(e.x >= 0 && e.y >= 0 && e.z >= 0 && pdf >= 0 && ps >= 0);
        ++checked;
      }
      for (float u1 : {0.f, 0.3f, 0.99999994f})
        for (float u2 : {0.f, 0.7f, 0.99999994f})
          for (int smooth = 0; smooth < 2; ++smooth) {
            const k::KBsdfSample s =
                smooth ? k::yarn_cycles_sample_smooth(c, wo, u1, u2) : k::yarn_cycles_sample(c, wo, u1, u2);
            ASSERT_TRUE(std::isfinite(s.weight.x) && std::isfinite(s.weight.y) && std::isfinite(s.weight.z) &&
                        std::isfinite(s.pdf) && std::isfinite(s.wi.x) && std::isfinite(s.wi.y) &&
                        std::isfinite(s.wi.z));
            ASSERT_TRUE(s.weight.x >= 0 && s.weight.y >= 0 && s.weight.z >= 0 && s.pdf >= 0);
            if (maxc(s.weight) > 0) ASSERT_GT(s.pdf, 0.f);
            if (s.pdf > 0)
              ASSERT_NEAR(double(s.wi.x) * s.wi.x + double(s.wi.y) * s.wi.y + double(s.wi.z) * s.wi.z, 1.0, 1e-5);
            ++checked;
          }
    }
  }
  std::printf("[cycles robustness] %ld evaluations and samples, all finite and non-negative\n", checked);
}

// ---- Chi-square of the sampling ------------------------------------------------

struct Chi2Case {
  std::string name;
  Params p;
  double theta = 0, phi = 0;
  bool smooth = false;
};
void PrintTo(const Chi2Case& c, std::ostream* os) { *os << c.name; }

std::vector<Chi2Case> chi2_cases() {
  std::vector<Chi2Case> v;
  for (const Params& p : param_sets())
    for (double th : {0.0, 45.0, 70.0, 85.0, 120.0})
      for (int smooth = 0; smooth < 2; ++smooth) {
        Chi2Case c;
        c.p = p;
        c.theta = th;
        c.phi = 75.0;
        c.smooth = smooth == 1;
        c.name = "Cycles_" + p.tag + "_th" + std::to_string(int(th)) + (c.smooth ? "_smooth" : "");
        v.push_back(c);
      }
  return v;
}

class BsdfCyclesChi2 : public ::testing::TestWithParam<Chi2Case> {};

// The delta samples (and failed ones) fall in the chi-square test's failure
// bin, whose expectation is 1 - int pdf: p3 plus the GGX lobe's share that
// leaves below the surface.
TEST_P(BsdfCyclesChi2, SampleMatchesPdf) {
  const Chi2Case& c = GetParam();
  const Vec3 wo = dir_deg(c.theta, c.phi);
  const k::KYarnCycles m = k::yarn_cycles_make(yarn_of(c.p), wo);
  SampleFn sample = [&](float a, float b, Vec3* wi) {
    const k::KBsdfSample s = c.smooth ? k::yarn_cycles_sample_smooth(m, wo, a, b) : k::yarn_cycles_sample(m, wo, a, b);
    *wi = s.wi;
    return s.pdf > 0.f && !k::kb_has_flag(s.flags, KB_DELTA);
  };
  DirFn pdf = [&](Vec3 wi) {
    return double(c.smooth ? k::yarn_cycles_pdf_smooth(m, wo, wi) : k::yarn_cycles_pdf(m, wo, wi));
  };
  Chi2Options opt;
  opt.significance = sidak(0.01, int(chi2_cases().size()));
  opt.seed = std::hash<std::string>{}(c.name);
  const Chi2Outcome r = chi2_test(c.name, sample, pdf, opt);
  std::printf("[chi2] %-36s p = %.4f  chi2 = %8.1f  dof = %4d  int(pdf) = %.5f  failed+delta = %.5f (p3 %.5f)\n",
              c.name.c_str(), r.p_value, r.stat, r.dof, r.pdf_integral, r.fail_fraction, c.smooth ? 0.0 : m.p3);
  EXPECT_TRUE(r.pass) << r.message << " (per-test significance " << opt.significance << ")";
  EXPECT_NEAR(r.pdf_integral + r.fail_fraction, 1.0, 5e-3) << c.name;
}

INSTANTIATE_TEST_SUITE_P(Mixture, BsdfCyclesChi2, ::testing::ValuesIn(chi2_cases()),
                         [](const ::testing::TestParamInfo<Chi2Case>& info) { return info.param.name; });

// ---- The isotropic footprint (multiscale.h) -----------------------------------

TEST(MultiScaleFootprint, IsotropicFootprintFromDifferentialLengths) {
  const float us = 40.f;
  // Seen along the normal: a square of side uv_scale (len_x + len_y) / 2.
  k::KFootprintAxes f = k::knit_footprint_isotropic(0.01f, 0.03f, k::kv3(0, 0, 1), us);
  EXPECT_FLOAT_EQ(f.fx.x, 0.8f);
  EXPECT_FLOAT_EQ(f.fx.y, 0.f);
  EXPECT_FLOAT_EQ(f.fy.x, 0.f);
  EXPECT_FLOAT_EQ(f.fy.y, 0.8f);
  // At 60 degrees, along the view's projection (here at 30 degrees from +u)
  // twice as long, across it unchanged; the sign and length of the
  // direction do not matter.
  const double th = 60 * kPi / 180, ph = 30 * kPi / 180;
  for (double s : {1.0, -3.0}) {
    const k::kvec3 v = k::kv3(float(s * std::sin(th) * std::cos(ph)), float(s * std::sin(th) * std::sin(ph)),
                              float(s * std::cos(th)));
    f = k::knit_footprint_isotropic(0.02f, 0.02f, v, us);
    EXPECT_NEAR(std::hypot(f.fx.x, f.fx.y), 1.6, 1e-5);
    EXPECT_NEAR(std::hypot(f.fy.x, f.fy.y), 0.8, 1e-6);
    EXPECT_NEAR(std::fabs(f.fx.x * std::sin(ph) - f.fx.y * std::cos(ph)), 0.0, 1e-6);  // along the projection
    EXPECT_NEAR(f.fx.x * f.fy.x + f.fx.y * f.fy.y, 0.0, 1e-6);                          // perpendicular
    EXPECT_EQ(f.fx.z, 0.f);
    EXPECT_EQ(f.fy.z, 0.f);
  }
  // Grazing: the stretch stops at 1 / 0.1.
  f = k::knit_footprint_isotropic(0.02f, 0.02f, k::kv3(1, 0, 1e-4f), us);
  EXPECT_NEAR(f.fx.x, 8.0, 1e-4);
  EXPECT_NEAR(f.fy.y, 0.8, 1e-6);
  f = k::knit_footprint_isotropic(0.02f, 0.02f, k::kv3(0, 1, 0), us);
  EXPECT_NEAR(f.fx.y, 8.0, 1e-4);
  EXPECT_NEAR(f.fy.x, -0.8, 1e-6);
  // Degenerate input stays finite.
  f = k::knit_footprint_isotropic(0.f, 0.f, k::kv3(0, 0, 0), us);
  EXPECT_TRUE(std::isfinite(f.fx.x) && std::isfinite(f.fy.y));
}

}  // namespace
