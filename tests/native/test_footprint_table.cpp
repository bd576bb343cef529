// The multi-scale class table (knit/aggregate_table.h): over footprints of
// whole pattern repeats it must give what explicit tubes give (fraction of
// rays passing through, mean normal, slope covariance), from both sides;
// the colour histogram must follow the cells; and the material must use it
// only for footprints of a cell or more.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "groundtruth.h"
#include "knit/aggregate_table.h"
#include "knit/kernel.h"
#include "knit/shading.h"
#include "test_patterns.h"

namespace {

using namespace knit;
using namespace knit::test;

// The explicit tubes' first hit of the ray seen along wi through pattern
// point (x, y): from in front, from (x, y, top) into the shell; from behind,
// from the shell's bottom to (x, y, top).
TubeHit tubes_along(const GroundTruthScene& sc, double x, double y, const D3& wi) {
  D3 o, d;
  sc.entry_ray(x, y, wi, o, d);
  double tmax = sc.shell_exit(o, d);
  if (d[2] > 0) {  // from behind: the ray crossed the shell from its bottom to (x, y, top)
    tmax = 2 * sc.surface.shell_top() / d[2];
    o = add(o, mul(d, -tmax));
  }
  return sc.tubes.intersect(o, d, 0, tmax);
}

// The marched aggregate over the square footprint of side `size` at (x, y),
// 16 shifts of 64 points: its share of colour index 1 and its mean layer
// count (hit-weighted), and its hits.
struct MarchedMix {
  double c1 = 0, layers = 0, hits = 0;
};
MarchedMix marched_mix(const KnitSurface& s, float x, float y, float size, k::kvec3 wi, std::mt19937& rng,
                       std::uniform_real_distribution<float>& U) {
  MarchedMix mm;
  for (int i = 0; i < 16; ++i) {
    const k::KnitAggregate m = k::knit_aggregate(s.geom(), s.codes(), s.colors(), x, y, k::kv3(size, 0, 0),
                                                 k::kv3(0, size, 0), wi, 64, U(rng), U(rng), 0, 0, 6.2832f, 32);
    mm.c1 += m.color_w[1] * m.hits;
    mm.layers += m.layers * m.hits;
    mm.hits += m.hits;
  }
  mm.c1 /= mm.hits;
  mm.layers /= mm.hits;
  return mm;
}

double angle_between(const D3& a, const D3& b) {
  const double d = (a[0] * b[0] + a[1] * b[1] + a[2] * b[2]) /
                   std::sqrt((a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) * (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]));
  return std::acos(std::clamp(d, -1.0, 1.0)) * 180 / kPiD;
}

// The tables' direction bins come from atan2_coarse, environment-map
// texels from atan2_approx and acos_approx: against double precision atan2
// over every octant, the axes, near-axis and tiny arguments.
double worst_atan2_error(float (*f)(float, float)) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> ang(-3.2f, 3.2f), mag(-20.0f, 5.0f);
  double worst = 0;
  auto check = [&](float y, float x) {
    const double ref = std::atan2(double(y), double(x));
    const double got = f(y, x);
    EXPECT_TRUE(std::isfinite(got)) << y << " " << x;
    // +-pi are the same direction; the cut sits on x < 0, y = 0.
    double e = std::fabs(got - ref);
    e = std::min(e, std::fabs(e - 2 * kPiD));
    worst = std::max(worst, e);
  };
  for (int i = 0; i < 200000; ++i) {
    const float a = ang(rng), r = std::exp2(mag(rng));
    check(r * std::sin(a), r * std::cos(a));
  }
  for (float v : {1.0f, 1e-30f, 3e30f})
    for (float y : {0.0f, v, -v})
      for (float x : {0.0f, v, -v}) check(y, x);
  check(1.0f, 1e-7f);
  check(-1e-7f, -1.0f);
  EXPECT_EQ(f(0.0f, 0.0f), 0.0f);
  return worst;
}

TEST(FootprintTable, ApproximateAtan2IsWithinItsBoundOfDoublePrecision) {
  const double fine = worst_atan2_error(atan2_approx), coarse = worst_atan2_error(atan2_coarse);
  std::printf("[atan2] worst error %.3g rad (atan2_approx), %.3g rad (atan2_coarse)\n", fine, coarse);
  EXPECT_LT(fine, 4e-7);
  EXPECT_LT(coarse, 1e-4);
  EXPECT_GT(fine, 0.0) << "an exact atan2 would not need this test";
}

// acos_approx: against double precision acos of the same float, over
// [-1, 1] and its ends. The float argument itself resolves angles near 0
// and pi only to about 3e-4 rad; inside |c| < 0.999 the error must be
// atan2_approx's.
TEST(FootprintTable, ApproximateAcosIsWithinItsArgumentsResolution) {
  double worst_inner = 0, worst_ends = 0;
  for (int i = 0; i <= 400000; ++i) {
    const float c = -1.0f + 2.0f * float(i) / 400000.0f;
    const double e = std::fabs(double(acos_approx(c)) - std::acos(double(c)));
    double& worst = std::fabs(c) < 0.999f ? worst_inner : worst_ends;
    worst = std::max(worst, e);
  }
  std::printf("[acos] worst error %.3g rad inside |c| < 0.999, %.3g at the ends\n", worst_inner, worst_ends);
  EXPECT_LT(worst_inner, 5e-7);
  EXPECT_LT(worst_ends, 1e-5);
  EXPECT_FLOAT_EQ(acos_approx(1.0f), 0.0f);
  EXPECT_NEAR(acos_approx(-1.0f), kPiD, 1e-6);
  EXPECT_NEAR(acos_approx(2.0f), 0.0f, 1e-7) << "clamped";
}

TEST(FootprintTable, ClassesFollowCodeAndNeighbourSigns) {
  KnitSurface st(stockinette(), StitchParams{});
  EXPECT_EQ(FootprintTable::cell_class(st, 0, 0), 0);
  KnitSurface rs(reverse_stockinette(), StitchParams{});
  EXPECT_EQ(FootprintTable::cell_class(rs, 0, 0), 4 + 2 + 1);
  // Garter: knit rows between purl rows take the purl signs for head and sinker.
  KnitSurface ga(garter(), StitchParams{});
  const int a = FootprintTable::cell_class(ga, 0, 0), b = FootprintTable::cell_class(ga, 1, 0);
  EXPECT_NE(a, b);
  EXPECT_TRUE((a == 3 && b == 4) || (a == 4 && b == 3)) << a << " " << b;
  KnitSurface sl(slip_floats(), StitchParams{});
  FootprintTable t(sl, CapmOptions{}, 8);
  EXPECT_EQ(t.classes_present(), 3);  // knit, front float, back float
}

