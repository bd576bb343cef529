// The kernel's float stitch geometry against the double-precision reference
// curve (native/src/yarn_curve.cpp): exact curve, piece bounds, quadratic
// interpolants and their error bound.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "knit/kernel.h"
#include "knit/surface.h"
#include "knit/yarns.h"
#include "test_patterns.h"

namespace {

using namespace knit;

constexpr double kPi = 3.14159265358979323846;

KnitSurface make(const Pattern& p, StitchParams sp = {}) { return KnitSurface(p, sp); }

TEST(Stitch, KernelCurveMatchesDoubleReference) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> T(-40.0, 40.0);
  for (const Pattern& pat : {test::seed(), test::slip_floats(), test::pyramid16()}) {
    KnitSurface s = make(pat);
    double worst_p = 0, worst_d1 = 0, worst_d2 = 0;
    for (int i = 0; i < 20000; ++i) {
      const double t = T(rng);
      const int row = int(rng() % 40) - 20;
      const CurvePoint ref = yarn_curve_exact(pat, s.params(), row, t);
      const k::KCurve got = k::knit_row_curve(s.geom(), s.codes(), row, float(t));
      const double gp[3] = {got.p.x, got.p.y, got.p.z}, g1[3] = {got.d1.x, got.d1.y, got.d1.z},
                   g2[3] = {got.d2.x, got.d2.y, got.d2.z};
      for (int k = 0; k < 3; ++k) {
        worst_p = std::max(worst_p, std::abs(gp[k] - ref.p[size_t(k)]));
        worst_d1 = std::max(worst_d1, std::abs(g1[k] - ref.dp[size_t(k)]));
        worst_d2 = std::max(worst_d2, std::abs(g2[k] - ref.ddp[size_t(k)]));
      }
    }
    // Float evaluation of t up to |t| ~ 40: a few ulps of 40 (~4e-6) times |Y'|.
    EXPECT_LT(worst_p, 1e-4);
    EXPECT_LT(worst_d1, 1e-3);
    EXPECT_LT(worst_d2, 5e-3);
  }
}

TEST(Stitch, CurveIsC1AcrossEveryCellBoundary) {
  // Knit/purl/front/back neighbours in every combination: the blended curve
  // must be continuous with a continuous tangent at every boundary.
  Pattern pat = Pattern::from_rows({{0, 1, 2, 3, 0, 2, 1, 3, 3, 2, 2, 0, 0, 3, 1, 1}});
  StitchParams sp;
  for (int c = -1; c <= 17; ++c) {
    const double tb = 2 * kPi * c;
    for (double eps : {1e-7}) {
      CurvePoint a = yarn_curve_exact(pat, sp, 0, tb - eps), b = yarn_curve_exact(pat, sp, 0, tb + eps);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(a.p[size_t(k)], b.p[size_t(k)], 1e-5) << "boundary " << c;
        EXPECT_NEAR(a.dp[size_t(k)], b.dp[size_t(k)], 1e-4) << "boundary " << c;
      }
    }
    // Also across the blend window's ends (pi/4 from the boundary).
    for (double e : {kPi / 4, -kPi / 4}) {
      CurvePoint a = yarn_curve_exact(pat, sp, 0, tb + e - 1e-7), b = yarn_curve_exact(pat, sp, 0, tb + e + 1e-7);
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR(a.p[size_t(k)], b.p[size_t(k)], 1e-5);
        EXPECT_NEAR(a.dp[size_t(k)], b.dp[size_t(k)], 1e-4);
        EXPECT_NEAR(a.ddp[size_t(k)], b.ddp[size_t(k)], 1e-3);
      }
    }
  }
}

