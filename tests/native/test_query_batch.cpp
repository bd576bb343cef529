// KnitSurface::query_batch: the AVX-512 and AVX2 paths against the scalar
// kernel (query), point for point, and the API around it. The batch's agreement
// with the double-precision tube ray casts is in test_groundtruth.cpp
// (VerticalQueryMatchesExplicitTubes runs both paths).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "knit/surface.h"
#include "../support/test_patterns.h"

namespace knit {
namespace {

struct Named {
  const char* name;
  Pattern pattern;
};

std::vector<Named> loop_patterns() {
  return {{"stockinette", test::stockinette()}, {"reverse", test::reverse_stockinette()},
          {"garter", test::garter()},           {"rib1x1", test::rib_1x1()},
          {"seed", test::seed()},               {"pyramid16", test::pyramid16()}};
}

// A short, deep stitch with a thin yarn (steep in depth), and a rounder,
// shorter one with a thinner yarn than the default.
// (a, h, d, r)
StitchParams steep_stitch() { return StitchParams{1.5f, 3.7f, -2.0f, 0.22f}; }
StitchParams round_stitch() { return StitchParams{1.2f, 3.6f, 1.0f, 0.35f}; }

double angle_deg(Vec3 a, Vec3 b) {
  const double c = double(a.x) * b.x + double(a.y) * b.y + double(a.z) * b.z;
  return std::acos(std::max(-1.0, std::min(1.0, c))) * 180.0 / 3.14159265358979;
}

// The vector paths this CPU runs: its widest, and AVX2 beside AVX-512.
std::vector<KnitSurface::BatchPath> vector_paths() {
  std::vector<KnitSurface::BatchPath> paths = {KnitSurface::BatchPath::Simd};
  if (KnitSurface::batch_best_isa() == KnitSurface::BatchIsa::Avx512) paths.push_back(KnitSurface::BatchPath::Avx2);
  return paths;
}

// n points drawn uniformly from [-half, half] in x and y (x, then y, for
// each point in turn).
void random_points(int n, unsigned seed, float half, std::vector<float>& x, std::vector<float>& y) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-half, half);
  x.resize(size_t(n));
  y.resize(size_t(n));
  for (int i = 0; i < n; ++i) {
    x[size_t(i)] = U(rng);
    y[size_t(i)] = U(rng);
  }
}