// Over a whole pattern repeat, seen from in front and from behind: p_delta,
// mean normal and slope covariance against a dense grid of explicit-tube
// rays over the same square (double precision, tests/support/groundtruth.h).
TEST(FootprintTable, MatchesExplicitTubesOverFootprint) {
  double worst_pd = 0, worst_n = 0;
  for (const NamedPattern& np : groundtruth_patterns()) {
    GroundTruthScene sc(np.pattern, StitchParams{}, 0, 45);
    const FootprintTable table(sc.surface, CapmOptions{});
    for (double th_deg : {0.0, 25.0, 40.0, 60.0, 70.0, 120.0, 150.0}) {
      const double th = th_deg * kPiD / 180;
      const D3 wi = {std::sin(th) * 0.8, std::sin(th) * 0.6, std::cos(th)};
      const k::kvec3 wif = k::kv3(float(wi[0]), float(wi[1]), float(wi[2]));
      const float size = float(sc.x1 - sc.x0);  // a whole pattern repeat (>= 4 stitches)
      const float cx = float(0.5 * (sc.x0 + sc.x1)), cy = float(sc.y0 + 0.5 * size);
      const k::KFootprint f =
          k::knit_footprint(sc.surface.geom(), cx, cy, k::kv3(size, 0, 0), k::kv3(0, size, 0), 16, 0.3f, 0.6f);
      ASSERT_EQ(f.stratified, 1);
      const k::KnitAggregate a = table.aggregate(sc.surface, f, wif);
      EXPECT_FLOAT_EQ(table.p_delta(sc.surface, f, wif), a.p_delta);
      // Explicit tubes over the cells the footprint covers.
      const double cw = 6.283185307179586, ch = sc.surface.geom().row_spacing;
      const double x0 = f.bx0 * cw, y0 = f.by0 * ch, w = f.ncx * cw, h = f.ncy * ch;
      int n = 0, through = 0, hits = 0;
      double mx = 0, my = 0, mxx = 0, myy = 0;
      D3 nsum = {0, 0, 0};
      const int G = 72;
      const double side = wi[2] < 0 ? -1 : 1;
      for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j) {
          const TubeHit th_ = tubes_along(sc, x0 + w * (i + 0.5) / G, y0 + h * (j + 0.5) / G, wi);
          ++n;
          if (!th_.hit) {
            ++through;
            continue;
          }
          const double nz = std::max(side * th_.normal[2], 1 / std::sqrt(17.0));  // slope clamp 4
          const double bx = std::clamp(th_.normal[0] / nz, -4.0, 4.0), by = std::clamp(th_.normal[1] / nz, -4.0, 4.0);
          mx += bx;
          my += by;
          mxx += bx * bx;
          myy += by * by;
          for (int c = 0; c < 3; ++c) nsum[c] += th_.normal[c];
          ++hits;
        }
      const double pd = double(through) / n;
      mx /= std::max(hits, 1);
      my /= std::max(hits, 1);
      const double sxx = mxx / std::max(hits, 1) - mx * mx, syy = myy / std::max(hits, 1) - my * my;
      const double nerr = hits > 0 ? angle_between({a.n.x, a.n.y, a.n.z}, nsum) : 0;
      std::printf("[ table ] %-20s %3.0f deg: p_delta table %.4f explicit %.4f | mean normal %.2f deg | "
                  "slope var xx %.3f/%.3f yy %.3f/%.3f\n",
                  np.name.c_str(), th_deg, a.p_delta, pd, nerr, a.sxx, sxx, a.syy, syy);
      worst_pd = std::max(worst_pd, std::abs(a.p_delta - pd));
      worst_n = std::max(worst_n, nerr);
      EXPECT_NEAR(a.p_delta, pd, 0.03) << np.name << " " << th_deg;
      EXPECT_LT(nerr, 3.0) << np.name << " " << th_deg;
      EXPECT_NEAR(a.sxx, sxx, 0.2 * sxx + 0.05) << np.name << " " << th_deg;
      EXPECT_NEAR(a.syy, syy, 0.2 * syy + 0.05) << np.name << " " << th_deg;
    }
  }
  std::printf("[ table ] worst |p_delta - explicit| %.4f, worst mean-normal angle %.2f deg\n", worst_pd, worst_n);
}

// The cells of a footprint are visited row by row with the column wrapped
// by hand (or counted per class from per-row prefix counts): the same
// footprint moved by whole pattern repeats, to negative coordinates too,
// must give the same aggregate.
TEST(FootprintTable, CellVisitsWrapAndOneClassNeedsNone) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> U(0, 1);
  {
    KnitSurface s(pyramid16(), StitchParams{});
    const FootprintTable table(s, CapmOptions{});
    ASSERT_GT(table.classes_present(), 1);
    const float cw = 6.2831853f, ch = s.geom().row_spacing;
    for (int rep = 0; rep < 40; ++rep) {
      // Sizes of n + 1/2 cells and centres placed so that the first cell
      // covered is (cy, cx) with half a cell to spare (knit_footprint's
      // floor), so that the moved copies cover the same cells despite float
      // rounding.
      const int cx = int(16 * U(rng)), cy = int(16 * U(rng));
      const int nx = 2 + int(6 * U(rng)), ny = 2 + int(6 * U(rng));
      const float w = cw * (float(nx) + 0.5f), h = ch * (float(ny) + 0.5f);
      const float th = 1.3f * U(rng), ph = 6.2831853f * U(rng);
      const k::kvec3 wi = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      auto at = [&](int mx, int my) {
        const float x = (float(cx + 16 * mx) + 0.5f * float(nx)) * cw;
        const float y = (float(cy + 16 * my) + 0.5f * float(ny)) * ch;
        return k::knit_footprint(s.geom(), x, y, k::kv3(w, 0, 0), k::kv3(0, h, 0), 4, 0.5f, 0.5f);
      };
      const k::KFootprint f0 = at(0, 0);
      ASSERT_EQ(f0.stratified, 1);
      ASSERT_EQ(f0.ncx, nx);
      ASSERT_EQ(f0.bx0, cx);
      ASSERT_EQ(f0.by0, cy);
      const k::KnitAggregate a0 = table.aggregate(s, f0, wi);
      for (const auto& m : {std::pair<int, int>{-3, 0}, {0, -2}, {-5, -7}, {4, 3}}) {
        const k::KFootprint f = at(m.first, m.second);
        ASSERT_EQ(f.ncx, f0.ncx);
        ASSERT_EQ(f.ncy, f0.ncy);
        ASSERT_EQ(f.bx0, cx + 16 * m.first);
        ASSERT_EQ(f.by0, cy + 16 * m.second);
        const k::KnitAggregate a = table.aggregate(s, f, wi);
        EXPECT_FLOAT_EQ(a.p_delta, a0.p_delta) << rep << " moved " << m.first << ", " << m.second;
        EXPECT_FLOAT_EQ(a.n.x, a0.n.x) << rep;
        EXPECT_FLOAT_EQ(a.n.z, a0.n.z) << rep;
        EXPECT_FLOAT_EQ(a.layers, a0.layers) << rep;
        // A shadow ray's p_delta is the camera hit's, bit for bit.
        EXPECT_EQ(table.p_delta(s, f, wi), a.p_delta) << rep;
        EXPECT_FLOAT_EQ(table.p_delta(s, f, wi), a0.p_delta) << rep;
      }
    }
  }
  // The cells of a box are counted per class (one class: no count at all;
  // several: per-row prefix counts, the rows of a box taller than the
  // pattern grouped by repeat), for boxes of any size, with one colour
  // index or several. The reference: the box's cells enumerated one by one,
  // each aggregated as a footprint of that single cell, averaged in double.
  for (const Pattern& pat : {Pattern::from_rows({{0, 0}, {0, 0}}), pyramid16()}) {
    std::vector<std::vector<int>> codes(size_t(pat.rows()), std::vector<int>(size_t(pat.cols())));
    std::vector<std::vector<int>> colours = codes;
    for (int r = 0; r < pat.rows(); ++r)
      for (int c = 0; c < pat.cols(); ++c) codes[size_t(r)][size_t(c)] = int(pat.stitch(r, c));
    colours[0][1] = 1;
    KnitSurface plain(pat, StitchParams{});
    KnitSurface coloured(Pattern::from_rows(codes, colours), StitchParams{});
    const FootprintTable tp(plain, CapmOptions{}), tc(coloured, CapmOptions{});
    const float cw = 6.2831853f, ch = plain.geom().row_spacing;
    int large = 0;
    for (int rep = 0; rep < 30; ++rep) {
      // 1.5 to 41.5 cells a side: up to 1,600 cells, and up to 2.6 repeats of the 16 x 16 pyramid.
      const float sx = cw * (1.5f + 40 * U(rng) * U(rng)), sy = ch * (1.5f + 40 * U(rng) * U(rng));
      const float x = 400 * U(rng) - 200, y = 400 * U(rng) - 200;
      const float th = 1.3f * U(rng), ph = 6.2831853f * U(rng);
      const k::kvec3 wi = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      const k::KFootprint fp = k::knit_footprint(plain.geom(), x, y, k::kv3(sx, 0, 0), k::kv3(0, sy, 0), 4, 0.5f, 0.5f);
      const k::KFootprint fc = k::knit_footprint(coloured.geom(), x, y, k::kv3(sx, 0, 0), k::kv3(0, sy, 0), 4, 0.5f, 0.5f);
      ASSERT_EQ(fp.stratified, 1);
      large += int64_t(fp.ncx) * fp.ncy > KNIT_MS_MAX_POINTS ? 1 : 0;
      double ref_hits = 0, ref_layers = 0;
      for (int ky = 0; ky < fp.ncy; ++ky)
        for (int kx = 0; kx < fp.ncx; ++kx) {
          const float cx = (float(fp.bx0 + kx) + 0.5f) * cw, cy = (float(fp.by0 + ky) + 0.5f) * ch;
          const k::KFootprint one =
              k::knit_footprint(plain.geom(), cx, cy, k::kv3(1.01f * cw, 0, 0), k::kv3(0, 1.01f * ch, 0), 4, 0.5f, 0.5f);
          ASSERT_EQ(one.ncx * one.ncy, 1);
          ASSERT_EQ(one.bx0, fp.bx0 + kx);
          ASSERT_EQ(one.by0, fp.by0 + ky);
          const k::KnitAggregate c = tp.aggregate(plain, one, wi);
          ref_hits += 1.0 - double(c.p_delta);
          ref_layers += (1.0 - double(c.p_delta)) * double(c.layers);
        }
      const double ref_pd = 1 - ref_hits / (double(fp.ncx) * fp.ncy);
      const k::KnitAggregate ap = tp.aggregate(plain, fp, wi), ac = tc.aggregate(coloured, fc, wi);
      const std::string what = std::to_string(pat.rows()) + " rows, footprint " + std::to_string(rep) + " (" +
                               std::to_string(fp.ncx) + " x " + std::to_string(fp.ncy) + " cells)";
      EXPECT_NEAR(ap.p_delta, ref_pd, 2e-5) << what;
      if (ref_hits > 0) EXPECT_NEAR(ap.layers, ref_layers / ref_hits, 1e-4) << what;
      EXPECT_LE(ap.points, KNIT_MS_MAX_POINTS) << what;
      EXPECT_EQ(ap.points, ac.points) << what;
      EXPECT_NEAR(ap.p_delta, ac.p_delta, 1e-6) << what;
      EXPECT_NEAR(ap.n.z, ac.n.z, 1e-6) << what;
      EXPECT_NEAR(ap.layers, ac.layers, 1e-5) << what;
      EXPECT_NEAR(ap.sxx, ac.sxx, 1e-5) << what;
      EXPECT_EQ(tp.p_delta(plain, fp, wi), ap.p_delta) << what;  // bit for bit, as above
      EXPECT_EQ(tc.p_delta(coloured, fc, wi), ac.p_delta) << what;
      EXPECT_NEAR(tc.p_delta(coloured, fc, wi), ap.p_delta, 1e-6) << what;
    }
    EXPECT_GE(large, 5) << "footprints of more than KNIT_MS_MAX_POINTS cells tested";
  }
}