TEST(Stitch, PieceBoundsContainTheCurve) {
  Pattern pat = Pattern::from_rows({{0, 1, 2, 3, 0, 2, 1, 3}, {1, 1, 0, 0, 3, 3, 2, 2}});
  for (StitchParams sp : {StitchParams{}, StitchParams{1.25f, 3.0f, -0.6f, 0.4f}, StitchParams{1.75f, 5.0f, 1.4f, 0.5f}}) {
    KnitSurface s = make(pat, sp);
    for (int row = -2; row < 4; ++row)
      for (int gp = -16; gp < 80; ++gp) {
        k::KBox b = k::knit_piece_bounds(s.geom(), s.codes(), k::knit_row(s.geom(), row), gp);
        // The line query's first cull: a box from the row and piece alone (no pattern).
        k::KBox bxy = k::knit_piece_bounds_xy(s.geom(), k::knit_row(s.geom(), row).yk, gp);
        for (int i = 0; i <= 64; ++i) {
          double t = (gp + i / 64.0) * kPi / 4;
          CurvePoint c = yarn_curve_exact(pat, sp, row, t);
          const float tol = 1e-4f;
          ASSERT_GE(c.p[0], bxy.lo.x - tol) << "row " << row << " piece " << gp;
          ASSERT_LE(c.p[0], bxy.hi.x + tol) << "row " << row << " piece " << gp;
          ASSERT_GE(c.p[1], bxy.lo.y - tol) << "row " << row << " piece " << gp;
          ASSERT_LE(c.p[1], bxy.hi.y + tol) << "row " << row << " piece " << gp;
          ASSERT_GE(c.p[2], bxy.lo.z - tol) << "row " << row << " piece " << gp;
          ASSERT_LE(c.p[2], bxy.hi.z + tol) << "row " << row << " piece " << gp;
          ASSERT_GE(c.p[0], b.lo.x - tol) << "row " << row << " piece " << gp;
          ASSERT_LE(c.p[0], b.hi.x + tol) << "row " << row << " piece " << gp;
          ASSERT_GE(c.p[1], b.lo.y - tol);
          ASSERT_LE(c.p[1], b.hi.y + tol);
          ASSERT_GE(c.p[2], b.lo.z - tol);
          ASSERT_LE(c.p[2], b.hi.z + tol);
        }
      }
  }
}

// The quadratic interpolants (our derivation replacing the paper's Eq. 5-8)
// against the exact curve: report and bound the maximum error per component.
TEST(Stitch, QuadraticInterpolantErrorWithinBound) {
  Pattern pat = Pattern::from_rows({{0, 1, 2, 3, 0, 2, 1, 3}, {1, 1, 0, 0, 3, 3, 2, 2}});
  for (StitchParams sp : {StitchParams{}, StitchParams{1.25f, 3.0f, -0.6f, 0.4f}, StitchParams{1.75f, 5.0f, 1.4f, 0.5f}}) {
    KnitSurface s = make(pat, sp);
    double worst[3] = {0, 0, 0}, worst_plain = 0, worst_blend = 0;
    for (int row = 0; row < 2; ++row)
      for (int gp = 0; gp < 64; ++gp) {
        k::KQuad q = k::knit_piece_quad(s.geom(), s.codes(), k::knit_row(s.geom(), row), gp);
        const bool blend = (gp % 8 == 0 || gp % 8 == 7);
        // It interpolates: through the exact curve at its three nodes (a
        // blended piece's nodes are built from both profiles' nodes).
        for (int i = 0; i <= 2; ++i) {
          CurvePoint c = yarn_curve_exact(pat, sp, row, (gp + i / 2.0) * kPi / 4);
          k::kvec3 a = k::knit_quad_eval(q, i / 2.0f);
          ASSERT_NEAR(a.x, c.p[0], 2e-5 * (1 + std::abs(c.p[0]))) << "row " << row << " piece " << gp << " node " << i;
          ASSERT_NEAR(a.y, c.p[1], 2e-5 * (1 + std::abs(c.p[1]))) << "row " << row << " piece " << gp << " node " << i;
          ASSERT_NEAR(a.z, c.p[2], 2e-5 * (1 + std::abs(c.p[2]))) << "row " << row << " piece " << gp << " node " << i;
        }
        for (int i = 0; i <= 200; ++i) {
          const double u = i / 200.0;
          CurvePoint c = yarn_curve_exact(pat, sp, row, (gp + u) * kPi / 4);
          k::kvec3 a = k::knit_quad_eval(q, float(u));
          const double e[3] = {std::abs(a.x - c.p[0]), std::abs(a.y - c.p[1]), std::abs(a.z - c.p[2])};
          const double en = std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]);
          for (int k = 0; k < 3; ++k) worst[k] = std::max(worst[k], e[k]);
          (blend ? worst_blend : worst_plain) = std::max(blend ? worst_blend : worst_plain, en);
        }
      }
    const double bound = s.geom().quad_margin;
    std::printf("[ quad ] %s: max error x %.4f y %.4f z %.4f | plain pieces %.4f, blend pieces %.4f | bound %.4f\n",
                sp.to_string().c_str(), worst[0], worst[1], worst[2], worst_plain, worst_blend, bound);
    EXPECT_LE(worst_plain, bound / 2 + 1e-4) << "plain-piece error exceeds the analytic bound";
    EXPECT_LE(worst_blend, bound) << "blend-piece error exceeds the margin used by the query";
  }
}