// The vector path `path` (which must run here as `isa`) against query().
void check_agreement(KnitSurface::BatchPath path, KnitSurface::BatchIsa isa) {
  for (const Named& np : loop_patterns()) {
    // the default stitch, a thinner tube (gaps between the yarns), and the
    // steep stitch
    StitchParams thin;
    thin.r = 0.4f;
    for (const StitchParams& sp : {StitchParams{}, thin, steep_stitch()}) {
      const float r = sp.r;
      const KnitSurface s(np.pattern, sp);
      ASSERT_TRUE(s.batch_isa(path) == isa) << np.name;
      // points over a wide window, negative coordinates included, and an odd
      // count (a partial vector and a partial block at the end)
      const int n = 40001;
      std::vector<float> x, y;
      random_points(n, 11, 400.0f, x, y);
      std::vector<SurfaceHit> b(n);
      s.query_batch(x.data(), y.data(), size_t(n), b.data(), path);
      long hit_diff = 0, layer_diff = 0, cell_diff = 0, both = 0, far_z = 0;
      double zmax = 0, zsum = 0, nmax = 0, tmax = 0;
      std::vector<double> nerr;
      for (int i = 0; i < n; ++i) {
        const SurfaceHit a = s.query(x[size_t(i)], y[size_t(i)]);
        const SurfaceHit& c = b[size_t(i)];
        if (a.hit != c.hit) ++hit_diff;
        if (a.layers != c.layers) ++layer_diff;
        if (!a.hit || !c.hit) continue;
        ++both;
        if (a.row != c.row || a.col != c.col || a.stitch != c.stitch || a.color != c.color) ++cell_diff;
        const double dz = std::abs(double(a.position.z) - c.position.z) / r;
        zsum += dz;
        zmax = std::max(zmax, dz);
        if (dz > 0.01) ++far_z;
        EXPECT_EQ(a.position.x, c.position.x);
        EXPECT_EQ(a.position.y, c.position.y);
        nerr.push_back(angle_deg(a.normal, c.normal));
        nmax = std::max(nmax, nerr.back());
        tmax = std::max(tmax, angle_deg(a.tangent, c.tangent));
      }
      std::sort(nerr.begin(), nerr.end());
      const double n9999 = nerr[size_t(0.9999 * double(nerr.size() - 1))];
      std::printf("%s batch vs scalar %-12s a %.1f h %.1f d %+.1f r %.2f: %d points, %ld hits | hit differ %ld, layers differ %ld, cell "
                  "differs %ld | z/r mean %.2e max %.2e (%ld over 0.01) | normal 99.99%% %.3f max %.3f deg, tangent "
                  "max %.3f deg\n",
                  KnitSurface::batch_isa_name(isa), np.name, double(sp.a), double(sp.h), double(sp.d), double(r), n, both, hit_diff, layer_diff, cell_diff, zsum / double(both), zmax, far_z,
                  n9999, nmax, tmax);
      // The same search in another order, with fused multiply-adds: hits,
      // layer counts and cells agree but for a point in ten thousand (a
      // point on a tube's rim or on a cell boundary); heights and
      // directions to float rounding, except where a Newton search meets
      // its step cap (KNIT_NEWTON_EXTREME) and the two stop it at different
      // places: a few points in 10^4, most on the steep stitch (0.18 r and
      // 19 degrees apart at worst there). Neither is the better one: at the
      // four such points of rib1x1's steep case the double-precision tube
      // ray casts put the scalar kernel 0.065 r off on average and this
      // path 0.036 r. A different crossing would be r or more apart.
      const long far_n = long(nerr.end() - std::upper_bound(nerr.begin(), nerr.end(), 1.0));
      EXPECT_LE(hit_diff, n / 10000) << np.name;
      EXPECT_LE(layer_diff, n / 10000) << np.name;
      EXPECT_LE(cell_diff, both / 10000 + 1) << np.name;
      EXPECT_LE(zsum / double(both), 1e-4) << np.name;
      EXPECT_LE(far_z, both / 2500 + 2) << np.name;
      EXPECT_LE(far_n, both / 2500 + 2) << np.name;
      EXPECT_LE(zmax, 0.25) << np.name;
      EXPECT_LE(n9999, 2.5) << np.name;
    }
  }
}

TEST(QueryBatch, Avx512PathAgreesWithTheScalarKernel) {
  if (KnitSurface::batch_best_isa() != KnitSurface::BatchIsa::Avx512)
    GTEST_SKIP() << "this CPU has no AVX-512: the 16-lane path cannot run here (the AVX2 test covers the 8-lane one)";
  check_agreement(KnitSurface::BatchPath::Simd, KnitSurface::BatchIsa::Avx512);
}

TEST(QueryBatch, Avx2PathAgreesWithTheScalarKernel) {
  if (!KnitSurface::batch_simd_available())
    GTEST_SKIP() << "this CPU has neither AVX-512 nor AVX2 with FMA: query_batch runs the scalar kernel here, "
                    "nothing to compare";
  check_agreement(KnitSurface::BatchPath::Avx2, KnitSurface::BatchIsa::Avx2);
}