// The class counts of a box are taken over the class matrix's smallest
// periods (a rib written out over several rows repeats every row): the
// same counts as the box's cells classed one by one (cell_class, from the
// pattern), for patterns whose periods are smaller than their size, boxes
// of any size and place, negative coordinates included.
TEST(FootprintTable, BoxCountsOverThePeriodsAreTheCellsCounts) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> U(0, 1);
  // 2x2 rib written 4 x 8 (periods 1 x 4); seed written 6 x 6 (2 x 2); a
  // 3 x 4 block tiled 6 x 8 (3 x 4); the pyramid (16 x 16, no shorter period).
  const std::vector<std::vector<int>> rib = {{0, 0, 1, 1, 0, 0, 1, 1}, {0, 0, 1, 1, 0, 0, 1, 1},
                                             {0, 0, 1, 1, 0, 0, 1, 1}, {0, 0, 1, 1, 0, 0, 1, 1}};
  std::vector<std::vector<int>> seed(6, std::vector<int>(6)), block(6, std::vector<int>(8));
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) seed[size_t(r)][size_t(c)] = (r + c) % 2;
  const int b[3][4] = {{0, 1, 1, 0}, {1, 1, 0, 0}, {0, 0, 0, 1}};
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 8; ++c) block[size_t(r)][size_t(c)] = b[r % 3][c % 4];
  struct Case {
    Pattern pat;
    int pr, pc;
  };
  for (const Case& cs : {Case{Pattern::from_rows(rib), 1, 4}, Case{Pattern::from_rows(seed), 2, 2},
                         Case{Pattern::from_rows(block), 3, 4}, Case{pyramid16(), 16, 16}}) {
    KnitSurface s(cs.pat, StitchParams{});
    const FootprintTable table(s, CapmOptions{}, 4);
    EXPECT_EQ(table.period_rows(), cs.pr) << cs.pat.rows() << " x " << cs.pat.cols();
    EXPECT_EQ(table.period_cols(), cs.pc) << cs.pat.rows() << " x " << cs.pat.cols();
    const float cw = 6.2831853f, ch = s.geom().row_spacing;
    for (int rep = 0; rep < 60; ++rep) {
      const float sx = cw * (1.5f + 30 * U(rng) * U(rng)), sy = ch * (1.5f + 30 * U(rng) * U(rng));
      const float x = 600 * U(rng) - 300, y = 600 * U(rng) - 300;
      const k::KFootprint f = k::knit_footprint(s.geom(), x, y, k::kv3(sx, 0, 0), k::kv3(0, sy, 0), 4, 0.5f, 0.5f);
      ASSERT_EQ(f.stratified, 1);
      std::array<double, FootprintTable::kClasses> ref{};
      for (int ky = 0; ky < f.ncy; ++ky)
        for (int kx = 0; kx < f.ncx; ++kx) ref[size_t(FootprintTable::cell_class(s, f.by0 + ky, f.bx0 + kx))] += 1;
      const std::array<double, FootprintTable::kClasses> got = table.box_counts(f);
      for (int c = 0; c < FootprintTable::kClasses; ++c)
        ASSERT_EQ(got[size_t(c)], ref[size_t(c)]) << "class " << c << ", box " << f.ncx << " x " << f.ncy << " at ("
                                                  << f.bx0 << ", " << f.by0 << ")";
    }
  }
}

// Colours: on the two-colour diamond blocks, the table's histogram over a
// footprint against the marched aggregate's (64 points, many shifts), and
// its mean layer count.
TEST(FootprintTable, ColourHistogramFollowsTheCells) {
  KnitSurface s(example("diamond_blocks_2colour"), StitchParams{});
  const FootprintTable table(s, CapmOptions{});
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> U(0, 1);
  double worst_c = 0, worst_l = 0;
  for (int rep = 0; rep < 24; ++rep) {
    const float size = 6.2831853f * (3 + 5 * U(rng));
    const float x = 300 * U(rng), y = 216 * U(rng);
    const float th = 1.2f * U(rng), ph = 6.2831853f * U(rng);
    const k::kvec3 wi = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const k::KFootprint f = k::knit_footprint(s.geom(), x, y, k::kv3(size, 0, 0), k::kv3(0, size, 0), 64, 0.5f, 0.5f);
    const k::KnitAggregate t = table.aggregate(s, f, wi);
    const MarchedMix mm = marched_mix(s, x, y, size, wi, rng, U);
    const double c1 = mm.c1, layers = mm.layers;
    worst_c = std::max(worst_c, std::abs(t.color_w[1] - c1));
    worst_l = std::max(worst_l, std::abs(t.layers - layers));
    EXPECT_NEAR(t.color_w[0] + t.color_w[1], 1.0, 1e-4);
    EXPECT_NEAR(t.color_w[1], c1, 0.08) << "footprint " << rep;
    EXPECT_NEAR(t.layers, layers, 0.15) << "footprint " << rep;
  }
  std::printf("[ table ] two colours: worst colour-weight difference %.3f, layers %.3f\n", worst_c, worst_l);
}

// The same below a cell: the sub-cells' histogram and layer count over a
// box against the marched aggregate over the same box (points over the
// footprint itself, not over whole cells). Boxes of `lo` to `lo` + 0.45 of
// a cell on their shorter side, at least `lo` on both.
struct SubColourErrors {
  double mean_c = 0, worst_c = 0, worst_l = 0;
  int boxes = 0, mixed = 0;
};

SubColourErrors sub_cell_colours(float lo, double box_c_bound, double box_l_bound) {
  KnitSurface s(example("diamond_blocks_2colour"), StitchParams{});
  const FootprintTable table(s, CapmOptions{});
  const float cw = 6.2831853f, ch = s.geom().row_spacing;
  std::mt19937 rng(6);
  std::uniform_real_distribution<float> U(0, 1);
  SubColourErrors r;
  const int reps = 48;
  for (int rep = 0; rep < reps; ++rep) {
    const float size = (lo + 0.45f * U(rng)) * std::min(cw, ch);
    const float x = 300 * U(rng), y = 216 * U(rng);
    const float th = 1.2f * U(rng), ph = 6.2831853f * U(rng);
    const k::kvec3 wi = k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
    const float ex = size / cw, ey = size / ch;
    if (ex < lo || ey < lo || !FootprintTable::sub_box(x, y, ex, ey, s.geom())) continue;
    const k::KnitAggregate t = table.aggregate_sub(s, x, y, ex, ey, wi);
    const MarchedMix mm = marched_mix(s, x, y, size, wi, rng, U);
    if (!(mm.hits > 0) || t.hits == 0) continue;
    const double c1 = mm.c1, layers = mm.layers;
    if (c1 > 0.05 && c1 < 0.95) ++r.mixed;
    r.worst_c = std::max(r.worst_c, std::abs(t.color_w[1] - c1));
    r.worst_l = std::max(r.worst_l, std::abs(t.layers - layers));
    r.mean_c += std::abs(t.color_w[1] - c1);
    ++r.boxes;
    EXPECT_NEAR(t.color_w[0] + t.color_w[1], 1.0, 1e-4);
    EXPECT_NEAR(t.color_w[1], c1, box_c_bound) << "footprint " << rep;
    EXPECT_NEAR(t.layers, layers, box_l_bound) << "footprint " << rep;
  }
  r.mean_c /= std::max(r.boxes, 1);
  std::printf("[ sub-cells ] two colours, boxes from %.2f cells: colour-weight difference mean %.3f worst %.3f, "
              "layers worst %.3f; %d boxes, %d of both colours\n",
              lo, r.mean_c, r.worst_c, r.worst_l, r.boxes, r.mixed);
  return r;
}