// Vertical lines cull pieces by the interpolant's distance in x and y, with
// quad_margin_xy in place of quad_margin: it must bound the x and y error
// of every piece of knit and purl rows against the double-precision curve
// (yarn_curve_exact), blended pieces included (x and y do not blend).
TEST(Stitch, QuadraticInterpolantXYErrorWithinItsBound) {
  Pattern pat = Pattern::from_rows({{0, 1, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1}});
  for (StitchParams sp : {StitchParams{}, StitchParams{1.25f, 3.0f, -0.6f, 0.4f}, StitchParams{1.75f, 5.0f, 1.4f, 0.5f},
                          StitchParams{0.4f, 2.0f, 0.5f, 0.2f}}) {
    KnitSurface s = make(pat, sp);
    ASSERT_EQ(s.geom().has_floats, 0);
    double worst = 0;
    for (int row = 0; row < 2; ++row)
      for (int gp = 0; gp < 64; ++gp) {
        const k::KQuad q = k::knit_loop_piece_quad_xy(s.geom(), k::knit_row(s.geom(), row).yk, gp);
        for (int i = 0; i <= 400; ++i) {
          const double u = i / 400.0;
          const CurvePoint c = yarn_curve_exact(pat, sp, row, (gp + u) * kPi / 4);
          const k::kvec3 a = k::knit_quad_eval(q, float(u));
          worst = std::max(worst, std::hypot(a.x - c.p[0], a.y - c.p[1]));
        }
      }
    std::printf("[ quad ] %s: max x, y error %.4f | quad_margin_xy %.4f (quad_margin %.4f)\n", sp.to_string().c_str(),
                worst, double(s.geom().quad_margin_xy), double(s.geom().quad_margin));
    EXPECT_LE(worst, s.geom().quad_margin_xy);
    EXPECT_GT(worst, 0.5 * s.geom().quad_margin_xy);  // (and not a loose one)
  }
}

// Vertical queries through knit and purl rows reject pieces on the x, y
// interpolant, built without the pattern: it must be the full interpolant's
// x and y, blended pieces included, for every mix of knit and purl.
TEST(Stitch, LoopInterpolantXYIsTheFullInterpolantsXY) {
  Pattern pat = Pattern::from_rows({{0, 1, 1, 0, 0, 0, 1, 0}, {1, 0, 0, 1, 1, 0, 0, 1}, {0, 0, 1, 1, 0, 1, 0, 1}});
  for (StitchParams sp : {StitchParams{}, StitchParams{1.25f, 3.0f, -0.6f, 0.4f}}) {
    KnitSurface s = make(pat, sp);
    int blended = 0;
    for (int row = -3; row < 6; ++row)
      for (int gp = -16; gp < 80; ++gp) {
        const k::KRow rw = k::knit_row(s.geom(), row);
        const k::KQuad q = k::knit_piece_quad(s.geom(), s.codes(), rw, gp);
        const k::KQuad x = k::knit_loop_piece_quad_xy(s.geom(), rw.yk, gp);
        const k::KSpan span = k::knit_span(s.geom(), s.codes(), rw, k::knit_piece_column(gp));
        const int dn = k::knit_piece_neighbour(gp - 8 * span.c);
        if (dn != 0 && !k::knit_same_profile(span.mid, k::knit_span_cell(span, span.c + dn))) ++blended;
        ASSERT_EQ(x.t0, q.t0);
        for (const auto& [a, b] : {std::pair{x.q0, q.q0}, std::pair{x.q1, q.q1}, std::pair{x.q2, q.q2}}) {
          ASSERT_NEAR(a.x, b.x, 1e-5f * (1 + std::abs(b.x))) << "row " << row << " piece " << gp;
          ASSERT_NEAR(a.y, b.y, 1e-5f * (1 + std::abs(b.y))) << "row " << row << " piece " << gp;
          ASSERT_EQ(a.z, 0.0f);
        }
      }
    EXPECT_GT(blended, 100);  // the blends were exercised
  }
}

