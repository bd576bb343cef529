// Ply and fiber profiles (native/kernel/ply_profile.h, knit/ply_profile.h):
// the closed-form shadowing against a brute-force 2D visibility computation,
// the table lookup against the closed form, periodicity along the twist, the
// perturbed frame, and validation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "bsdf_test_util.h"
#include "knit/ply_profile.h"

namespace {

using namespace knit;
using namespace knit::test;

// Cosine-weighted visibility of the outer boundary of a ring of n discs
// (radius a, centres on radius c) at phase psi, by casting 2D rays against
// every disc, in double. Also returns the normal tilt.
struct RingRef {
  double shadow, delta;
};
RingRef ring_ref(int n, double c, double a, double psi) {
  double period = 2 * kPi / n;
  // The boundary point seen along the radial line at psi: the largest hit of
  // the line with any disc.
  double best = -1, bx = 0, by = 0, bcx = 0, bcy = 0;
  double ex = std::cos(psi), ey = std::sin(psi);
  for (int k = 0; k < n; ++k) {
    double cx = c * std::cos(k * period), cy = c * std::sin(k * period);
    double b = ex * cx + ey * cy, disc = b * b - (cx * cx + cy * cy - a * a);
    if (disc < 0) continue;
    double t = b + std::sqrt(disc);
    if (t > best) {
      best = t;
      bx = t * ex;
      by = t * ey;
      bcx = cx;
      bcy = cy;
    }
  }
  RingRef r{1.0, 0.0};
  if (best < 0) return r;  // the line misses every disc (gap): not compared
  double nx = (bx - bcx) / a, ny = (by - bcy) / a;
  double theta = std::atan2(ny, nx);
  r.delta = std::remainder(theta - psi, 2 * kPi);
  // Cosine-weighted directions are uniform in sin(angle from the normal).
  const int m = 4000;
  int blocked = 0;
  double ox = bx + 1e-9 * nx, oy = by + 1e-9 * ny;
  for (int i = 0; i < m; ++i) {
    double sa = -1.0 + (i + 0.5) * 2.0 / m, ang = theta + std::asin(sa);
    double dx = std::cos(ang), dy = std::sin(ang);
    for (int k = 0; k < n; ++k) {
      double cx = c * std::cos(k * period) - ox, cy = c * std::sin(k * period) - oy;
      double b = dx * cx + dy * cy, disc = b * b - (cx * cx + cy * cy - a * a);
      if (disc >= 0 && b + std::sqrt(disc) > 1e-7) {
        ++blocked;
        break;
      }
    }
  }
  r.shadow = 1.0 - double(blocked) / m;
  return r;
}

TEST(PlyProfile, ClosedFormShadowMatchesBruteForceVisibility) {
  double worst_g = 0, worst_gap = 0, worst_d = 0;
  for (int n : {2, 3, 4, 5, 6, 8}) {
    for (double scale : {1.0, 0.9, 1.1}) {  // touching, gaps, overlapping
      double a = double(float(PlyParams::packed_radius(n) * scale)), c = double(float(1 - a));
      for (int i = 0; i <= 60; ++i) {
        double psi = (i / 60.0 - 0.5) * 2 * kPi / n * 0.999;
        if (c * std::abs(std::sin(psi)) > a) continue;  // the radial line passes through a gap
        RingRef ref = ring_ref(n, c, a, psi);
        k::KPlyRing got = k::ply_ring_eval(n, float(c), float(a), float(psi));
        double dg = std::abs(got.shadow - ref.shadow);
        (scale < 1.0 ? worst_gap : worst_g) = std::max(scale < 1.0 ? worst_gap : worst_g, dg);
        worst_d = std::max(worst_d, std::abs(got.delta - ref.delta));
      }
    }
  }
  std::printf("[ply] closed-form vs brute-force 2D visibility: max |dG| %.4f (touching/overlapping), "
              "%.4f (10%% gaps), max |d tilt| %.2e rad\n", worst_g, worst_gap, worst_d);
  // Touching or overlapping plies: only the two nearest neighbours can occlude.
  // 4000 rays: quadrature error ~5e-4; float geometry near the contact point.
  EXPECT_LT(worst_g, 3e-3);
  // With gaps, plies further away are seen through the gaps and ignored.
  EXPECT_LT(worst_gap, 0.08);
  EXPECT_LT(worst_d, 1e-4);
}

TEST(PlyProfile, CrestsAreLitAndGroovesShadowed) {
  const float a = PlyParams::packed_radius(3);
  k::KPlyRing crest = k::ply_ring_eval(3, 1 - a, a, 0.f);
  k::KPlyRing groove = k::ply_ring_eval(3, 1 - a, a, float(kPi / 3) * 0.999f);
  EXPECT_NEAR(crest.shadow, 1.f, 1e-6);
  EXPECT_NEAR(crest.delta, 0.f, 1e-6);
  // At the bottom of the groove between touching plies the neighbour closes
  // the whole half-plane.
  EXPECT_LT(groove.shadow, 0.1f);
  EXPECT_GT(groove.delta, 0.5f);  // the ply flank faces sideways
  // Darker and more tilted from the crest down into the groove.
  float prev = 1.f, prev_d = 0.f;
  for (int i = 1; i <= 50; ++i) {
    k::KPlyRing r = k::ply_ring_eval(3, 1 - a, a, float(kPi / 3) * i / 50.f);
    EXPECT_LE(r.shadow, prev + 1e-6f);
    EXPECT_GE(r.delta, prev_d - 1e-6f);
    prev = r.shadow;
    prev_d = r.delta;
  }
  // Symmetric about the crest.
  for (float psi : {0.1f, 0.4f, 0.9f}) {
    k::KPlyRing p = k::ply_ring_eval(3, 1 - a, a, psi), m = k::ply_ring_eval(3, 1 - a, a, -psi);
    EXPECT_NEAR(p.shadow, m.shadow, 1e-6);
    EXPECT_NEAR(p.delta, -m.delta, 1e-6);
  }
}

TEST(PlyProfile, TableLookupMatchesClosedForm) {
  Rng rng(41);
  for (int cfg = 0; cfg < 5; ++cfg) {
    PlyParams p;
    p.ply_count = 2 + cfg;
    const bool gaps = cfg == 4;  // plies 10% thinner than packed
    p.ply_radius = PlyParams::packed_radius(p.ply_count) * (gaps ? 0.9f : 1.f);
    p.fiber_count = 20 + 30 * cfg;
    PlyProfile prof(p);
    double worst_g = 0, sum_g = 0, worst_n = 0, sum_n = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      float phi = float(2 * kPi * rng.uniform_d()), s = float(20 * rng.uniform_d());
      k::KPlyShade a = prof.lookup(phi, s), b = prof.procedural(phi, s);
      double dg = std::abs(a.shadow - b.shadow);
      double dn = std::acos(std::min(1.0, double(a.n.x) * b.n.x + double(a.n.y) * b.n.y + double(a.n.z) * b.n.z));
      worst_g = std::max(worst_g, dg);
      worst_n = std::max(worst_n, dn);
      sum_g += dg;
      sum_n += dn;
    }
    std::printf("[ply] %d plies%s, %d fibres: table (%zu bytes) vs closed form: G max %.4f mean %.1e; "
                "normal max %.4f rad mean %.1e rad\n",
                p.ply_count, gaps ? " with gaps" : "", p.fiber_count, PlyProfile::table_bytes(), worst_g,
                sum_g / n, worst_n, sum_n / n);
    EXPECT_LT(sum_g / n, 1e-3);
    EXPECT_LT(sum_n / n, 1e-3);
    if (!gaps) {
      // Packed plies: the warped abscissae resolve the grooves.
      EXPECT_LT(worst_g, 0.02);
      EXPECT_LT(worst_n, 0.01);
    }
    // With gaps the closed form clamps to the ply's tangent point, a kink the
    // table smooths over one cell; the fibre phase, which follows the normal
    // tilt, then shifts and G_f can differ by ~0.25 in that cell alone.
  }
}