TEST(FootprintTable, SubCellColoursFollowTheCells) {
  const SubColourErrors e = sub_cell_colours(0.5f, 0.1, 0.2);
  EXPECT_LT(e.mean_c, 0.02);
  EXPECT_GT(e.mixed, 3) << "too few footprints on a colour boundary to test the mix";
}

// Boxes of a quarter cell (table_min_cells 0.25): the two or three
// sub-cells a side they overlap reach up to a quarter cell beyond them, so
// a box beside a colour edge takes some of the other colour. Measured
// 2026-12-05: the bounds below were set from it (docs/multiscale.md,
// "Footprints of a quarter cell").
TEST(FootprintTable, QuarterCellColoursFollowTheCells) {
  const SubColourErrors e = sub_cell_colours(0.25f, 0.3, 0.25);
  EXPECT_LT(e.mean_c, 0.04);
  EXPECT_GT(e.boxes, 30);
  EXPECT_GT(e.mixed, 3) << "too few footprints on a colour boundary to test the mix";
}

// The material uses the table for footprints of a cell or more and marches
// smaller ones; footprint_table = false always marches, and so do patterns
// with slip stitches.
TEST(FootprintTable, MaterialUsesItOnlyForLargeFootprints) {
  KnitMaterialParams mp;
  mp.mode = KnitMode::MultiScale;
  KnitMaterial with(seed(), mp);
  mp.footprint_table = false;
  KnitMaterial without(seed(), mp);
  ASSERT_NE(with.footprint_table(), nullptr);
  EXPECT_EQ(without.footprint_table(), nullptr);
  EXPECT_GT(with.state_bytes(), without.state_bytes());
  BaseHit hit;
  hit.u = 0.31f;
  hit.v = 0.47f;
  const Vec3 dir = k::kv3_normalize(k::kv3(0.3f, 0.2f, -1.0f));
  // Small footprint (a tenth of a stitch): both march, identically.
  hit.dudx = hit.dvdy = 0.1f * 6.2831853f / mp.uv_scale;
  const KnitShade a = with.shade(hit, dir, nullptr), b = without.shade(hit, dir, nullptr);
  EXPECT_GT(a.steps, 0);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.point.p_delta, b.point.p_delta);
  // Four stitches: the table (no marching), close to the marched aggregate.
  hit.dudx = hit.dvdy = 4 * 6.2831853f / mp.uv_scale;
  const KnitShade c = with.shade(hit, dir, nullptr), d = without.shade(hit, dir, nullptr);
  EXPECT_EQ(c.steps, 0);
  EXPECT_GT(d.steps, 0);
  EXPECT_NEAR(c.point.p_delta, d.point.p_delta, 0.1);
  EXPECT_NEAR(with.transmittance(hit, dir, nullptr), c.point.p_delta, 1e-6);
  // Slip-stitch floats cross cells: such patterns keep the marched aggregate.
  mp.footprint_table = true;
  KnitMaterial floats(slip_floats(), mp);
  EXPECT_EQ(floats.footprint_table(), nullptr);
  EXPECT_GT(floats.shade(hit, dir, nullptr).steps, 0);
}

// KnitMaterial::uses_shift: where it says the footprint's sample shift is
// not read (near field; a multi-scale footprint of a cell or more, read
// from the class table, of a one-colour pattern), shade() and
// transmittance() give the same bits for any shift, so the renderer may
// skip drawing it; where it says the shift is read, it does change results.
TEST(FootprintTable, ShiftIsReadOnlyWhereTheMaterialSaysSo) {
  std::mt19937 rng(10);
  std::uniform_real_distribution<float> U(0, 1);
  KnitMaterialParams ms;
  ms.mode = KnitMode::MultiScale;
  KnitMaterialParams nf;
  KnitMaterialParams ms2 = ms;  // two yarn colours
  ms2.bsdf.reflect_colors = {Rgb{0.8f, 0.7f, 0.6f}, Rgb{0.2f, 0.3f, 0.7f}};
  ms2.bsdf.transmit_colors = ms2.bsdf.reflect_colors;
  std::vector<std::vector<int>> codes = {{0, 0, 1, 1}, {0, 0, 1, 1}}, colours = {{0, 0, 0, 0}, {0, 1, 0, 1}};
  const KnitMaterial one(Pattern::from_rows(codes), ms), two(Pattern::from_rows(codes, colours), ms2),
      near(Pattern::from_rows(codes), nf);
  int unread = 0, read_differs = 0, read = 0;
  for (int i = 0; i < 400; ++i) {
    BaseHit hit;
    hit.u = U(rng);
    hit.v = U(rng);
    // below a cell (marched), a few cells (visited or counted), and boxes of
    // more than KNIT_MS_MAX_POINTS cells (several colours: their points)
    const float cells = i % 4 == 3 ? 10 + 20 * U(rng) : 0.2f + 6 * U(rng);
    hit.dudx = cells * 6.2831853f / ms.uv_scale;
    hit.dvdy = cells * 4.5f / ms.uv_scale;
    const Vec3 dir = k::kv3_normalize(k::kv3(U(rng) - 0.5f, U(rng) - 0.5f, -1.0f));
    const std::array<float, 2> s1 = {U(rng), U(rng)}, s2 = {U(rng), U(rng)};
    for (const KnitMaterial* m : {&one, &two, &near}) {
      const KnitShade a = m->shade(hit, dir, nullptr, s1), b = m->shade(hit, dir, nullptr, s2);
      const float ta = m->transmittance(hit, dir, nullptr, s1), tb = m->transmittance(hit, dir, nullptr, s2);
      const bool same = a.point.p_delta == b.point.p_delta && a.sn.x == b.sn.x && a.sn.z == b.sn.z &&
                        a.st.y == b.st.y && a.kd_r.r == b.kd_r.r && a.kd_r.g == b.kd_r.g &&
                        a.point.color == b.point.color && a.offset.z == b.offset.z && ta == tb;
      if (!m->uses_shift(hit)) {
        ASSERT_TRUE(same) << "hit " << i << ", " << cells << " cells: the shift changed what uses_shift says is not read";
        ++unread;
      } else {
        ++read;
        read_differs += same ? 0 : 1;
      }
    }
  }
  EXPECT_FALSE(near.uses_shift(BaseHit{}));
  EXPECT_GT(unread, 400);       // the one-colour table footprints and the near field
  EXPECT_GT(read_differs, 50);  // the marched footprints and the two-colour picks do read it
  std::printf("[ shift ] %d shadings where it is not read, %d where it is (%d of them changed by it)\n", unread,
              read, read_differs);
}