// The bounds that let vertical queries skip the cubic (knit_quad_beyond):
// a piece is never called farther than m when the interpolant's true
// distance in x and y (double precision, 2001 points) is within m, and the
// bounds reject most pieces beyond m. The one-sided bound rejects pieces the
// chord bound alone keeps.
TEST(Stitch, QuadBeyondIsSureOfItsPieces) {
  KnitSurface s = make(test::seed());
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int far = 0, rejected = 0, by_chord = 0;
  for (int i = 0; i < 20000; ++i) {
    const int row = static_cast<int>(U(rng) * 12) - 4, gp = static_cast<int>(U(rng) * 96) - 16;
    const k::KRow rw = k::knit_row(s.geom(), row);
    const k::KQuad q = k::knit_loop_piece_quad_xy(s.geom(), rw.yk, gp);
    const float px = q.t0 + (U(rng) * 2 - 0.5f) * 4, py = rw.yk + (U(rng) * 2 - 1) * 6;
    double best = 1e30;
    for (int j = 0; j <= 2000; ++j) {
      const double u = j / 2000.0;
      const double x = q.q0.x + (q.q1.x + double(q.q2.x) * u) * u, y = q.q0.y + (q.q1.y + double(q.q2.y) * u) * u;
      best = std::min(best, std::hypot(x - px, y - py));
    }
    for (const float m : {0.25f, 0.5f, 1.0f, 1.5f}) {
      const bool beyond = k::knit_quad_xy_beyond(q, px, py, m) != 0;
      const k::kvec3 A = k::kv3(q.q0.x - px, q.q0.y - py, 0), B = k::kv3(q.q1.x, q.q1.y, 0),
                     C = k::kv3(q.q2.x, q.q2.y, 0);
      const bool chord = k::knit_quad_beyond(A, B, C, m, 0) != 0;
      ASSERT_TRUE(!beyond || best > m - 1e-4)
          << "row " << row << " piece " << gp << " at (" << px << ", " << py << "), m " << m << ": distance " << best;
      ASSERT_TRUE(!chord || beyond) << "the one-sided test only adds rejections";
      if (m == 1.0f && best > 1.0) {
        ++far;
        rejected += beyond;
        by_chord += chord;
      }
    }
  }
  std::printf("[ bound ] pieces farther than 1.0: %d, found beyond 1.0: %d (%.1f%%), by the chord alone %d (%.1f%%)\n",
              far, rejected, 100.0 * rejected / far, by_chord, 100.0 * by_chord / far);
  EXPECT_GT(rejected, far * 3 / 4);
  // the one-sided bound catches over a quarter of the pieces the chord misses
  EXPECT_LT(far - rejected, (far - by_chord) * 3 / 4);
}

TEST(Stitch, ShellTopBoundsEveryTube) {
  for (const Pattern& pat : {test::stockinette(), test::slip_floats(), test::pyramid16()}) {
    KnitSurface s = make(pat);
    double top = 0;
    for (int row = 0; row < pat.rows(); ++row)
      for (int i = 0; i < 4096; ++i) {
        double t = 2 * kPi * pat.cols() * i / 4096.0;
        top = std::max(top, std::abs(yarn_curve_exact(pat, s.params(), row, t).p[2]) + s.params().r);
      }
    EXPECT_NEAR(s.shell_top(), top, 1e-3) << "shell_top must be the highest tube point";
  }
}

