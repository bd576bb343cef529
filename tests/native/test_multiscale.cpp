// The multi-scale aggregation (kernel multiscale.h): Sobol' points, the
// near-field limit, stability as the footprint grows, and p_delta and the
// LEAN slope covariance against explicit-tube ray casts.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "groundtruth.h"
#include "knit/kernel.h"
#include "test_patterns.h"

namespace {

using namespace knit;
using namespace knit::test;

k::KnitAggregate aggregate(const KnitSurface& s, float x, float y, float size, k::kvec3 wi, int n,
                           float shift_x = 0.37f, float shift_y = 0.71f) {
  return k::knit_aggregate(s.geom(), s.codes(), s.colors(), x, y, k::kv3(size, 0, 0), k::kv3(0, size, 0), wi,
                           n, shift_x, shift_y, 0, 0, 6.2832f, 32);
}

// A stratified footprint is averaged over the ncx x ncy whole cells nearest
// its centre: the box of cells must be centred on the footprint within half
// a cell in each direction, and overlap it at least as much as the box one
// cell over on either side.
TEST(MultiScale, WholeCellBoxIsCentredOnTheFootprint) {
  KnitSurface s(seed(), StitchParams{});
  const float cw = 6.2831853f, ch = s.geom().row_spacing;
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> U(0, 1);
  // Overlap in one axis of [lo, lo + n) with [a, b] (cell units).
  auto overlap = [](double lo, int n, double a, double b) {
    return std::max(0.0, std::min(lo + n, b) - std::max(lo, a));
  };
  double worst = 0;
  for (int rep = 0; rep < 2000; ++rep) {
    const float x = 200 * U(rng) - 100, y = 200 * U(rng) - 100;
    const float w = cw * (1 + 5 * U(rng)), h = ch * (1 + 5 * U(rng));
    const k::KFootprint f = k::knit_footprint(s.geom(), x, y, k::kv3(w, 0, 0), k::kv3(0, h, 0), 4, 0.5f, 0.5f);
    ASSERT_EQ(f.stratified, 1);
    const double cx = double(x) / cw, cy = double(y) / ch;  // centre, cell units
    const double ox = f.bx0 + 0.5 * f.ncx - cx, oy = f.by0 + 0.5 * f.ncy - cy;
    worst = std::max({worst, std::abs(ox), std::abs(oy)});
    EXPECT_LE(std::abs(ox), 0.5 + 1e-4) << "x " << x << " width " << w / cw << " cells";
    EXPECT_LE(std::abs(oy), 0.5 + 1e-4) << "y " << y << " height " << h / ch << " cells";
    const double ax = cx - 0.5 * w / cw, bx = cx + 0.5 * w / cw;
    for (int d : {-1, 1})
      EXPECT_GE(overlap(f.bx0, f.ncx, ax, bx) + 1e-4, overlap(f.bx0 + d, f.ncx, ax, bx)) << "x " << x;
  }
  std::printf("[footprint] worst offset of the whole-cell box from the footprint's centre: %.3f cells\n", worst);
}

// Grazing rays have huge ray differentials: the aggregate stays bounded
// (at most KNIT_MS_MAX_POINTS points, finite outputs) and still averages
// the fabric (p_delta near the gap fraction of a large footprint).
TEST(MultiScale, HugeFootprintsStayBounded) {
  KnitSurface s(stockinette(), StitchParams{});
  const k::kvec3 wi = k::kv3(0, 0, 1);
  const float ref = aggregate(s, 3.0f, 2.0f, 400.0f, wi, 64).p_delta;
  for (float size : {1e6f, 1e12f, 1e30f, INFINITY}) {
    const k::KnitAggregate a = aggregate(s, 3.0f, 2.0f, size, wi, 16);
    EXPECT_LE(a.points, KNIT_MS_MAX_POINTS) << size;
    EXPECT_TRUE(std::isfinite(a.p_delta) && a.p_delta >= 0 && a.p_delta <= 1) << size << ": " << a.p_delta;
    EXPECT_TRUE(std::isfinite(a.n.x) && std::isfinite(a.n.y) && std::isfinite(a.n.z)) << size;
    EXPECT_NEAR(a.p_delta, ref, 0.15) << size;
  }
}

TEST(MultiScale, SobolPointsFormA02Net) {
  // 16 points: every elementary interval of area 1/16 holds exactly one.
  for (int log_w = 0; log_w <= 4; ++log_w) {
    const int w = 1 << log_w, h = 16 / w;
    std::vector<int> count(16, 0);
    for (int i = 0; i < 16; ++i) {
      const k::kvec3 p = k::knit_sobol2(i);
      ASSERT_GE(p.x, 0.f);
      ASSERT_LT(p.x, 1.f);
      ASSERT_GE(p.y, 0.f);
      ASSERT_LT(p.y, 1.f);
      count[size_t(int(p.x * w) * h + int(p.y * h))]++;
    }
    for (int c : count) EXPECT_EQ(c, 1) << w << "x" << h;
  }
}

TEST(MultiScale, PointFootprintConvergesToNearField) {
  KnitSurface s(seed(), StitchParams{});
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0, 1);
  int n = 0, pd_same = 0, normal_same = 0, sigma_zero = 0, both_hit = 0;
  for (int i = 0; i < 400; ++i) {
    const float x = 40 * U(rng), y = 40 * U(rng), th = 1.3f * U(rng), ph = 6.283f * U(rng);
    const k::kvec3 wi = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const SurfaceHit h = s.capm(x, y, wi);
    const k::KnitAggregate a = aggregate(s, x, y, 1e-5f, wi, 16);
    ++n;
    if (a.p_delta == (h.hit ? 0.f : 1.f)) ++pd_same;
    if (h.hit && a.hits == a.points) {
      ++both_hit;
      if (k::kv3_len(k::kv3_sub(a.n, h.normal)) < 1e-3f) ++normal_same;
      if (a.sxx + a.syy < 1e-4f) ++sigma_zero;  // float cancellation in E[b^2] - E[b]^2
    }
  }
  // A handful of rays graze a tube edge, where a 1e-5 shift may change the
  // answer; everything else must be the near-field result exactly.
  EXPECT_GE(pd_same, n * 99 / 100);
  EXPECT_GE(normal_same, both_hit * 99 / 100);
  EXPECT_GE(sigma_zero, both_hit * 99 / 100);
  EXPECT_GT(both_hit, 250);
}