// Grazing rays have huge ray differentials (clamped to 1e5 cells per axis by
// knit_footprint): the table counts the 1e10 cells of such a box by pattern
// repeats (never one by one), reports the footprint's points, not its
// cells, and stays finite.
// p_delta is a probability: in [0, 1] for every direction, also where the
// table's four interpolated nodes are all fully covered and the float sum of
// the bilinear weights exceeds 1 (a negative shadow transmittance of -1.2e-7
// was caught by the renderer's sample check on the multi-scale half
// cylinder; 2x2 rib, grazing directions).
TEST(FootprintTable, PassFractionsAreProbabilities) {
  KnitSurface s(Pattern::from_rows({{0, 0, 1, 1}}), StitchParams{});
  const FootprintTable table(s, CapmOptions{}, 32);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  int full = 0;
  float lo = 1, hi = 0;
  for (int i = 0; i < 200000; ++i) {
    const float z = 2 * U(rng) - 1, ph = 6.2831853f * U(rng), sr = std::sqrt(std::max(0.0f, 1 - z * z));
    const k::kvec3 wi = k::kv3(sr * std::cos(ph), sr * std::sin(ph), z);
    const float size = 4 * K_2PI * (1 + 3 * U(rng));
    const k::KFootprint f = k::knit_footprint(s.geom(), 100 * U(rng), 100 * U(rng), k::kv3(size, 0, 0),
                                              k::kv3(0, size * 0.7f, 0), 16, U(rng), U(rng));
    if (!f.stratified) continue;
    const float pd = table.p_delta(s, f, wi);
    const k::KnitAggregate a = table.aggregate(s, f, wi);
    ASSERT_GE(pd, 0.0f) << "direction " << wi.x << " " << wi.y << " " << wi.z;
    ASSERT_LE(pd, 1.0f);
    ASSERT_GE(a.p_delta, 0.0f) << "direction " << wi.x << " " << wi.y << " " << wi.z;
    ASSERT_LE(a.p_delta, 1.0f);
    lo = std::min(lo, pd);
    hi = std::max(hi, pd);
    if (pd == 0) ++full;
  }
  std::printf("[ p_delta ] range [%g, %g], fully covered footprints %d\n", lo, hi, full);
  EXPECT_GT(full, 100);  // the directions that exposed the bug were exercised
}

TEST(FootprintTable, HugeFootprintsStayBounded) {
  KnitSurface s(seed(), StitchParams{});
  const FootprintTable table(s, CapmOptions{}, 16);
  const k::kvec3 wi = k::kv3(0, 0, 1);
  for (float size : {1e3f, 1e6f, 1e30f, INFINITY}) {
    const k::KFootprint f = k::knit_footprint(s.geom(), 3.0f, 2.0f, k::kv3(size, 0, 0), k::kv3(0, size, 0), 16, 0.3f, 0.6f);
    const k::KnitAggregate a = table.aggregate(s, f, wi);
    EXPECT_LE(a.points, KNIT_MS_MAX_POINTS) << size;
    EXPECT_TRUE(std::isfinite(a.p_delta) && a.p_delta > 0 && a.p_delta < 1) << size << ": " << a.p_delta;
    EXPECT_TRUE(std::isfinite(a.n.x) && std::isfinite(a.n.y) && std::isfinite(a.n.z)) << size;
    EXPECT_FLOAT_EQ(table.p_delta(s, f, wi), a.p_delta) << size;
  }
}

// Below a stitch cell a footprint is shaded as the near field (the default,
// near_field_below_cell), or, without that, gets the share of
// footprint_points its area covers (at least one): seen straight down every
// point is one CAPM segment, so the segments count the points.
TEST(FootprintTable, FootprintsBelowACellAreTheNearFieldOrMarchPointsInProportionToTheirArea) {
  KnitMaterialParams mp;
  mp.mode = KnitMode::MultiScale;
  mp.footprint_points = 16;
  mp.near_field_below_cell = false;  // (by default such footprints are the near field, below)
  mp.table_min_cells = 1;  // whole cells only: the sub-cells have a test of their own
  KnitMaterial m(seed(), mp);
  mp.near_field_below_cell = true;
  KnitMaterial nf_below(seed(), mp);
  mp.mode = KnitMode::NearField;
  KnitMaterial near(seed(), mp);
  const float cell = 6.2831853f * m.surface().geom().row_spacing;
  BaseHit hit;
  hit.u = 0.31f;
  hit.v = 0.47f;
  const Vec3 down = k::kv3(0, 0, -1);
  for (const auto& [area, points] : std::vector<std::pair<float, int>>{{0.0f, 1}, {1e-4f, 1}, {0.25f, 4}, {0.5f, 8},
                                                                      {0.99f, 16}}) {
    hit.dudx = hit.dvdy = std::sqrt(area * cell) / mp.uv_scale;
    EXPECT_FALSE(m.near_field_at(hit));
    const KnitShade agg = m.shade(hit, down, nullptr);
    EXPECT_EQ(agg.steps, points) << "footprint of " << area << " cells";
    EXPECT_TRUE(agg.aggregated);
    EXPECT_FALSE(agg.in_shell);
    // With near_field_below_cell: one near-field ray, in the shell (so the
    // renderer self-shadows it), as the near-field material shades it.
    EXPECT_TRUE(nf_below.near_field_at(hit));
    const KnitShade a = nf_below.shade(hit, down, nullptr, {0.9f, 0.1f}), b = near.shade(hit, down, nullptr);
    EXPECT_EQ(a.steps, b.steps);
    EXPECT_FALSE(a.aggregated);
    EXPECT_EQ(a.in_shell, b.in_shell);
    EXPECT_EQ(a.pass_through, b.pass_through);
    EXPECT_EQ(a.point.layers, b.point.layers);
    EXPECT_EQ(a.sn.x, b.sn.x);
    EXPECT_EQ(a.sn.z, b.sn.z);
  }
  // A cell or more in both directions: the class table, not the near field.
  hit.dudx = 1.2f * 6.2831853f / mp.uv_scale;
  hit.dvdy = 1.2f * m.surface().geom().row_spacing / mp.uv_scale;
  EXPECT_FALSE(nf_below.near_field_at(hit));
  const KnitShade t = nf_below.shade(hit, down, nullptr);
  EXPECT_TRUE(t.from_table);
  EXPECT_FALSE(t.aggregated);
  hit.dvdy = 0.8f * m.surface().geom().row_spacing / mp.uv_scale;  // below a cell in one direction
  EXPECT_TRUE(nf_below.near_field_at(hit));
}

// The sub-cells (a quarter of a cell on a side): a box of table_min_cells
// or more is the area-weighted sum of the sub-cells it overlaps. Against
// explicit tubes over the same boxes (double-precision ray casts on a 32 x
// 32 grid per box), from in front and behind, the fraction of rays passing
// through and the mean normal; and the sub-cells must be closer to the
// tubes than the whole cell they lie in, which is all a table of whole
// cells can give a box below a cell. The hit fractions come from the
// eighths of a cell where the box touches few enough of them; the same
// table without its eighths (quarters alone) is measured beside them.
struct SubCellErrors {
  double p_delta = 0, p_delta_cell = 0, worst = 0;  // means over the boxes, and the worst
  double p_delta_quarters = 0;                      // the same table without its eighths
  double normal = 0, normal_cell = 0;               // mean angles (degrees), boxes with a mean normal
  int boxes = 0, normals = 0;
};