TEST(PlyProfile, TableStorage) {
  EXPECT_EQ(PlyProfile::table_bytes(), 3072u);
  EXPECT_EQ(KPLY_TABLE_SIZE, 3 * KPLY_TABLE_N);
  std::printf("[ply] profile table: %d floats = %zu bytes (paper: 0.02 MB of 1D textures)\n",
              KPLY_TABLE_SIZE, PlyProfile::table_bytes());
}

TEST(PlyProfile, PeriodicAroundAndAlongTheYarn) {
  PlyParams p;  // 3 plies, twisted, 40 fibres
  PlyProfile prof(p);
  const k::KPlyParams& kp = prof.kernel_params();
  EXPECT_EQ(kp.fiber_ring, 20);
  Rng rng(42);
  for (int i = 0; i < 2000; ++i) {
    float phi = float(2 * kPi * rng.uniform_d()), s = float(5 * rng.uniform_d());
    k::KPlyShade a = prof.procedural(phi, s);
    // One ply period around the yarn.
    k::KPlyShade b = prof.procedural(phi + float(2 * kPi / 3), s);
    EXPECT_NEAR(a.ply_shadow, b.ply_shadow, 2e-4);
    // Along the helix: the ply pattern moves with the twist.
    float ds = 0.37f;
    k::KPlyShade c = prof.procedural(phi + kp.ply_rate * ds, s + ds);
    EXPECT_NEAR(a.ply_shadow, c.ply_shadow, 2e-4);
    EXPECT_GE(a.shadow, 0.f);
    EXPECT_LE(a.shadow, 1.f);
    EXPECT_NEAR(a.shadow, a.ply_shadow * a.fiber_shadow, 1e-6);
  }
  // The helix angle at the surface is the twist: after one ply pitch
  // L = 2 pi R / tan(twist) the pattern repeats.
  float pitch = float(2 * kPi * p.yarn_radius / std::tan(p.ply_twist));
  EXPECT_NEAR(kp.ply_rate * pitch, 2 * kPi, 1e-4);
}