// Spatial stability: with a fixed sample shift (as a renderer's sampler
// would give neighbouring pixels the same pattern), the aggregate's variance
// over footprint positions falls as the footprint grows.
TEST(MultiScale, OutputStabilisesAsFootprintGrows) {
  for (const NamedPattern& np : {NamedPattern{"seed", seed()}, NamedPattern{"pyramid16", pyramid16()}}) {
    KnitSurface s(np.pattern, StitchParams{});
    const k::kvec3 wi = k::kv3_normalize(k::kv3(0.3f, 0.2f, 0.93f));
    std::mt19937 rng(8);
    std::uniform_real_distribution<float> U(0, 1);
    double prev_var = 1e9, prev_var_n = 1e9, first_var_n = 0;
    for (float stitches : {0.25f, 1.f, 4.f, 16.f}) {
      const float size = stitches * 6.2832f;
      double sum = 0, sum2 = 0, nz = 0, nz2 = 0;
      const int m = 200;
      for (int i = 0; i < m; ++i) {
        const k::KnitAggregate a = aggregate(s, 500 * U(rng), 500 * U(rng), size, wi, 16, 0.37f, 0.71f);
        sum += a.p_delta;
        sum2 += a.p_delta * a.p_delta;
        nz += a.n.z;
        nz2 += a.n.z * a.n.z;
      }
      const double var = std::max(0.0, sum2 / m - (sum / m) * (sum / m));
      const double var_n = std::max(0.0, nz2 / m - (nz / m) * (nz / m));
      std::printf("[ ms ] %-10s footprint %5.2f stitches: p_delta mean %.4f var %.6f | normal.z var %.6f\n",
                  np.name.c_str(), stitches, sum / m, var, var_n);
      EXPECT_LE(var, prev_var) << np.name << " " << stitches;
      if (stitches < 1) first_var_n = var_n;
      prev_var = var;
      prev_var_n = var_n;
    }
    EXPECT_LT(prev_var, 1e-3) << np.name;
    EXPECT_LT(prev_var_n, first_var_n / 10) << np.name;
  }
}