SubCellErrors sub_cells_against_tubes(double lo, double hi, double box_normal_bound, const char* label) {
  SubCellErrors r;
  double sum_n = 0, sum_n_cell = 0;
  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> U(0, 1);
  for (const NamedPattern& np : groundtruth_patterns()) {
    GroundTruthScene sc(np.pattern, StitchParams{}, 0, 45);
    const FootprintTable table(sc.surface, CapmOptions{});
    const FootprintTable quarters(sc.surface, CapmOptions{}, 256, FootprintTable::LayerCounts::Auto, true, false);
    const double cw = 6.283185307179586, ch = sc.surface.geom().row_spacing;
    double pat_sub = 0, pat_cell = 0, pat_quarters = 0;
    int pat_boxes = 0;
    for (double th_deg : {0.0, 30.0, 55.0, 125.0}) {
      const double th = th_deg * kPiD / 180;
      const D3 wi = {std::sin(th) * 0.6, std::sin(th) * 0.8, std::cos(th)};
      const k::kvec3 wif = k::kv3(float(wi[0]), float(wi[1]), float(wi[2]));
      for (int b = 0; b < 40; ++b) {
        const double ex = lo + (hi - lo) * U(rng), ey = lo + (hi - lo) * U(rng);
        const double bw = ex * cw, bh = ey * ch;
        const double x0 = sc.x0 + (sc.x1 - sc.x0 - bw) * U(rng), y0 = sc.y0 + (sc.y1 - sc.y0 - bh) * U(rng);
        const float cx = float(x0 + 0.5 * bw), cy = float(y0 + 0.5 * bh);
        EXPECT_TRUE(FootprintTable::sub_box(cx, cy, float(ex), float(ey), sc.surface.geom()));
        const k::KnitAggregate a = table.aggregate_sub(sc.surface, cx, cy, float(ex), float(ey), wif);
        // (the same sum in another order: p_delta_sub folds the box's areas
        // where it can, SubCellHitFractionsSumTheBoxOverlaps)
        EXPECT_NEAR(table.p_delta_sub(sc.surface, cx, cy, float(ex), float(ey), wif), a.p_delta, 1e-6);
        // The whole cell under the box's centre, from the whole-cell table.
        const k::KFootprint fc = k::knit_footprint(sc.surface.geom(), cx, cy, k::kv3(float(cw), 0, 0),
                                                   k::kv3(0, float(ch), 0), 4, 0.5f, 0.5f);
        EXPECT_EQ(fc.ncx * fc.ncy, 1);
        const k::KnitAggregate ac = table.aggregate(sc.surface, fc, wif);
        const float pd_cell = ac.p_delta;
        const int G = 32;
        int through = 0;
        D3 nsum = {0, 0, 0};
        for (int i = 0; i < G; ++i)
          for (int j = 0; j < G; ++j) {
            const TubeHit h = tubes_along(sc, x0 + bw * (i + 0.5) / G, y0 + bh * (j + 0.5) / G, wi);
            if (!h.hit) {
              ++through;
              continue;
            }
            for (int c = 0; c < 3; ++c) nsum[c] += h.normal[c];
          }
        const double pd = double(through) / (G * G);
        const double e_sub = std::fabs(a.p_delta - pd), e_cell = std::fabs(pd_cell - pd);
        const double e_quarters = std::fabs(quarters.p_delta_sub(sc.surface, cx, cy, float(ex), float(ey), wif) - pd);
        r.p_delta += e_sub;
        r.p_delta_cell += e_cell;
        r.p_delta_quarters += e_quarters;
        pat_sub += e_sub;
        pat_cell += e_cell;
        pat_quarters += e_quarters;
        r.worst = std::max(r.worst, e_sub);
        ++r.boxes;
        ++pat_boxes;
        if (through < G * G / 2 && a.hits > 0) {  // a mean normal of half the rays or more
          const double nerr = angle_between({a.n.x, a.n.y, a.n.z}, nsum);
          sum_n += nerr;
          sum_n_cell += angle_between({ac.n.x, ac.n.y, ac.n.z}, nsum);
          ++r.normals;
          EXPECT_LT(nerr, box_normal_bound) << label << " " << np.name << " " << th_deg << " box " << b;
        }
      }
    }
    std::printf("[ sub-cells %s ] %-20s mean |p_delta - explicit|: sub-cells %.4f (quarters alone %.4f), whole "
                "cell %.4f (%d boxes)\n",
                label, np.name.c_str(), pat_sub / pat_boxes, pat_quarters / pat_boxes, pat_cell / pat_boxes,
                pat_boxes);
  }
  r.p_delta /= std::max(r.boxes, 1);
  r.p_delta_cell /= std::max(r.boxes, 1);
  r.p_delta_quarters /= std::max(r.boxes, 1);
  r.normal = sum_n / std::max(r.normals, 1);
  r.normal_cell = sum_n_cell / std::max(r.normals, 1);
  std::printf("[ sub-cells %s ] all: mean |p_delta - explicit| sub-cells %.4f (quarters alone %.4f), whole cell "
              "%.4f, worst %.4f; mean normal %.2f deg (whole cell %.2f) over %d boxes\n",
              label, r.p_delta, r.p_delta_quarters, r.p_delta_cell, r.worst, r.normal, r.normal_cell, r.normals);
  return r;
}

// Boxes of half a cell to 0.7 of a cell (table_min_cells 0.5, the default
// until the eighths).
// Measured 2026-12-05: p_delta 0.0163 (quarters alone 0.0212, whole cell
// 0.0386), normals 4.2 deg (9.4).
TEST(FootprintTable, SubCellsMatchExplicitTubes) {
  const SubCellErrors e = sub_cells_against_tubes(0.5, 0.7, 25.0, "0.5-0.7");
  EXPECT_LT(e.p_delta, 0.02);
  EXPECT_LT(e.p_delta, 0.85 * e.p_delta_quarters) << "the eighths must resolve what the quarters cannot";
  EXPECT_LT(e.p_delta, 0.7 * e.p_delta_cell) << "the sub-cells must resolve what the whole cell cannot";
  EXPECT_LT(e.normal, 6.0);
  EXPECT_LT(e.normal, 0.7 * e.normal_cell);
}

// Boxes of a quarter to 0.45 of a cell (table_min_cells down to 0.25): each
// overlaps two or three sub-cells a side, whose statistics reach beyond the
// box, so the errors are about twice those of boxes of half a cell.
// Measured 2026-12-05: p_delta 0.0285 (quarters alone 0.0439, whole cell
// 0.0737), normals 9.2 deg (17.1), worst box 35.3 deg (docs/multiscale.md,
// "Footprints of a quarter cell" and "Eighths of a cell: the gaps").
TEST(FootprintTable, QuarterCellBoxesMatchExplicitTubes) {
  const SubCellErrors e = sub_cells_against_tubes(0.25, 0.45, 40.0, "0.25-0.45");
  EXPECT_LT(e.p_delta, 0.035);
  EXPECT_LT(e.p_delta, 0.75 * e.p_delta_quarters) << "the eighths must resolve what the quarters cannot";
  EXPECT_LT(e.p_delta, 0.7 * e.p_delta_cell) << "the sub-cells must resolve what the whole cell cannot";
  EXPECT_LT(e.normal, 11.0);
  EXPECT_LT(e.normal, 0.7 * e.normal_cell);
}