// The vector paths keep the constants of the last stitch (a and h) between
// calls: calls alternating between two stitches must each get their own.
TEST(QueryBatch, AlternatingStitchesKeepTheirOwnConstants) {
  if (!KnitSurface::batch_simd_available())
    GTEST_SKIP() << "this CPU has neither AVX-512 nor AVX2 with FMA: no vector path to check";
  const StitchParams other = round_stitch();
  const KnitSurface sa(test::seed(), StitchParams{}), sb(test::seed(), other);
  std::vector<float> x, y;
  for (int i = 0; i < 2000; ++i) {
    x.push_back(0.731f * float(i % 97) - 30.0f);
    y.push_back(0.413f * float(i / 97) * 4.0f - 10.0f);
  }
  const size_t n = x.size();
  const std::vector<KnitSurface::BatchPath> paths = vector_paths();
  for (const KnitSurface::BatchPath path : paths) {
    SCOPED_TRACE(KnitSurface::batch_isa_name(sa.batch_isa(path)));
    std::vector<SurfaceHit> a1(n), b1(n), a2(n);
    sa.query_batch(x.data(), y.data(), n, a1.data(), path);
    sb.query_batch(x.data(), y.data(), n, b1.data(), path);
    sa.query_batch(x.data(), y.data(), n, a2.data(), path);
    long b_agree = 0, differ_ab = 0;
    for (size_t i = 0; i < n; ++i) {
      ASSERT_EQ(a1[i].hit, a2[i].hit) << i;
      ASSERT_EQ(a1[i].position.z, a2[i].position.z) << i;
      ASSERT_EQ(a1[i].layers, a2[i].layers) << i;
      const SurfaceHit q = sb.query(x[i], y[i]);
      if (q.hit == b1[i].hit && q.layers == b1[i].layers &&
          (!q.hit || std::abs(q.position.z - b1[i].position.z) < 1e-3f))
        ++b_agree;
      if (a1[i].hit != b1[i].hit || (a1[i].hit && a1[i].position.z != b1[i].position.z)) ++differ_ab;
    }
    EXPECT_GE(b_agree, long(n) - 2);    // the second stitch's results are its own
    EXPECT_GT(differ_ab, long(n) / 2);  // and the two stitches do differ
  }
}