// p_delta over a footprint of many stitches against the fraction of explicit
// tube ray casts that pass through the same area, and the LEAN covariance
// against the covariance of the explicit tubes' normals.
TEST(MultiScale, MatchesExplicitTubesOverFootprint) {
  for (const NamedPattern& np : groundtruth_patterns()) {
    GroundTruthScene sc(np.pattern, StitchParams{}, 0, 45);
    for (double th_deg : {0.0, 40.0, 70.0}) {
      const double th = th_deg * kPiD / 180;
      const D3 wi = {std::sin(th) * 0.8, std::sin(th) * 0.6, std::cos(th)};
      const k::kvec3 wif = k::kv3(float(wi[0]), float(wi[1]), float(wi[2]));
      const float size = float(sc.x1 - sc.x0);  // a whole pattern repeat (>= 4 stitches)
      const float cx = float(0.5 * (sc.x0 + sc.x1)), cy = float(sc.y0 + 0.5 * size);
      // The model: 8 aggregates with different shifts (as 8 samples of a pixel).
      // The model: 24 aggregates with random shifts (as 24 samples of a pixel).
      std::mt19937 srng(unsigned(th_deg) + 1);
      std::uniform_real_distribution<float> S(0, 1);
      const int reps = 24;
      double apd = 0, asxx = 0, asyy = 0;
      int points = 0;
      for (int rep = 0; rep < reps; ++rep) {
        const k::KnitAggregate a =
            k::knit_aggregate(sc.surface.geom(), sc.surface.codes(), sc.surface.colors(), cx, cy,
                              k::kv3(size, 0, 0), k::kv3(0, size, 0), wif, 64, S(srng), S(srng), 0, 0, 6.2832f, 32);
        apd += a.p_delta / reps;
        asxx += a.sxx / reps;
        asyy += a.syy / reps;
        points += a.points;
      }
      // Reference: a dense grid of explicit-tube rays over the same square.
      int n = 0, through = 0;
      double mx = 0, my = 0, mxx = 0, mxy = 0, myy = 0;
      int hits = 0;
      const int G = 60;
      for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j) {
          const double x = cx + size * ((i + 0.5) / G - 0.5), y = cy + size * ((j + 0.5) / G - 0.5);
          D3 o, d;
          sc.entry_ray(x, y, wi, o, d);
          const TubeHit h = sc.tubes.intersect(o, d, 0, sc.shell_exit(o, d));
          ++n;
          if (!h.hit) {
            ++through;
            continue;
          }
          const double nz = std::max(h.normal[2], 1 / std::sqrt(17.0));  // slope clamp 4, as the kernel
          const double bx = std::clamp(h.normal[0] / nz, -4.0, 4.0), by = std::clamp(h.normal[1] / nz, -4.0, 4.0);
          mx += bx;
          my += by;
          mxx += bx * bx;
          mxy += bx * by;
          myy += by * by;
          ++hits;
        }
      const double pd = double(through) / n;
      mx /= hits;
      my /= hits;
      const double sxx = mxx / hits - mx * mx, syy = myy / hits - my * my;
      std::printf("[ ms ] %-20s %2.0f deg: p_delta model %.4f explicit %.4f | slope var xx %.3f/%.3f yy %.3f/%.3f\n",
                  np.name.c_str(), th_deg, apd, pd, asxx, sxx, asyy, syy);
      // Sampling noise of the model's points, plus 0.5% for the geometry.
      const double sigma = std::sqrt(std::max(pd * (1 - pd), 0.01) / points);
      EXPECT_NEAR(apd, pd, 3.5 * sigma + 0.005) << np.name << " " << th_deg;
      EXPECT_NEAR(asxx, sxx, 0.15 * sxx + 0.05) << np.name << " " << th_deg;
      EXPECT_NEAR(asyy, syy, 0.15 * syy + 0.05) << np.name << " " << th_deg;
    }
  }
}