// A global piece's column is floor(gp / 8), computed in integers: for
// negative pieces too, and for every piece a query can reach (|x| up to
// KNIT_MAX_COORD plus a stitch).
TEST(Stitch, PieceColumnIsTheFloorOfAnEighth) {
  const int reach = int(std::ceil(double(KNIT_MAX_COORD) / (kPi / 4))) + 64;
  std::vector<int> gps;
  for (int gp = -300; gp <= 300; ++gp) gps.push_back(gp);
  for (int base : {reach, -reach, 1 << 20, -(1 << 20)})
    for (int d = -20; d <= 20; ++d) gps.push_back(base + d);
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> U(-reach, reach);
  for (int i = 0; i < 100000; ++i) gps.push_back(U(rng));
  for (int gp : gps) {
    const int want = int(std::floor(double(gp) / 8.0));
    ASSERT_EQ(k::knit_piece_column(gp), want) << "gp = " << gp;
    ASSERT_EQ(gp - 8 * k::knit_piece_column(gp), gp & 7) << "gp = " << gp;  // the piece's place in its cell
  }
}

// The kernel's line query reports a miss, in bounded work, for points beyond
// KNIT_MAX_COORD and for non-finite ones (the hosts reject both earlier); a
// point of the same stitch one period nearer the origin is still a hit.
TEST(Stitch, LineQueryMissesBeyondItsCoordinateRange) {
  KnitSurface s = make(test::stockinette());
  const float x = 3.0f, y = 0.4f * float(s.geom().row_spacing);
  ASSERT_TRUE(s.query(x, y).hit);
  const float period = 2.0f * float(kPi);
  EXPECT_TRUE(s.query(x + 1000 * period, y).hit);
  for (float far : {2e7f, -2e7f, 3e9f, -3e9f, 1e30f, INFINITY, -INFINITY, NAN}) {
    EXPECT_FALSE(s.query(far, y).hit) << "x = " << far;
    EXPECT_FALSE(s.query(x, far).hit) << "y = " << far;
    const k::KnitLineHit h = k::knit_line_query(s.geom(), s.codes(), s.colors(), k::kv3(x, y, 3.0f),
                                                k::kv3_normalize(k::kv3(1.0f, 0.5f, -1.0f)), 0.0f, far, 0);
    EXPECT_EQ(h.hit, 0) << "s_max = " << far;
    EXPECT_EQ(h.crossings, 0) << "s_max = " << far;
  }
}

// KNIT_QUERY_FIRST visits pieces nearest first and stops early: it must find
// a hit exactly where the exhaustive query does, also for lines long enough
// to overflow its candidate list (KNIT_QUERY_MAX_CAND), and its entries may
// differ only where two Newton solutions of one crossing differ.
TEST(Stitch, FirstEntryQueryFindsWhatTheFullQueryFinds) {
  KnitSurface s = make(test::seed());
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> U(0, 1);
  int hits = 0, close = 0, n = 0, any_later = 0;
  for (float len : {4.0f, 60.0f}) {
    for (int i = 0; i < 4000; ++i) {
      const float th = 1.5f * U(rng), ph = 6.2831853f * U(rng);
      const k::kvec3 o = k::kv3(40 * U(rng), 40 * U(rng), s.shell_top() * (2 * U(rng) - 1));
      const k::kvec3 D = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), -std::cos(th));
      const k::KnitLineHit a = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, 0, len, KNIT_QUERY_ENTRY);
      const k::KnitLineHit b = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, 0, len, KNIT_QUERY_FIRST);
      ASSERT_EQ(a.hit, b.hit) << "ray " << i << " length " << len;
      EXPECT_EQ(b.crossings, 0);
      // ANY (shadow rays) stops at the first entry it finds: the same hit or
      // miss, with an entry inside the range (not necessarily the nearest).
      const k::KnitLineHit c = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, 0, len, KNIT_QUERY_ANY);
      ASSERT_EQ(c.hit, b.hit) << "ray " << i << " length " << len;
      if (c.hit) {
        EXPECT_GE(c.s_in, 0.0f);
        EXPECT_LE(c.s_in, len);
        EXPECT_GE(c.s_in, b.s_in - 1e-5f);
        any_later += c.s_in > b.s_in + 1e-3f * s.params().r;
      }
      if (a.hit) {
        ++hits;
        close += std::abs(a.s_in - b.s_in) < 1e-3f * s.params().r;
      }
      ++n;
    }
  }
  EXPECT_GT(hits, n / 4);
  EXPECT_GT(close, hits * 95 / 100) << "entries agree on " << close << " of " << hits << " hits";
  std::printf("[ any ] %d hits, of which ANY stopped at a later entry than FIRST's in %d\n", hits, any_later);
}