// A point's result must not depend on how many points are asked with it:
// the vector paths run calls of 128 points or more (AVX-512) or 32 or more
// (AVX2) on pairs of registers and smaller ones on one (query_batch.cpp),
// and Python's query cuts its arrays into blocks, so the same point meets
// both. Every field, bit for bit, one call of all the points against calls
// of sizes on both sides of both thresholds, for each vector path this CPU
// has.
TEST(QueryBatch, ResultsDoNotDependOnTheCallSize) {
  if (!KnitSurface::batch_simd_available())
    GTEST_SKIP() << "this CPU has neither AVX-512 nor AVX2 with FMA: no vector path to check";
  const std::vector<KnitSurface::BatchPath> paths = vector_paths();
  const int sizes[] = {1, 3, 16, 17, 31, 32, 33, 64, 127, 128, 129, 300, 1024, 1500};
  const int n = 12000;
  std::vector<float> x, y;
  random_points(n, 23, 200.0f, x, y);
  auto same_bits = [](float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  auto same_vec = [&](const Vec3& a, const Vec3& b) {
    return same_bits(a.x, b.x) && same_bits(a.y, b.y) && same_bits(a.z, b.z);
  };
  for (const StitchParams& sp : {StitchParams{}, steep_stitch()}) {
    const KnitSurface s(test::pyramid16(), sp);
    for (const KnitSurface::BatchPath path : paths) {
      SCOPED_TRACE(KnitSurface::batch_isa_name(s.batch_isa(path)));
      std::vector<SurfaceHit> whole(n), pieces(n);
      s.query_batch(x.data(), y.data(), size_t(n), whole.data(), path);
      int at = 0, calls = 0;
      while (at < n) {
        const int m = std::min(sizes[size_t(calls++) % std::size(sizes)], n - at);
        s.query_batch(x.data() + at, y.data() + at, size_t(m), pieces.data() + at, path);
        at += m;
      }
      long hits = 0, differ = 0;
      for (int i = 0; i < n; ++i) {
        const SurfaceHit& a = whole[size_t(i)];
        const SurfaceHit& b = pieces[size_t(i)];
        hits += a.hit;
        if (a.hit != b.hit || a.layers != b.layers || a.row != b.row || a.col != b.col || a.stitch != b.stitch ||
            a.color != b.color || !same_vec(a.position, b.position) || !same_vec(a.normal, b.normal) ||
            !same_vec(a.tangent, b.tangent)) {
          if (++differ <= 3)  // (a zero's sign counts: tangent z was once 0 in one call and -0 in another)
            std::printf("  point %d (%.6f, %.6f) differs: z %.9g / %.9g, tangent z %g / %g, normal z %.9g / %.9g\n", i,
                        double(x[size_t(i)]), double(y[size_t(i)]), double(a.position.z), double(b.position.z),
                        double(a.tangent.z), double(b.tangent.z), double(a.normal.z), double(b.normal.z));
        }
      }
      std::printf("%s, a %.1f h %.1f d %+.1f r %.2f: %d points in one call and in %d calls of 1-1500: %ld hits, "
                  "%ld differ\n",
                  KnitSurface::batch_isa_name(s.batch_isa(path)), double(sp.a), double(sp.h), double(sp.d),
                  double(sp.r), n, calls, hits, differ);
      EXPECT_GT(hits, long(n) / 4);  // (something to compare)
      EXPECT_EQ(differ, 0);
    }
  }
}

TEST(QueryBatch, SlipStitchesAndTheScalarChoiceTakeTheKernel) {
  const KnitSurface floats(test::slip_floats(), StitchParams{});
  EXPECT_TRUE(floats.batch_isa(KnitSurface::BatchPath::Auto) == KnitSurface::BatchIsa::Scalar);
  EXPECT_THROW(floats.batch_isa(KnitSurface::BatchPath::Simd), std::invalid_argument);
  EXPECT_THROW(floats.batch_isa(KnitSurface::BatchPath::Avx2), std::invalid_argument);
  const KnitSurface plain(test::seed(), StitchParams{});
  EXPECT_TRUE(plain.batch_isa(KnitSurface::BatchPath::Scalar) == KnitSurface::BatchIsa::Scalar);
  EXPECT_EQ(plain.batch_isa(KnitSurface::BatchPath::Auto) != KnitSurface::BatchIsa::Scalar,
            KnitSurface::batch_simd_available());
  EXPECT_TRUE(plain.batch_isa(KnitSurface::BatchPath::Auto) == KnitSurface::batch_best_isa());
  EXPECT_STREQ(KnitSurface::batch_isa_name(KnitSurface::BatchIsa::Avx2), "avx2");
  if (KnitSurface::batch_simd_available()) {
    EXPECT_TRUE(plain.batch_isa(KnitSurface::BatchPath::Avx2) == KnitSurface::BatchIsa::Avx2);
  } else {
    EXPECT_THROW(plain.batch_isa(KnitSurface::BatchPath::Avx2), std::invalid_argument);
  }
  // The fallback is the kernel itself: bit for bit.
  std::vector<float> x, y;
  for (int i = 0; i < 300; ++i) {
    x.push_back(0.37f * float(i) - 20.0f);
    y.push_back(0.23f * float(i) + 3.0f);
  }
  std::vector<SurfaceHit> b(x.size());
  floats.query_batch(x.data(), y.data(), x.size(), b.data());
  for (size_t i = 0; i < x.size(); ++i) {
    const SurfaceHit a = floats.query(x[i], y[i]);
    ASSERT_EQ(a.hit, b[i].hit);
    ASSERT_EQ(a.layers, b[i].layers);
    ASSERT_EQ(a.position.z, b[i].position.z);
  }
}

// Each entry's cell (stitch code and colour) from its row and column, on
// a pattern whose every cell has its own colour, so that a cell one column
// or row off shows: against the pattern itself (the row counted from the
// bottom, both indices periodic) for every hit of both paths, and the cell
// against the scalar kernel's. Points on both sides of the origin, where
// columns and rows are negative and wrap.
TEST(QueryBatch, EntryCellsAreThePatternsCells) {
  if (!KnitSurface::batch_simd_available())
    GTEST_SKIP() << "this CPU has neither AVX-512 nor AVX2 with FMA: no vector path to check";
  const int rows = 5, cols = 7;
  std::vector<std::vector<int>> codes(rows, std::vector<int>(cols)), colors = codes;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      codes[size_t(r)][size_t(c)] = (r * 3 + c * 5) % 4 < 2 ? 0 : 1;
      colors[size_t(r)][size_t(c)] = r * cols + c;
    }
  const Pattern pat = Pattern::from_rows(codes, colors);
  const auto wrap = [](int a, int m) { return ((a % m) + m) % m; };
  const std::vector<KnitSurface::BatchPath> paths = vector_paths();
  for (const StitchParams& sp : {StitchParams{}, steep_stitch()}) {
    const KnitSurface s(pat, sp);
    const int n = 20000;
    std::vector<float> x, y;
    random_points(n, 17, 200.0f, x, y);
    for (const KnitSurface::BatchPath path : paths) {
      SCOPED_TRACE(KnitSurface::batch_isa_name(s.batch_isa(path)));
      std::vector<SurfaceHit> b(static_cast<size_t>(n));
      s.query_batch(x.data(), y.data(), size_t(n), b.data(), path);
      long hits = 0, negative = 0, wrong = 0, other_cell = 0;
      for (int i = 0; i < n; ++i) {
        const SurfaceHit& h = b[size_t(i)];
        if (!h.hit) continue;
        ++hits;
        if (h.row < 0 || h.col < 0) ++negative;
        const int pr = rows - 1 - wrap(h.row, rows), pc = wrap(h.col, cols);
        if (h.color != pat.color(pr, pc) || h.stitch != int(pat.stitch(pr, pc))) ++wrong;
        const SurfaceHit a = s.query(x[size_t(i)], y[size_t(i)]);
        if (a.hit && (a.row != h.row || a.col != h.col || a.color != h.color)) ++other_cell;
      }
      EXPECT_EQ(wrong, 0);
      EXPECT_LE(other_cell, hits / 10000 + 1);  // (an entry on a cell boundary)
      EXPECT_GT(negative, hits / 3);
      EXPECT_GT(hits, n / 4);  // (81% with Crane's stitch, 34% with the thin steep one)
    }
  }
}