// p_delta_sub and its per-class hits against their definition, summed in
// double precision sub-cell by sub-cell: each sub-cell the box overlaps,
// weighted by the overlap's area, with the bilinear hit fraction of its
// class and place in the cell (the stored, bfloat16-rounded statistics):
// eighths of a cell where the box touches at most kMaxEighthBox of them,
// else quarters. The table folds boxes over one cell when the classes
// change along one axis only: ribs (by column), garter (by row), one class;
// seed takes the visit of every sub-cell. Boxes up to the 64 sub-cells
// sub_box allows, anywhere (negative coordinates, far from the origin),
// views from both sides.
TEST(FootprintTable, SubCellHitFractionsSumTheBoxOverlaps) {
  struct Case {
    const char* name;
    int axis;  // 0: the classes change along x only, 1: along y only, 2: both
  };
  for (const Case& cs : {Case{"rib_2x2", 0}, Case{"stockinette", 0}, Case{"garter", 1}, Case{"seed", 2}}) {
    KnitSurface s(example(cs.name), StitchParams{});
    const FootprintTable table(s, CapmOptions{});
    ASSERT_TRUE(table.has_eighths());
    if (cs.axis == 0) EXPECT_EQ(table.period_rows(), 1) << cs.name;
    if (cs.axis == 1) EXPECT_EQ(table.period_cols(), 1) << cs.name;
    if (cs.axis == 2) EXPECT_TRUE(table.period_rows() > 1 && table.period_cols() > 1) << cs.name;
    const int nodes = FootprintTable::kThetaBins * FootprintTable::kPhiBins;
    // The stored hit fractions at each resolution: floats a node, the hit
    // fraction first.
    struct Level {
      int sub;
      std::vector<float> values;
      size_t stride;
    };
    const auto level = [&](int sub, std::vector<float> values) {
      const size_t pairs = size_t(table.classes_present()) * size_t(sub * sub);
      return Level{sub, values, values.size() / (pairs * size_t(nodes))};
    };
    const Level quarters = level(FootprintTable::kSub, table.sub_moments());
    const Level eighths = level(FootprintTable::kEighth, table.eighth_hits());
    ASSERT_GT(quarters.stride, 0u);
    ASSERT_EQ(eighths.stride, 1u);
    // (the cell's width as the kernel has it, 2 pi in float: a column is
    // [c K_2PI, (c + 1) K_2PI), which far from the origin differs from the
    // double's by a good part of 1e-4 sub-cells)
    const double cw = double(K_2PI), ch = s.geom().row_spacing;
    std::mt19937 rng(77);
    std::uniform_real_distribution<double> U(0, 1);
    int boxes = 0, long_boxes = 0, eighth_boxes = 0;
    double worst = 0;
    for (int b = 0; b < 400; ++b) {
      const double ex = 0.25 + (b % 3 == 0 ? 2.5 : 0.75) * U(rng), ey = 0.25 + (b % 3 == 1 ? 2.5 : 0.75) * U(rng);
      const double far = b % 4 == 0 ? 2000 : 20;
      const float x = float(far * (2 * U(rng) - 1)), y = float(far * (2 * U(rng) - 1));
      if (!FootprintTable::sub_box(x, y, float(ex), float(ey), s.geom())) continue;
      const double th = 3.0 * U(rng), ph = 2 * kPiD * U(rng);
      const k::kvec3 wi = k::kv3(float(std::sin(th) * std::cos(ph)), float(std::sin(th) * std::sin(ph)),
                                 float(std::cos(th)));
      const SphereNodes dn = sphere_nodes(wi, FootprintTable::kThetaBins, FootprintTable::kPhiBins);
      // The definition, in double, at `lv`'s resolution; false when the box
      // touches more than `most` of its sub-cells.
      const double fex = double(float(ex)), fey = double(float(ey));  // as p_delta_sub takes them
      double area = 0, hits = 0;
      std::array<double, FootprintTable::kClasses> by_slot{};
      int touched = 0;
      const auto define = [&](const Level& lv, int most) {
        const int sub = lv.sub;
        const double xlo = (double(x) / cw - 0.5 * fex) * sub, xhi = (double(x) / cw + 0.5 * fex) * sub;
        const double ylo = (double(y) / ch - 0.5 * fey) * sub, yhi = (double(y) / ch + 0.5 * fey) * sub;
        if ((std::ceil(xhi) - std::floor(xlo)) * (std::ceil(yhi) - std::floor(ylo)) > most) return false;
        area = hits = 0;
        by_slot.fill(0);
        touched = 0;
        for (int64_t j = int64_t(std::floor(ylo)); j < int64_t(std::ceil(yhi)); ++j)
          for (int64_t i = int64_t(std::floor(xlo)); i < int64_t(std::ceil(xhi)); ++i) {
            const double w = (std::min(xhi, double(i + 1)) - std::max(xlo, double(i))) *
                             (std::min(yhi, double(j + 1)) - std::max(ylo, double(j)));
            if (!(w > 0)) continue;
            ++touched;
            const int64_t kr = int64_t(std::floor(double(j) / sub)), kc = int64_t(std::floor(double(i) / sub));
            const int slot = table.slot_of(FootprintTable::cell_class(s, int(kr), int(kc)));
            EXPECT_GE(slot, 0);
            const int pair = slot * sub * sub + int(j - kr * sub) * sub + int(i - kc * sub);
            double h = 0;
            for (int q = 0; q < 4; ++q)
              h += double(dn.w[size_t(q)]) *
                   lv.values[(size_t(pair) * size_t(nodes) + size_t(dn.node[size_t(q)])) * lv.stride];
            h = std::clamp(h, 0.0, 1.0);
            area += w;
            hits += w * h;
            by_slot[size_t(slot)] += w * h;
          }
        return true;
      };
      const bool in_eighths = define(eighths, FootprintTable::kMaxEighthBox);
      if (!in_eighths) define(quarters, 1 << 30);
      ASSERT_GT(area, 0);
      const double ref = std::clamp(1 - hits / area, 0.0, 1.0);
      std::array<float, FootprintTable::kClasses> got_slots{};
      const float got = table.p_delta_sub(s, x, y, float(ex), float(ey), wi, got_slots.data());
      EXPECT_NEAR(got, ref, 2e-6) << cs.name << " box " << b << " at " << x << ", " << y << ": " << ex << " x " << ey
                                  << (in_eighths ? " (eighths)" : " (quarters)");
      for (int sl = 0; sl < table.classes_present(); ++sl)
        EXPECT_NEAR(got_slots[size_t(sl)], by_slot[size_t(sl)] / area, 2e-6)
            << cs.name << " box " << b << " slot " << sl;
      worst = std::max(worst, std::abs(double(got) - ref));
      ++boxes;
      eighth_boxes += in_eighths;
      if (!in_eighths && touched > 2 * quarters.sub * quarters.sub) ++long_boxes;
    }
    std::printf("[ sub-cells ] %-12s p_delta_sub against the sub-cell sum in double: worst %.2e over %d boxes "
                "(%d in eighths, %d of more than 32 quarters)\n",
                cs.name, worst, boxes, eighth_boxes, long_boxes);
    EXPECT_GT(boxes, 200) << cs.name;
    EXPECT_GT(eighth_boxes, 30) << cs.name << ": too few boxes to test the eighths";
    EXPECT_GT(long_boxes, 20) << cs.name << ": too few long boxes to test the fold";
  }
}

// The sub-cells come from the rays of the whole cells, split by where they
// start: a (0,2)-net puts a sixteenth of them in each, so each linear
// statistic of a node is the mean of its sixteen sub-cells' (to their
// bfloat16 rounding); and they must differ from it, or they would resolve
// nothing. Likewise a sub-cell's hit fraction and its four eighths'.
TEST(FootprintTable, WholeCellsAreTheMeanOfTheirSubCells) {
  KnitSurface s(seed(), StitchParams{});
  const FootprintTable t(s, CapmOptions{}, 64);
  constexpr int kStats = 24, kLinearStats = 20, kNodes = FootprintTable::kThetaBins * FootprintTable::kPhiBins;
  constexpr int kSubs = FootprintTable::kSub * FootprintTable::kSub;
  const std::vector<float>&whole = t.node_moments(), &sub = t.sub_moments();
  ASSERT_EQ(sub.size(), whole.size() * kSubs);
  ASSERT_TRUE(t.one_colour());  // (the neighbour shares are not kept: skipped below)
  double worst = 0, spread = 0;
  for (int slot = 0; slot < t.classes_present(); ++slot)
    for (int node = 0; node < kNodes; ++node)
      for (int q = 0; q < kLinearStats; ++q) {
        if (q >= 11) break;  // the neighbour shares, kept only with several colour indices
        const float w = whole[(size_t(slot) * kNodes + size_t(node)) * kStats + size_t(q)];
        double mean = 0, big = 1;
        for (int si = 0; si < kSubs; ++si) {
          const float v = sub[((size_t(slot) * kSubs + size_t(si)) * kNodes + size_t(node)) * kStats + size_t(q)];
          mean += v / kSubs;
          big = std::max(big, double(std::fabs(v)));
          if (q == 0) spread = std::max(spread, double(std::fabs(v - w)));
        }
        worst = std::max(worst, std::fabs(mean - w) / big);
      }
  std::printf("sub-cells: worst relative gap to their whole cell's mean %.2g; widest hit-fraction spread %.3f\n",
              worst, spread);
  EXPECT_LT(worst, 1.0 / 512 + 1e-6);  // bfloat16's rounding, 2^-9 of the largest value
  EXPECT_GT(worst, 0.0) << "stored in float: the bound above is loose";
  EXPECT_GT(spread, 0.2);

  // The eighths' hit fractions: each sub-cell's is the mean of the four
  // eighths inside it (both rounded to bfloat16: 2^-9 of 1 each), and they
  // differ from it (with 64 rays a direction, an eighth holds one ray: its
  // hit fraction is 0 or 1, its sub-cell's a mean of four).
  constexpr int kE = FootprintTable::kEighth, kEighths = kE * kE, kS = FootprintTable::kSub;
  const std::vector<float> eighth = t.eighth_hits();
  ASSERT_EQ(eighth.size(), size_t(t.classes_present()) * kEighths * kNodes);
  double worst_e = 0, spread_e = 0;
  int both = 0;
  for (int slot = 0; slot < t.classes_present(); ++slot)
    for (int node = 0; node < kNodes; ++node)
      for (int si = 0; si < kSubs; ++si) {
        const int sy = si / kS, sx = si % kS;
        const float q = sub[((size_t(slot) * kSubs + size_t(si)) * kNodes + size_t(node)) * kStats];
        double mean = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) {
            const int ei = (2 * sy + dy) * kE + 2 * sx + dx;
            const float v = eighth[(size_t(slot) * kEighths + size_t(ei)) * kNodes + size_t(node)];
            EXPECT_TRUE(v >= 0 && v <= 1) << v;
            mean += v / 4;
            spread_e = std::max(spread_e, double(std::fabs(v - q)));
            both += v > 0 && v < 1;
          }
        worst_e = std::max(worst_e, std::fabs(mean - q));
      }
  std::printf("eighths: worst gap to their sub-cell's hit fraction %.2g; widest spread %.3f; %d of them neither 0 "
              "nor 1 (the poles' means)\n",
              worst_e, spread_e, both);
  EXPECT_LT(worst_e, 2.0 / 512 + 1e-6);
  EXPECT_GT(spread_e, 0.4);
  // Without eighths, or with rays that do not put one in each (fewer than
  // 64 a direction, or not a multiple of 64: a direction's run of the net
  // then starts off a multiple of 64): none kept.
  EXPECT_FALSE(FootprintTable(s, CapmOptions{}, 64, FootprintTable::LayerCounts::Auto, true, false).has_eighths());
  EXPECT_FALSE(FootprintTable(s, CapmOptions{}, 32).has_eighths());
  EXPECT_FALSE(FootprintTable(s, CapmOptions{}, 100).has_eighths());
}