// Long slanted segments: each row looks only at the pieces within the
// segment's x extent across that row's band (rows plus pieces, not rows
// times pieces). The first entry along a 2,000-unit segment must be the
// first entry found along its 25-unit pieces in turn, and a hit or a miss
// the same; with slip stitches too.
TEST(Stitch, LongSegmentsFindTheEntryTheirPiecesFind) {
  int far_all = 0;
  for (const Pattern& p : {test::seed(), test::slip_floats()}) {
    KnitSurface s = make(p);
    std::mt19937 rng(29);
    std::uniform_real_distribution<float> U(0, 1);
    int hits = 0, agree = 0, far = 0, n = 0;
    for (int i = 0; i < 200; ++i) {
      const float len = 2000.0f, ph = 6.2831853f * U(rng);
      const float top = s.shell_top();
      // from the shell's top down by 1-21% of its depth over the whole length
      const float dz = -2 * top * (0.01f + 0.2f * U(rng)) / len;
      const float hs = std::sqrt(1 - dz * dz);
      const k::kvec3 o = k::kv3(-1000 + 2000 * U(rng), -1000 + 2000 * U(rng), top * 0.999f);
      const k::kvec3 D = k::kv3(hs * std::cos(ph), hs * std::sin(ph), dz);
      const k::KnitLineHit whole = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, 0, len, KNIT_QUERY_FIRST);
      k::KnitLineHit piecewise = k::knit_line_hit_none();
      for (float a = 0; a < len && !piecewise.hit; a += 25.0f)
        piecewise = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, a, std::min(len, a + 25.0f),
                                       KNIT_QUERY_FIRST);
      ASSERT_EQ(whole.hit, piecewise.hit) << "segment " << i;
      const k::KnitLineHit any = k::knit_line_query(s.geom(), s.codes(), s.colors(), o, D, 0, len, KNIT_QUERY_ANY);
      ASSERT_EQ(any.hit, whole.hit) << "segment " << i;
      if (whole.hit) {
        ++hits;
        agree += std::abs(whole.s_in - piecewise.s_in) < 1e-3f * s.params().r;
        far += whole.s_in > 100;
      }
      ++n;
    }
    std::printf("[long] %d segments of 2000 units, %d hits (%d beyond 100 units), %d entries within 1e-3 r of the "
                "pieces'\n", n, hits, far, agree);
    EXPECT_GT(hits, n / 4);
    EXPECT_GE(agree, hits * 99 / 100);
    far_all += far;
  }
  // (seed's loops all reach the shell's top, so its entries come within a
  // few stitches; the floats' shell is deeper)
  EXPECT_GT(far_all, 20) << "entries far along the segments";
}