TEST(PlyProfile, PerturbedFrameIsOrthonormalAndFollowsTheTwist) {
  PlyParams p;
  p.fiber_twist = 0.f;
  PlyProfile prof(p);
  Rng rng(43);
  for (int i = 0; i < 5000; ++i) {
    k::KPlyShade f = prof.lookup(float(2 * kPi * rng.uniform_d()), float(3 * rng.uniform_d()));
    auto dot = [](Vec3 u, Vec3 v) { return double(u.x) * v.x + double(u.y) * v.y + double(u.z) * v.z; };
    EXPECT_NEAR(dot(f.n, f.n), 1.0, 1e-5);
    EXPECT_NEAR(dot(f.t, f.t), 1.0, 1e-5);
    EXPECT_NEAR(dot(f.b, f.b), 1.0, 1e-5);
    EXPECT_NEAR(dot(f.n, f.t), 0.0, 1e-5);
    EXPECT_NEAR(dot(f.n, f.b), 0.0, 1e-5);
    EXPECT_NEAR(dot(f.t, f.b), 0.0, 1e-5);
    Vec3 nxt = v3(f.n.y * f.t.z - f.n.z * f.t.y, f.n.z * f.t.x - f.n.x * f.t.z, f.n.x * f.t.y - f.n.y * f.t.x);
    EXPECT_NEAR(dot(nxt, f.b), 1.0, 1e-5);  // right-handed like (x, y, z)
    EXPECT_GT(f.n.z, 0.f);
    Vec3 local = k::ply_to_local(f, f.n);
    EXPECT_NEAR(local.z, 1.f, 1e-5);
  }
  // On a ply crest the fibres run at the ply twist angle.
  k::KPlyShade crest = prof.procedural(0.f, 0.f);
  EXPECT_NEAR(crest.t.x, std::cos(p.ply_twist), 1e-5);
  EXPECT_NEAR(crest.t.y, std::sin(p.ply_twist), 1e-5);
  EXPECT_NEAR(crest.n.z, 1.f, 1e-6);
  // Balanced twist: a counter-twisted fibre brings the crest tangent back.
  PlyParams q = p;
  q.fiber_twist = -p.ply_twist;
  k::KPlyShade back = PlyProfile(q).procedural(0.f, 0.f);
  EXPECT_NEAR(back.t.x, 1.f, 1e-5);
  // A single untwisted ply without fibres: the unperturbed frame.
  PlyParams one;
  one.ply_count = 1;
  one.ply_twist = 0.f;
  one.fiber_count = 0;
  one.fiber_twist = 0.f;
  k::KPlyShade id = PlyProfile(one).lookup(1.f, 2.f);
  EXPECT_NEAR(id.t.x, 1.f, 1e-6);
  EXPECT_NEAR(id.b.y, 1.f, 1e-6);
  EXPECT_NEAR(id.n.z, 1.f, 1e-6);
  EXPECT_FLOAT_EQ(id.shadow, 1.f);
}

TEST(PlyProfile, FibreRingFromFibreCount) {
  EXPECT_EQ(k::ply_params_make(3, 0.46f, 0.5f, 40, -0.3f, 0.75f).fiber_ring, 20);
  EXPECT_EQ(k::ply_params_make(3, 0.46f, 0.5f, 6, -0.3f, 0.75f).fiber_ring, 5);
  EXPECT_EQ(k::ply_params_make(3, 0.46f, 0.5f, 4, -0.3f, 0.75f).fiber_ring, 3);
  EXPECT_EQ(k::ply_params_make(3, 0.46f, 0.5f, 3, -0.3f, 0.75f).fiber_ring, 0);
  EXPECT_EQ(k::ply_params_make(3, 0.46f, 0.5f, 0, -0.3f, 0.75f).fiber_ring, 0);
  EXPECT_GT(k::ply_params_make(3, 0.46f, 0.5f, 10000, -0.3f, 0.75f).fiber_ring, 100);
}

void expect_invalid(const PlyParams& p, const std::string& needle) {
  try {
    p.validate();
    ADD_FAILURE() << "accepted invalid parameters, expected an error naming " << needle;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(PlyProfile, ValidationNamesTheFieldAndValue) {
  PlyParams ok;
  EXPECT_NO_THROW(ok.validate());
  auto with = [&](auto change) {
    PlyParams p = ok;
    change(p);
    return p;
  };
  expect_invalid(with([](auto& p) { p.ply_count = 0; }), "PlyParams.ply_count = 0");
  expect_invalid(with([](auto& p) { p.ply_count = 17; }), "ply_count = 17");
  expect_invalid(with([](auto& p) { p.ply_radius = 1.f; }), "ply_radius = 1");
  expect_invalid(with([](auto& p) { p.ply_twist = 2.f; }), "ply_twist = 2");
  expect_invalid(with([](auto& p) { p.fiber_count = -3; }), "fiber_count = -3");
  expect_invalid(with([](auto& p) { p.fiber_twist = NAN; }), "fiber_twist = nan");
  expect_invalid(with([](auto& p) { p.yarn_radius = 0.f; }), "yarn_radius = 0");
  EXPECT_THROW(PlyProfile(with([](auto& p) { p.yarn_radius = -1.f; })), std::invalid_argument);
}

}  // namespace