// Stage 1 takes each point's candidates from the bin of the stitch cell it
// falls in, unless a lane of its vector lies beyond 1e4 units: then the
// whole vector tests every pair of the box, as before the bins. The bins
// must keep every pair the box test keeps that could come near, so the
// same points must give bit-identical results either way: here once among
// themselves, and once with a far point in every vector of 8 and of 16.
TEST(QueryBatch, CandidateBinsGiveWhatTheWholeBoxGives) {
  if (!KnitSurface::batch_simd_available())
    GTEST_SKIP() << "this CPU has neither AVX-512 nor AVX2 with FMA: no vector path to check";
  const std::vector<KnitSurface::BatchPath> paths = vector_paths();
  for (const StitchParams& sp : {StitchParams{}, steep_stitch(), round_stitch()}) {
    const KnitSurface s(test::pyramid16(), sp);
    const int n = 6000;
    std::vector<float> x, y, xf, yf;
    random_points(n, 5, 300.0f, x, y);
    // the same points, with a point at x = 2e4 in every eighth place
    std::vector<int> at;
    for (int i = 0; i < n; ++i) {
      if (xf.size() % 8 == 7) {
        xf.push_back(2.0e4f);
        yf.push_back(1.0f);
      }
      at.push_back(int(xf.size()));
      xf.push_back(x[size_t(i)]);
      yf.push_back(y[size_t(i)]);
    }
    for (const KnitSurface::BatchPath path : paths) {
      SCOPED_TRACE(KnitSurface::batch_isa_name(s.batch_isa(path)));
      std::vector<SurfaceHit> a(x.size()), b(xf.size());
      s.query_batch(x.data(), y.data(), x.size(), a.data(), path);
      s.query_batch(xf.data(), yf.data(), xf.size(), b.data(), path);
      long hits = 0, differ = 0;
      for (int i = 0; i < n; ++i) {
        const SurfaceHit& p = a[size_t(i)];
        const SurfaceHit& q = b[size_t(at[size_t(i)])];
        hits += p.hit ? 1 : 0;
        if (p.hit != q.hit || p.layers != q.layers || p.position.z != q.position.z || p.normal.x != q.normal.x ||
            p.normal.y != q.normal.y || p.normal.z != q.normal.z || p.row != q.row || p.col != q.col)
          ++differ;
      }
      EXPECT_EQ(differ, 0) << "a " << sp.a << " r " << sp.r;
      EXPECT_GT(hits, n / 10);
    }
  }
}

