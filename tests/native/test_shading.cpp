// KnitMaterial: the renderer-facing shading layer over the geometry and the
// BSDF, checked against KnitSurface and against explicit-tube ray casts from
// both sides of the fabric.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "groundtruth.h"
#include "knit/shading.h"
#include "test_patterns.h"

namespace {

using namespace knit;
using namespace knit::test;

KnitMaterialParams flat_params(float uv_scale = 1) {
  KnitMaterialParams p;
  p.uv_scale = uv_scale;
  return p;
}

// A view ray entering sc's window at a random point, at up to max_theta
// from the normal: the explicit tubes' first hit and the material's shading.
struct ViewSample {
  double x = 0, y = 0;
  D3 d{};
  TubeHit gt;
  BaseHit bh;
  KnitShade sh;
};
ViewSample view_sample(const GroundTruthScene& sc, const KnitMaterial& m, std::mt19937& rng, double max_theta) {
  std::uniform_real_distribution<double> U(0, 1);
  ViewSample v;
  v.x = sc.x0 + (sc.x1 - sc.x0) * U(rng);
  v.y = sc.y0 + (sc.y1 - sc.y0) * U(rng);
  const double th = max_theta * U(rng), ph = 6.283 * U(rng);
  const D3 wi = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
  D3 o;
  sc.entry_ray(v.x, v.y, wi, o, v.d);
  v.gt = sc.tubes.intersect(o, v.d, 0, sc.shell_exit(o, v.d));
  v.bh.u = float(v.x);
  v.bh.v = float(v.y);
  v.sh = m.shade(v.bh, k::kv3(float(v.d[0]), float(v.d[1]), float(v.d[2])), nullptr);
  return v;
}

TEST(Shading, FrontNearFieldMatchesCapmAndExplicitTubes) {
  GroundTruthScene sc(seed(), StitchParams{}, 0, 45);
  KnitMaterialParams mp = flat_params();
  mp.ply_detail = false;
  KnitMaterial m(seed(), mp);
  std::mt19937 rng(2);
  int n = 0, agree = 0, both = 0;
  double normal_err = 0;
  for (int i = 0; i < 600; ++i) {
    const ViewSample v = view_sample(sc, m, rng, 1.3);
    const double x = v.x, y = v.y;
    const TubeHit& gt = v.gt;
    const KnitShade& sh = v.sh;
    ++n;
    if (sh.pass_through == !gt.hit) ++agree;
    if (gt.hit && !sh.pass_through) {
      ++both;
      normal_err += angle_deg({sh.sn.x, sh.sn.y, sh.sn.z}, gt.normal);
      // The offset leads from the base hit (x, y, shell_top) to the yarn hit.
      const D3 p = {x + sh.offset.x, y + sh.offset.y, sc.surface.shell_top() + sh.offset.z};
      EXPECT_LT(norm(sub(p, gt.p)), 0.25) << i;
    }
  }
  EXPECT_GE(agree, n * 97 / 100);
  EXPECT_LT(normal_err / both, 2.0);
}

TEST(Shading, RaysFromBehindHitTheBackOfTheFabric) {
  GroundTruthScene sc(rib_1x1(), StitchParams{}, 0, 45);
  KnitMaterialParams mp = flat_params();
  mp.ply_detail = false;
  KnitMaterial m(rib_1x1(), mp);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> U(0, 1);
  const double top = sc.surface.shell_top();
  int n = 0, agree = 0, both = 0;
  double zerr = 0;
  for (int i = 0; i < 600; ++i) {
    const double x = sc.x0 + (sc.x1 - sc.x0) * U(rng), y = sc.y0 + (sc.y1 - sc.y0) * U(rng);
    const double th = 1.2 * U(rng), ph = 6.283 * U(rng);
    // The ray travels upwards and meets the mesh (z = top) at (x, y).
    const D3 d = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
    const double back = 2 * top / d[2];
    const D3 o = {x - back * d[0], y - back * d[1], -top};
    const TubeHit gt = sc.tubes.intersect(o, d, 0, back);
    BaseHit bh;
    bh.u = float(x);
    bh.v = float(y);
    const KnitShade sh = m.shade(bh, k::kv3(float(d[0]), float(d[1]), float(d[2])), nullptr);
    ++n;
    EXPECT_TRUE(sh.from_back);
    if (sh.pass_through == !gt.hit) ++agree;
    if (gt.hit && !sh.pass_through) {
      ++both;
      zerr += std::abs(top + sh.offset.z - gt.p[2]);
      EXPECT_LT(sh.sn.x * d[0] + sh.sn.y * d[1] + sh.sn.z * d[2], 0.05) << "the hit faces the incoming ray";
    }
  }
  EXPECT_GE(agree, n * 97 / 100);
  EXPECT_LT(zerr / both, 0.02);
}

TEST(Shading, NoParallaxUsesTheHeightAtTheHit) {
  KnitMaterialParams mp = flat_params();
  mp.capm = false;
  mp.ply_detail = false;
  KnitMaterial m(stockinette(), mp);
  KnitSurface s(stockinette(), StitchParams{});
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> U(0, 1);
  for (int i = 0; i < 200; ++i) {
    BaseHit bh;
    bh.u = 40 * U(rng);
    bh.v = 40 * U(rng);
    const KnitShade sh = m.shade(bh, k::kv3_normalize(k::kv3(0.6f, 0.1f, -0.5f)), nullptr);
    const SurfaceHit q = s.query(bh.u, bh.v);
    ASSERT_EQ(sh.pass_through, !q.hit);
    if (q.hit) {
      EXPECT_NEAR(sh.offset.x, 0, 1e-5);
      EXPECT_NEAR(sh.offset.y, 0, 1e-5);
      EXPECT_NEAR(sh.sn.z, q.normal.z, 1e-4);
    }
  }
}

TEST(Shading, MultiScaleMixesColoursAndWidensRoughness) {
  // Two-colour stripes: half the rows colour 0 (red), half colour 1 (blue).
  Pattern stripes = Pattern::from_rows({{0}, {0}}, {{0}, {1}});
  KnitMaterialParams mp = flat_params();
  mp.mode = KnitMode::MultiScale;
  mp.bsdf.reflect_colors = {Rgb{1, 0, 0}, Rgb{0, 0, 1}};
  mp.bsdf.transmit_colors = mp.bsdf.reflect_colors;
  mp.table_bsdf = false;  // the mean normal's widened lobes (the tabulated BSDF: test_table_bsdf.cpp)
  KnitMaterial m(stripes, mp);
  BaseHit bh;
  bh.u = 50;
  bh.v = 50;
  bh.dudx = 30;
  bh.dvdy = 30;
  const KnitShade sh = m.shade(bh, k::kv3(0, 0, -1), nullptr, {0.3f, 0.7f});
  ASSERT_FALSE(sh.pass_through);
  EXPECT_GT(sh.point.p_delta, 0.05f);
  EXPECT_LT(sh.point.p_delta, 0.4f);
  EXPECT_NEAR(sh.kd_r.r, 0.5f, 0.15f);
  EXPECT_NEAR(sh.kd_r.b, 0.5f, 0.15f);
  EXPECT_NEAR(sh.kd_r.r + sh.kd_r.b, 1.0f, 1e-4f);
  EXPECT_GT(sh.spec_r.alpha_x * sh.spec_r.alpha_y, mp.bsdf.roughness_x * mp.bsdf.roughness_y * 1.5f)
      << "the footprint's normal spread must widen the specular lobe";
  const float t = m.transmittance(bh, k::kv3(0, 0, -1), nullptr, {0.3f, 0.7f});
  EXPECT_NEAR(t, sh.point.p_delta, 1e-6f);
}

TEST(Shading, StateIsSmall) {
  Pattern big = Pattern::from_rows(std::vector<std::vector<int>>(48, std::vector<int>(48, 0)));
  KnitMaterial m(big, flat_params());
  // Pattern arrays (2 x 48 x 48 int32) + the 3 KiB ply table + parameters.
  EXPECT_LT(m.state_bytes(), 32u * 1024u);
  EXPECT_GT(m.state_bytes(), 2u * 48u * 48u * 4u);
  std::printf("[ state ] 48x48 pattern: %zu bytes (ply table %zu)\n", m.state_bytes(), PlyProfile::table_bytes());
}

TEST(Shading, ParamsValidationNamesTheField) {
  auto msg = [](KnitMaterialParams p) {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  KnitMaterialParams p;
  p.uv_scale = -2;
  EXPECT_NE(msg(p).find("KnitMaterialParams.uv_scale = -2"), std::string::npos);
  p = {};
  p.footprint_points = 0;
  EXPECT_NE(msg(p).find("footprint_points = 0"), std::string::npos);
  p = {};
  p.stitch.a = NAN;
  EXPECT_NE(msg(p).find("a must be finite"), std::string::npos);
  // More colour indices in the pattern than colours given.
  EXPECT_THROW(KnitMaterial(Pattern::from_rows({{0, 1}}, {{0, 1}}), KnitMaterialParams{}), std::invalid_argument);
}

}  // namespace

namespace {

using namespace knit;

// Regression: the multi-scale transmission lobe kept its own roughnesses but
// took the reflection lobe's axes, turning an anisotropic lobe by 90 degrees.
TEST(Shading, MultiScaleTransmissionLobeKeepsItsOrientation) {
  KnitMaterialParams mp;
  mp.uv_scale = 1;
  mp.ply_detail = false;
  mp.mode = KnitMode::MultiScale;
  mp.bsdf.roughness_x = 0.5f;
  mp.bsdf.roughness_y = 0.2f;
  mp.bsdf.trans_roughness_x = 0.3f;
  mp.bsdf.trans_roughness_y = 0.6f;
  KnitMaterial m(test::stockinette(), mp);
  int n = 0;
  for (float u = 1; u < 40; u += 0.37f) {
    BaseHit bh;
    bh.u = u;
    bh.v = 0.61f * u;
    bh.dudx = bh.dvdy = 1e-5f;  // a point: no footprint widening
    const KnitShade sh = m.shade(bh, k::kv3(0, 0, -1), nullptr, {0.3f, 0.6f});
    if (sh.pass_through) continue;
    ++n;
    EXPECT_NEAR(sh.spec_r.alpha_x, 0.5f, 1e-3f);
    EXPECT_NEAR(sh.spec_r.alpha_y, 0.2f, 1e-3f);
    EXPECT_NEAR(sh.spec_t.alpha_x, 0.3f, 1e-3f);
    EXPECT_NEAR(sh.spec_t.alpha_y, 0.6f, 1e-3f);
  }
  EXPECT_GT(n, 50);
}

// Regression: multi-scale colours of indices past the histogram's 8 bins all
// showed colour 7; they now come from one hit of the footprint.
TEST(Shading, MultiScaleShowsColourIndicesPastEight) {
  std::vector<std::vector<int>> codes(10, std::vector<int>(1, 0)), colors(10, std::vector<int>(1, 0));
  for (int r = 0; r < 10; ++r) colors[size_t(r)][0] = r;
  KnitMaterialParams mp;
  mp.uv_scale = 1;
  mp.mode = KnitMode::MultiScale;
  mp.bsdf.reflect_colors.clear();
  for (int c = 0; c < 10; ++c) mp.bsdf.reflect_colors.push_back(Rgb{c / 10.f, 0, 0});
  mp.bsdf.transmit_colors = mp.bsdf.reflect_colors;
  KnitMaterial m(Pattern::from_rows(codes, colors), mp);
  std::vector<int> seen(10, 0);
  for (int i = 0; i < 400; ++i) {
    BaseHit bh;
    bh.u = 3.1f;
    bh.v = 0.45f * float(i % 100);  // rows 0..9 of the repeat, from the top
    bh.dudx = bh.dvdy = 0.01f;
    const KnitShade sh = m.shade(bh, k::kv3(0, 0, -1), nullptr, {0.37f * float(i % 7) / 7, 0.5f});
    if (sh.pass_through) continue;
    ASSERT_GE(sh.point.color, 0);
    ASSERT_LT(sh.point.color, 10);
    EXPECT_NEAR(sh.kd_r.r, sh.point.color / 10.f, 1e-6f);
    seen[size_t(sh.point.color)]++;
  }
  for (int c = 0; c < 10; ++c) EXPECT_GT(seen[size_t(c)], 0) << "colour " << c << " never shown";
}

// FootprintMemo: the camera samples of one pixel find the pixel's box again
// from their own hits, to within their differentials' rounding; with the
// pixel's memo the later ones take the first one's box and its sums. What
// they get must be what the first sample's box gives in their own
// direction (to float rounding, whether or not their direction needs new
// sums), and within the memo's tolerance of their own box's; a box further
// off, or of another material, must be found anew. Rib (a folded box) and
// seed (sub-cell by sub-cell), in eighths and, past 64 eighths, quarters.
TEST(Shading, PixelMemoGivesItsSamplesTheFirstSamplesBox) {
  KnitMaterialParams mp = flat_params();
  mp.mode = KnitMode::MultiScale;
  const KnitMaterial rib(rib_1x1(), mp), sd(seed(), mp), other(rib_1x1(), mp);
  struct Case {
    const char* name;
    const KnitMaterial& m;
    float cells;  // the box's extent
  };
  for (const Case& cs : {Case{"rib_1x1", rib, 0.37f}, Case{"seed", sd, 0.41f}, Case{"rib_1x1 quarters", rib, 0.93f},
                         Case{"seed quarters", sd, 0.93f}}) {
    const KnitMaterial& m = cs.m;
    ASSERT_TRUE(m.footprint_table() && m.table_bsdf());
    const float cw = K_2PI, ch = m.surface().geom().row_spacing;
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> U(-1, 1);
    // A pixel's hits: the centre and the footprint's derivatives within
    // `jitter` of its extent (the renderer's samples show 1e-4 to 1e-3 of
    // the derivatives where the view is steep, a few hundredths where it
    // grazes), the directions over 12 degrees (some cross into other
    // direction nodes). (The centre lies mid-eighth at every edge: a box
    // of 0.93 cells stays in quarters.)
    const auto sample_hit = [&](float jitter) {
      BaseHit bh;
      bh.u = 37.5f * cw + jitter * cs.cells * cw * U(rng);
      bh.v = 11.5f * ch + jitter * cs.cells * ch * U(rng);
      bh.dudx = cs.cells * cw * (1 + jitter * U(rng));
      bh.dvdy = cs.cells * ch * (1 + jitter * U(rng));
      return bh;
    };
    const auto direction = [&]() {
      const float th = 0.6f + 0.1f * U(rng), ph = 0.8f + 0.1f * U(rng);
      return k::kv3(-std::sin(th) * std::cos(ph), -std::sin(th) * std::sin(ph), -std::cos(th));
    };
    const float tol = FootprintMemo::kTolerance;
    for (const float jitter : {2e-4f, 0.9f * tol}) {
      FootprintMemo memo;
      const BaseHit first = sample_hit(0);  // (the others within `jitter` of it)
      double worst_first = 0, worst_own = 0;
      const int n = 40;
      for (int i = 0; i < n; ++i) {
        const BaseHit bh = i == 0 ? first : sample_hit(jitter);
        const Vec3 d = direction();
        const KnitShade with = m.shade(bh, m.route_of(bh, &memo), d, nullptr);
        const KnitShade of_first = m.shade(first, d, nullptr);
        const KnitShade own = m.shade(bh, d, nullptr);
        ASSERT_TRUE(with.from_sub_cells && of_first.from_sub_cells) << cs.name;
        ASSERT_EQ(with.table_bsdf != nullptr, of_first.table_bsdf != nullptr) << cs.name;
        worst_first = std::max(worst_first, double(std::fabs(with.point.p_delta - of_first.point.p_delta)));
        worst_own = std::max(worst_own, double(std::fabs(with.point.p_delta - own.point.p_delta)));
        if (with.table_bsdf)
          for (int sl = 0; sl < m.footprint_table()->classes_present(); ++sl)
            EXPECT_NEAR(with.mix.share[size_t(sl)], of_first.mix.share[size_t(sl)], 2e-6f)
                << cs.name << " sample " << i;
      }
      std::printf("[ memo ] %-16s jitter %.4f: p_delta against the first sample's box: worst %.1e; against the "
                  "sample's own: %.1e\n",
                  cs.name, jitter, worst_first, worst_own);
      EXPECT_LT(worst_first, 2e-6) << cs.name;
      // (a box moved by j of its extent changes its p_delta by at most
      // about 2 j times the contrast of its edges, whose eighths differ by
      // up to one)
      EXPECT_LT(worst_own, 2.5 * jitter) << cs.name;
      EXPECT_EQ(memo.found(), 1) << cs.name;
      EXPECT_EQ(memo.reused(), n - 1) << cs.name;
      // Off by twice the tolerance: found, and its own.
      BaseHit off = first;
      off.u += 2 * tol * cs.cells * cw;
      const Vec3 d = direction();
      const KnitShade with = m.shade(off, m.route_of(off, &memo), d, nullptr);
      EXPECT_NEAR(with.point.p_delta, m.shade(off, d, nullptr).point.p_delta, 2e-6f) << cs.name;
      EXPECT_EQ(memo.found(), 2) << cs.name;
      // The same box of another material: found too.
      other.shade(first, other.route_of(first, &memo), d, nullptr);
      EXPECT_EQ(memo.found(), 3) << cs.name;
      EXPECT_EQ(memo.reused(), n - 1) << cs.name;
    }
  }
}

// Self-shadowing and bounces inside the shell (near field): from a yarn hit,
// the path towards a light (or a sampled direction) either leaves the shell
// or meets other yarn first. Checked against double-precision ray casts of the
// explicit tubes from the tubes' own hit point.
// The patterns of the self-shadowing comparisons, and their material: flat
// base, no ply detail (plain round tubes, as the explicit ones).
std::vector<NamedPattern> shadow_patterns() {
  return {NamedPattern{"stockinette", stockinette()}, NamedPattern{"seed", seed()},
          NamedPattern{"rib_1x1", rib_1x1()}};
}
KnitMaterialParams tube_params() {
  KnitMaterialParams mp = flat_params();
  mp.ply_detail = false;
  return mp;
}
// Whether the model's yarn point and the explicit tubes' hit are the same
// point (else a comparison from them is of different paths).
bool same_yarn_point(const ViewSample& v, double r) {
  const Vec3& p = v.sh.p_yarn;
  return norm(sub(D3{p.x, p.y, p.z}, v.gt.p)) <= 0.02 * r;
}
// A direction uniform over the sphere.
D3 sphere_direction(std::mt19937& rng) {
  std::uniform_real_distribution<double> U(0, 1);
  const double lz = 2 * U(rng) - 1, lp = 6.283 * U(rng), ls = std::sqrt(1 - lz * lz);
  return {ls * std::cos(lp), ls * std::sin(lp), lz};
}
// Distance from p along unit L to the shell's surface |z| = top.
double to_shell_surface(const D3& p, const D3& L, double top) {
  return L[2] > 0 ? (top - p[2]) / L[2] : (p[2] + top) / -L[2];
}

TEST(Shading, PathsFromAYarnHitMeetOtherYarnAsExplicitTubesDo) {
  for (const NamedPattern& np : shadow_patterns()) {
    GroundTruthScene sc(np.pattern, StitchParams{}, 0, 45);
    KnitMaterial m(np.pattern, tube_params());
    const double r = sc.surface.params().r, top = sc.surface.shell_top();
    std::mt19937 rng(7);
    int n = 0, agree = 0, occluded = 0, both = 0;
    double pos_err = 0;
    for (int i = 0; i < 3000 && n < 800; ++i) {
      const ViewSample v = view_sample(sc, m, rng, 1.2);
      const TubeHit& gt = v.gt;
      const BaseHit& bh = v.bh;
      const KnitShade& sh = v.sh;
      if (!gt.hit || sh.pass_through) continue;
      ASSERT_TRUE(sh.in_shell);
      if (!same_yarn_point(v, r)) continue;
      // A direction leaving the tube's surface, over the whole sphere otherwise.
      const D3 L = sphere_direction(rng);
      if (dot(L, gt.normal) < 0.1) continue;
      const double t_exit = to_shell_surface(gt.p, L, top);
      const TubeHit g2 = sc.tubes.intersect(gt.p, L, 0.05 * r, t_exit);
      // Skip the paths that graze a tube (the truth flips under a 3% r move).
      const TubeHit g3 = sc.tubes.intersect(add(gt.p, mul(gt.normal, 0.03 * r)), L, 0.05 * r, t_exit);
      if (g2.hit != g3.hit) continue;
      ++n;
      const Vec3 lw = k::kv3(float(L[0]), float(L[1]), float(L[2]));
      const bool occ = m.occluded_from(bh, sh, lw, nullptr);
      occluded += g2.hit;
      agree += occ == g2.hit;
      const KnitShade next = m.shade_from(bh, sh, lw, nullptr);
      EXPECT_EQ(next.pass_through, !occ) << np.name << " " << i;
      if (g2.hit && !next.pass_through) {
        ++both;
        EXPECT_TRUE(next.in_shell);
        pos_err += norm(sub(D3{next.p_yarn.x, next.p_yarn.y, next.p_yarn.z}, g2.p)) / r;
      }
    }
    std::printf("[self-shadow] %-12s paths %d: agreement %.2f%%, occluded (truth) %.1f%%, next-hit position error "
                "mean %.4f r\n",
                np.name.c_str(), n, 100.0 * agree / n, 100.0 * occluded / n, both ? pos_err / both : 0.0);
    EXPECT_GE(n, 500) << np.name;
    EXPECT_GT(occluded, n / 10) << np.name << ": too few occluded paths for a meaningful test";
    EXPECT_GE(agree, n * 98 / 100) << np.name;
    EXPECT_LT(pos_err / std::max(both, 1), 0.05) << np.name;
  }
  // No shell without parallax: nothing to march from.
  KnitMaterialParams flat = flat_params();
  flat.capm = false;
  KnitMaterial m(seed(), flat);
  BaseHit bh;
  bh.u = 3;
  bh.v = 2;
  const KnitShade sh = m.shade(bh, k::kv3(0, 0, -1), nullptr);
  EXPECT_FALSE(sh.in_shell);
  EXPECT_FALSE(m.occluded_from(bh, sh, k::kv3(0, 0, 1), nullptr));
  EXPECT_TRUE(m.shade_from(bh, sh, k::kv3(0, 0, 1), nullptr).pass_through);
}

// The same for light transmitted through the yarn (a light or a sampled
// direction behind the hit's surface): the path first crosses the hit's own
// tube, which must not count, then meets other yarn or leaves the shell.
// Truth: the ray cast from the explicit tube's hit point leaves the union of
// tubes containing it, then meets a tube or not before the shell's surface.
TEST(Shading, PathsThroughTheHitYarnMeetOtherYarnAsExplicitTubesDo) {
  for (const NamedPattern& np : shadow_patterns()) {
    GroundTruthScene sc(np.pattern, StitchParams{}, 0, 45);
    KnitMaterial m(np.pattern, tube_params());
    const double r = sc.surface.params().r, top = sc.surface.shell_top();
    std::mt19937 rng(11);
    int n = 0, agree = 0, occluded = 0;
    for (int i = 0; i < 6000 && n < 600; ++i) {
      const ViewSample v = view_sample(sc, m, rng, 1.2);
      const TubeHit& gt = v.gt;
      if (!gt.hit || v.sh.pass_through) continue;
      if (!same_yarn_point(v, r)) continue;
      const D3 L = sphere_direction(rng);
      if (dot(L, gt.normal) > -0.1 || std::fabs(L[2]) < 0.05) continue;  // into the tube, not along the shell
      const double t_exit = to_shell_surface(gt.p, L, top);
      // From o along L: out of the tubes holding o (in steps of 0.002),
      // then a tube met before the shell's surface or not.
      const auto meets_yarn = [&](const D3& o) {
        double te = 0.05 * r;
        while (te < t_exit && sc.tubes.inside(add(o, mul(L, te)))) te += 0.002;
        return te < t_exit && sc.tubes.intersect(o, L, te + 1e-6, t_exit).hit;
      };
      const bool truth = meets_yarn(gt.p);
      // Skip the paths that graze a tube (the truth flips under a 3% r move).
      if (truth != meets_yarn(add(gt.p, mul(gt.normal, -0.03 * r)))) continue;
      ++n;
      const bool occ = m.occluded_from(v.bh, v.sh, k::kv3(float(L[0]), float(L[1]), float(L[2])), nullptr);
      occluded += truth;
      agree += occ == truth;
    }
    std::printf("[self-shadow] %-12s transmitted paths %d: agreement %.2f%%, occluded (truth) %.1f%%\n",
                np.name.c_str(), n, 100.0 * agree / std::max(n, 1), 100.0 * occluded / std::max(n, 1));
    EXPECT_GE(n, 400) << np.name;
    EXPECT_GT(occluded, n / 10) << np.name << ": too few occluded paths for a meaningful test";
    EXPECT_LT(occluded, n * 9 / 10) << np.name << ": too few open paths for a meaningful test";
    EXPECT_GE(agree, n * 98 / 100) << np.name;
  }
}

}  // namespace