// The same chord bound in three dimensions, which lets every line query skip
// the cubic for a piece the line passes far from: a piece is dismissed only
// when the interpolant's true distance from the line (double precision,
// 2001 points) exceeds m, and a piece it keeps gets exactly the result
// knit_quad_closest gives.
TEST(Stitch, QuadClosestWithinDismissesOnlyFarPieces) {
  KnitSurface s = make(test::seed());
  const k::KnitGeom& g = s.geom();
  const float m = g.r + g.quad_margin;
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int far = 0, dismissed = 0, kept = 0;
  for (int i = 0; i < 20000; ++i) {
    const int row = static_cast<int>(U(rng) * 12) - 4, gp = static_cast<int>(U(rng) * 96) - 16;
    const k::KQuad q = k::knit_piece_quad(g, s.codes(), k::knit_row(g, row), gp);
    const k::kvec3 mid = k::knit_quad_eval(q, 0.5f);
    const k::kvec3 o = k::kv3(mid.x + (U(rng) * 2 - 1) * 3, mid.y + (U(rng) * 2 - 1) * 3, (U(rng) * 2 - 1) * 2);
    const float ct = 2 * U(rng) - 1, ph = 6.2831853f * U(rng), st = std::sqrt(1 - ct * ct);
    const k::kvec3 D = k::kv3(st * std::cos(ph), st * std::sin(ph), ct);
    double best = 1e30;
    for (int j = 0; j <= 2000; ++j) {
      const double u = j / 2000.0;
      const double p[3] = {q.q0.x + (q.q1.x + double(q.q2.x) * u) * u - o.x,
                           q.q0.y + (q.q1.y + double(q.q2.y) * u) * u - o.y,
                           q.q0.z + (q.q1.z + double(q.q2.z) * u) * u - o.z};
      const double along = p[0] * D.x + p[1] * D.y + p[2] * D.z;
      const double e[3] = {p[0] - along * D.x, p[1] - along * D.y, p[2] - along * D.z};
      best = std::min(best, std::sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2]));
    }
    const k::kvec3 w = k::knit_quad_closest_within(q, o, D, m);
    if (w.y == K_BIG) {
      ASSERT_GT(best, m) << "row " << row << " piece " << gp << " dismissed at distance " << best;
      ++dismissed;
    } else {
      const k::kvec3 c = k::knit_quad_closest(q, o, D);
      ASSERT_EQ(w.x, c.x);
      ASSERT_EQ(w.y, c.y);
      ++kept;
    }
    far += best > 1.5 * m;
  }
  std::printf("[ bound ] %d pieces dismissed, %d kept; farther than 1.5 m: %d\n", dismissed, kept, far);
  EXPECT_GT(dismissed, far / 2);  // it does dismiss most far pieces
  EXPECT_GT(kept, 1000);
}

// knit_crossing's floor: a crossing whose entry is sure to lie before
// s_floor is not searched for. Lines from points on and near the tubes
// (where a path's next segment starts) in all directions: with the floor,
// the crossing is the one found without it when that entry is at or past
// the floor, and a miss when it is before it.
TEST(Stitch, CrossingFloorSkipsOnlyEntriesBeforeIt) {
  KnitSurface s = make(test::seed());
  const k::KnitGeom& g = s.geom();
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> U(0, 1);
  int kept = 0, skipped = 0;
  for (int i = 0; i < 6000; ++i) {
    // A point near the surface of the tube under a random vertical line.
    const k::KnitLineHit top = k::knit_vertical_query(g, s.codes(), s.colors(), 40 * U(rng), 40 * U(rng));
    if (!top.hit) continue;
    const float ct = 2 * U(rng) - 1, ph = 6.2831853f * U(rng), st = std::sqrt(1 - ct * ct);
    const k::kvec3 D = k::kv3(st * std::cos(ph), st * std::sin(ph), ct);
    const k::kvec3 o = k::kv3_madd(top.p, top.n, (U(rng) - 0.5f) * 0.2f * g.r);
    const k::KSpan sp = k::knit_span(g, s.codes(), k::knit_row(g, top.row), k::knit_column_of(top.t));
    const k::KnitLineHit free = k::knit_crossing(g, s.codes(), s.colors(), sp, o, D, top.t, 0, -K_BIG);
    for (const float floor : {0.0f, -0.5f * g.r, 0.5f * g.r}) {
      const k::KnitLineHit h = k::knit_crossing(g, s.codes(), s.colors(), sp, o, D, top.t, 0, floor);
      if (free.hit && free.s_in >= floor) {
        ASSERT_TRUE(h.hit) << "ray " << i << " floor " << floor;
        EXPECT_EQ(h.s_in, free.s_in);
        EXPECT_EQ(h.t, free.t);
        ++kept;
      } else {
        EXPECT_FALSE(h.hit && h.s_in >= floor) << "ray " << i << " floor " << floor;
        skipped += !h.hit && free.hit;
      }
    }
  }
  std::printf("[ floor ] entries at or past the floor kept: %d; entries before it skipped: %d\n", kept, skipped);
  EXPECT_GT(kept, 1000);
  EXPECT_GT(skipped, 1000);
}