TEST(QueryBatch, OddInputsGiveWhatQueryGives) {
  const KnitSurface s(test::rib_1x1(), StitchParams{});
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  // NaN, infinities and points beyond the kernel's coordinate range
  // (KNIT_MAX_COORD, 1e7): misses, as query() gives them
  std::vector<float> x = {nan, 1.0f, inf, -inf, 2.0e7f, 3.0f, 0.5f};
  std::vector<float> y = {1.0f, nan, 1.0f, 1.0f, 1.0f, -2.0e7f, 0.0f};
  // then a block of points just inside that range, where the row and piece
  // windows are widest in float. Pattern space is meaningless there (1
  // unit between floats, the hosts stop at kMaxPatternCoord = 32768) and
  // the two paths round differently; what is asserted is that the batch
  // stays within its buffers and returns finite, unit-length results.
  for (int i = 0; i < 300; ++i) {
    x.push_back(9.99e6f - 0.37f * float(i));
    y.push_back(-9.99e6f + 0.53f * float(i));
  }
  // every vector path this CPU has (Auto takes the widest)
  std::vector<KnitSurface::BatchPath> paths = {KnitSurface::BatchPath::Auto};
  if (KnitSurface::batch_best_isa() == KnitSurface::BatchIsa::Avx512) paths.push_back(KnitSurface::BatchPath::Avx2);
  for (const KnitSurface::BatchPath path : paths) {
    SCOPED_TRACE(KnitSurface::batch_isa_name(s.batch_isa(path)));
    std::vector<SurfaceHit> b(x.size());
    s.query_batch(x.data(), y.data(), x.size(), b.data(), path);
    for (size_t i = 0; i < 7; ++i) {
      const SurfaceHit a = s.query(x[i], y[i]);
      EXPECT_EQ(a.hit, b[i].hit) << i;
      EXPECT_EQ(a.layers, b[i].layers) << i;
      if (a.hit && b[i].hit) EXPECT_NEAR(a.position.z, b[i].position.z, 0.02f * s.params().r) << i;
  }
  for (size_t i = 0; i < 6; ++i) EXPECT_FALSE(b[i].hit) << i;
  EXPECT_TRUE(b[6].hit);
  int far_hits = 0;
  for (size_t i = 7; i < x.size(); ++i) {
    if (!b[i].hit) continue;
    ++far_hits;
    const SurfaceHit& h = b[i];
    EXPECT_TRUE(std::isfinite(h.position.z) && std::abs(h.position.z) <= s.shell_top()) << i;
    EXPECT_NEAR(std::sqrt(h.normal.x * h.normal.x + h.normal.y * h.normal.y + h.normal.z * h.normal.z), 1.0f, 1e-4f);
    EXPECT_NEAR(std::sqrt(h.tangent.x * h.tangent.x + h.tangent.y * h.tangent.y + h.tangent.z * h.tangent.z), 1.0f,
                1e-4f);
    EXPECT_GE(h.layers, 1);
  }
  EXPECT_GT(far_hits, 30);  // (68 of the 300: the points fall on a 1-unit grid there)
  }
  std::vector<SurfaceHit> b(x.size());
  s.query_batch(x.data(), y.data(), 0, nullptr);  // nothing to do
  EXPECT_THROW(s.query_batch(nullptr, y.data(), 1, b.data()), std::invalid_argument);
}

}  // namespace
}  // namespace knit