// Which footprints the material reads from the sub-cells: at least
// table_min_cells in both directions and below a cell in one, within
// kMaxSubBox sub-cells; others keep their paths. Out-of-range
// table_min_cells is rejected naming the field.
TEST(FootprintTable, MaterialReadsSubCellsFromTableMinCells) {
  KnitMaterialParams mp;
  mp.mode = KnitMode::MultiScale;
  EXPECT_EQ(mp.table_min_cells, FootprintTable::kMinSubBox);  // the default: the sub-cells' own size
  mp.table_min_cells = 0.5f;
  KnitMaterial half(seed(), mp);
  mp.table_min_cells = 1;
  KnitMaterial whole(seed(), mp);
  ASSERT_TRUE(half.footprint_table()->has_sub_cells());
  ASSERT_FALSE(whole.footprint_table()->has_sub_cells());  // not built where they are not read
  EXPECT_LT(4 * whole.footprint_table()->bytes(), half.footprint_table()->bytes());
  EXPECT_THROW(whole.footprint_table()->p_delta_sub(whole.surface(), 1, 1, 0.6f, 0.6f, k::kv3(0, 0, 1)),
               std::logic_error);
  // Boxes outside the sub-cells' domain are refused, not read out of bounds.
  const FootprintTable& tb = *half.footprint_table();
  const k::KnitGeom& g = half.surface().geom();
  for (const std::array<float, 4>& b : std::vector<std::array<float, 4>>{{1, 1, 0.2f, 0.6f},
                                                                       {1, 1, 0.6f, 70.0f},
                                                                       {1e30f, 1, 0.6f, 0.6f},
                                                                       {1, std::nanf(""), 0.6f, 0.6f},
                                                                       {1, 1, std::nanf(""), 0.6f},
                                                                       {1, 1, 0.6f, INFINITY}}) {
    EXPECT_FALSE(FootprintTable::sub_box(b[0], b[1], b[2], b[3], g)) << b[0] << " " << b[1] << " " << b[2] << " " << b[3];
    EXPECT_THROW(tb.aggregate_sub(half.surface(), b[0], b[1], b[2], b[3], k::kv3(0, 0, 1)), std::invalid_argument);
  }
  EXPECT_TRUE(FootprintTable::sub_box(-5e3f, 7e3f, 0.5f, 1.7f, g));
  const float cw = 6.2831853f, ch = half.surface().geom().row_spacing;
  BaseHit hit;
  hit.u = 0.37f;
  hit.v = 0.21f;
  const Vec3 dir = k::kv3_normalize(k::kv3(0.3f, 0.1f, -1));
  auto size = [&](float ex, float ey) {
    hit.dudx = ex * cw / mp.uv_scale;
    hit.dvdy = ey * ch / mp.uv_scale;
  };
  size(0.6f, 0.8f);
  EXPECT_FALSE(half.near_field_at(hit));
  EXPECT_TRUE(whole.near_field_at(hit));
  EXPECT_FALSE(half.uses_shift(hit));  // one colour: no points, no pick
  const KnitShade t = half.shade(hit, dir, nullptr);
  EXPECT_TRUE(t.from_table);
  EXPECT_FALSE(t.aggregated);
  EXPECT_FALSE(t.in_shell);
  const Vec3 wi = k::kv3_neg(dir);
  const float x = mp.uv_scale * hit.u, y = mp.uv_scale * hit.v;
  const float pd = half.footprint_table()->p_delta_sub(half.surface(), x, y, 0.6f, 0.8f, wi);
  EXPECT_FLOAT_EQ(half.transmittance(hit, dir, nullptr), pd);
  EXPECT_FLOAT_EQ(t.pass_through ? 1.0f : t.point.p_delta, pd);
  size(0.45f, 0.8f);  // below half a cell in one direction: the near field
  EXPECT_TRUE(half.near_field_at(hit));
  {  // ... unless table_min_cells goes down to the sub-cells' own size (the default)
    KnitMaterialParams qp;
    qp.mode = KnitMode::MultiScale;
    const KnitMaterial quarter(seed(), qp);
    EXPECT_FALSE(quarter.near_field_at(hit));
    EXPECT_TRUE(quarter.shade(hit, dir, nullptr).from_table);
    size(0.3f, 0.26f);
    EXPECT_FALSE(quarter.near_field_at(hit));
    size(0.24f, 0.8f);  // below a quarter of a cell: the near field
    EXPECT_TRUE(quarter.near_field_at(hit));
    EXPECT_FALSE(FootprintTable::sub_box(1, 1, 0.24f, 0.8f, g));
    EXPECT_TRUE(FootprintTable::sub_box(1, 1, 0.25f, 0.25f, g));
  }
  size(0.6f, 40.0f);  // 3 x 81 sub-cells: more than kMaxSubBox
  EXPECT_TRUE(half.near_field_at(hit));
  size(1.5f, 2.5f);  // whole cells: the same path either way
  EXPECT_FALSE(half.near_field_at(hit));
  const KnitShade a = half.shade(hit, dir, nullptr), b = whole.shade(hit, dir, nullptr);
  EXPECT_TRUE(a.from_table);
  EXPECT_EQ(a.point.p_delta, b.point.p_delta);
  EXPECT_EQ(a.sn.z, b.sn.z);
  for (float bad : {0.24f, 1.01f, std::nanf("")}) {
    mp.table_min_cells = bad;
    try {
      KnitMaterial m(seed(), mp);
      ADD_FAILURE() << "table_min_cells " << bad << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("table_min_cells"), std::string::npos) << e.what();
    }
  }
}

// The build counts the layers under its hits with one batched query per
// direction node where the CPU has a vector path. The table must be the one
// the scalar counting query gives: every statistic but the layer count bit
// for bit; the layer count may differ by one ray's count in a few nodes, the
// hits lying on tube surfaces, where the two paths' rounding can decide
// differently whether the vertical line grazes a tube (measured: 17 of
// 8,064 nodes, by one count in 32 rays).
TEST(FootprintTable, BatchedLayerCountsBuildTheScalarTable) {
  const KnitSurface::BatchIsa isa = KnitSurface(stockinette(), StitchParams{}).batch_isa(KnitSurface::BatchPath::Auto);
  std::printf("layer counts batched on the %s path\n", KnitSurface::batch_isa_name(isa));
  if (isa == KnitSurface::BatchIsa::Scalar)
    GTEST_SKIP() << "this CPU or build has no vector query path: both builds count one query at a time";
  constexpr int kRays = 32, kStats = 24, kLayerStat = 9;  // the node layout of aggregate_table.h
  size_t nodes = 0, layer_differ = 0;
  double layers_total = 0;
  for (const Pattern& p : {seed(), slip_floats(), pyramid16(), example("basketweave"), example("linen_stitch")}) {
    KnitSurface s(p, StitchParams{});
    FootprintTable batched(s, CapmOptions{}, kRays, FootprintTable::LayerCounts::Auto);
    FootprintTable scalar(s, CapmOptions{}, kRays, FootprintTable::LayerCounts::Scalar);
    const std::vector<float>&a = batched.node_moments(), &b = scalar.node_moments();
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.size() % kStats, 0u);
    for (size_t i = 0; i < a.size(); ++i) {
      if (i % kStats != kLayerStat) {
        ASSERT_EQ(a[i], b[i]) << "statistic " << i % kStats << " of node " << i / kStats;
        continue;
      }
      ++nodes;
      layers_total += a[i];
      if (a[i] != b[i]) ++layer_differ;
      EXPECT_LE(std::fabs(a[i] - b[i]), 1.0f / kRays + 1e-6f) << "node " << i / kStats;
    }
  }
  std::printf("layer counts differ in %zu of %zu nodes\n", layer_differ, nodes);
  EXPECT_GT(layers_total, 0.0) << "the layer statistic was never filled";
  EXPECT_LT(double(layer_differ), 0.01 * double(nodes));
}

}  // namespace