TEST(Stitch, ParamsValidationNamesTheFieldAndValue) {
  auto msg = [](StitchParams p) {
    try {
      p.validate();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(msg({-1.f, 4.f, 1.f, 0.5f}).find("a (loop roundness) must be > 0, got -1"), std::string::npos);
  EXPECT_NE(msg({1.5f, 0.f, 1.f, 0.5f}).find("h (loop height) must be > 0, got 0"), std::string::npos);
  EXPECT_NE(msg({1.5f, 4.f, 0.f, 0.5f}).find("d (loop depth) must be non-zero"), std::string::npos);
  EXPECT_NE(msg({1.5f, 4.f, 1.f, -0.1f}).find("r (yarn radius) must be > 0, got -0.1"), std::string::npos);
  EXPECT_NE(msg({NAN, 4.f, 1.f, 0.5f}).find("a must be finite, got nan"), std::string::npos);
  EXPECT_NE(msg({1.5f, INFINITY, 1.f, 0.5f}).find("h must be finite"), std::string::npos);
  // The suggested r = 0.8 with Crane's a, h, d interpenetrates.
  std::string m = msg({1.5f, 4.f, 1.f, 0.8f});
  EXPECT_NE(m.find("pass through each other"), std::string::npos) << m;
  EXPECT_NE(m.find("r must be <= 0.69"), std::string::npos) << m;
  EXPECT_EQ(msg({}), "");
  EXPECT_EQ(msg({1.5f, 4.f, -1.f, 0.65f}), "");
}

// The clearance is what it claims: tubes of radius clearance/2 just touch in
// one of the neighbourhoods and never overlap in any, checked on the
// explicit curves of 4x4 patches.
TEST(Stitch, ClearanceSeparatesTubes) {
  StitchParams sp;
  const double c = sp.clearance();
  EXPECT_GT(c, 1.3);
  EXPECT_LT(c, 1.6);
  double overall = 1e300;
  for (const Pattern& pat : {test::stockinette(), test::garter(), test::rib_1x1(), test::seed()}) {
    ExplicitYarns y = explicit_yarns(pat, sp, 4 / pat.cols(), 4 / pat.rows(), 96);
    // Every pair of points on different rows, or far apart along one row.
    for (size_t a = 0; a < y.curves.size(); ++a)
      for (size_t b = a; b < y.curves.size() && b <= a + 2; ++b) {
        const auto& A = y.curves[a].points;
        const auto& B = y.curves[b].points;
        for (size_t i = 0; i < A.size(); i += 2)
          for (size_t j = (a == b ? i + 20 : 0); j < B.size(); j += 2) {
            double dx = A[i][0] - B[j][0], dy = A[i][1] - B[j][1], dz = A[i][2] - B[j][2];
            double dd = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (a == b) {
              // Only count same-row pairs whose chord leaves the tube (really
              // different pieces): the curve between them strays > dd away.
              double stray = 0;
              for (size_t m = i; m <= j; m += 4) {
                double ex = A[m][0] - A[i][0], ey = A[m][1] - A[i][1], ez = A[m][2] - A[i][2];
                stray = std::max(stray, std::sqrt(ex * ex + ey * ey + ez * ez));
              }
              if (stray < 1.5 * dd + 0.5) continue;
            }
            overall = std::min(overall, dd);
          }
      }
  }
  EXPECT_GE(overall, c * 0.995) << "explicit curves come closer than the computed clearance";
  EXPECT_LE(overall, c * 1.03) << "clearance is far below what the explicit curves show";
}

}  // namespace