// How many footprint points: the error of one aggregate against the
// footprint's true average (the mean of 32 aggregates of 64 points with
// random shifts), for n_points 4..32 and footprints of 0.5, 1 and 4
// stitches. Prints the table behind the default of 16 (docs/multiscale.md).
TEST(MultiScale, DefaultPointCountIsAccurateEnough) {
  KnitSurface s(seed(), StitchParams{});
  const k::kvec3 wi = k::kv3_normalize(k::kv3(0.4f, 0.1f, 0.91f));
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> U(0, 1);
  double err16 = 0;
  for (float stitches : {0.5f, 1.f, 4.f}) {
    const float size = stitches * 6.2832f;
    const int m = 40;
    std::vector<float> xs, ys, truth;
    for (int i = 0; i < m; ++i) {
      xs.push_back(300 * U(rng));
      ys.push_back(300 * U(rng));
      double t = 0;
      for (int r = 0; r < 32; ++r) t += aggregate(s, xs.back(), ys.back(), size, wi, 64, U(rng), U(rng)).p_delta / 32;
      truth.push_back(float(t));
    }
    for (int npts : {4, 8, 16, 32}) {
      double ep = 0;
      int used = 0;
      for (int i = 0; i < m; ++i) {
        const k::KnitAggregate a = aggregate(s, xs[size_t(i)], ys[size_t(i)], size, wi, npts, U(rng), U(rng));
        ep += (a.p_delta - truth[size_t(i)]) * (a.p_delta - truth[size_t(i)]);
        used = a.points;
      }
      const double rp = std::sqrt(ep / m);
      std::printf("[ ms ] footprint %.1f stitch(es), n_points %2d (%2d used): rms p_delta error %.4f\n", stitches,
                  npts, used, rp);
      if (npts == 16) err16 = std::max(err16, rp);
    }
  }
  EXPECT_LT(err16, 0.12) << "16 points (the default) should estimate p_delta within ~0.1 rms";
}

}  // namespace

namespace {

// Regression: seen from behind, slopes were taken against +z, so the
// downward-facing hits were all clamped. The seed pattern's back is its front
// shifted, so both sides must give the same slope spread.
TEST(MultiScale, BackViewSlopesMatchFrontView) {
  using namespace knit;
  KnitSurface s(test::seed(), StitchParams{});
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> U(0, 1);
  double front[2] = {0, 0}, back[2] = {0, 0};
  const float size = 4 * 6.2832f;
  for (int i = 0; i < 24; ++i) {
    const float x = 200 * U(rng), y = 200 * U(rng), sx = U(rng), sy = U(rng);
    const k::KnitAggregate f = k::knit_aggregate(s.geom(), s.codes(), s.colors(), x, y, k::kv3(size, 0, 0),
                                                 k::kv3(0, size, 0), k::kv3(0, 0, 1), 32, sx, sy, 0, 0, 6.2832f, 32);
    const k::KnitAggregate b = k::knit_aggregate(s.geom(), s.codes(), s.colors(), x, y, k::kv3(size, 0, 0),
                                                 k::kv3(0, size, 0), k::kv3(0, 0, -1), 32, sx, sy, 0, 0, 6.2832f, 32);
    front[0] += f.sxx;
    front[1] += f.syy;
    back[0] += b.sxx;
    back[1] += b.syy;
  }
  for (int c = 0; c < 2; ++c) {
    EXPECT_GT(back[c] / front[c], 0.75) << c;
    EXPECT_LT(back[c] / front[c], 1.33) << c;
  }
}

}  // namespace
