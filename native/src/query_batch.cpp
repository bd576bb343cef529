// KnitSurface::query_batch: vertical queries at many points, 32 or 16 at a
// time with AVX-512 or 16 or 8 at a time with AVX2, whichever the CPU has.
//
// The vertical query of query.h (knit_vertical_query) taken apart into
// stages, each run over a vector of lanes at once:
//   1. candidates: for every point, the (row, piece) pairs whose piece box
//      comes within r of the vertical line and whose quadratic interpolant's
//      chord bound does not rule it out (knit_line_query's culls, in the
//      same order), out of the few pairs the point's bin lists
//      (CandidateBins below). Lanes that pass are compressed into a list,
//      with their point's x and y, so the costly stages below run on full
//      vectors of live work and gather nothing by point.
//   2. closest points: the cubic of the piece's interpolant (Cardano or
//      Viete, as cubic.h), one Newton step on the exact curve, and whether
//      the line passes through the tube there (from the curve's Taylor
//      expansion before the step wherever its error bound leaves no doubt,
//      so the same answer as evaluating the curve again).
//   2b. per point, in row and piece order, the kernel's de-duplication: a
//      crossing found again from the next piece, or a closest point outside
//      the tube, is not searched.
//   3. entries: the safeguarded Newton search of knit_newton_extreme for the
//      entry (the maximum of z(t) + sqrt(r^2 - rho(t)^2)) on the exact curve,
//      depth signs and blends included. Each lane takes the next crossing
//      as soon as its search ends (one curve evaluation per lane per round).
//      A search writes its entry's height, normal, tangent and column
//      when it ends, from the curve evaluation it ends on; it may end one
//      short Newton step before the kernel's would, at the maximum that
//      step predicts (query_block).
//   4. per point: the layer count and the first entry, with its cell.
// A vertical line's distance to a knit or purl yarn lies in x and y, which
// do not depend on the codes (stitch.h), so stages 1-2 never read the
// pattern; the crossings take the depth signs of the three cells around
// their piece from KnitSurface::span_bits, one gather each.
//
// The same mathematics as the scalar kernel, evaluated in a different
// order and with fused multiply-adds, and entry searches that may end one
// short step sooner: results agree with query() up to float rounding and
// the searches' own tolerance, not bit for bit (tests/native/test_query_batch.cpp bounds the
// difference for both vector widths, and checks them against the
// double-precision tube ray casts). Patterns with slip stitches (codes 2,
// 3), CPUs without AVX2 and FMA, and non-x86 builds take the scalar kernel,
// point by point.
//
// The stages are written once (query_batch_stages.inc) over a small set of
// vector operations, which query_batch_avx512.inc (16 lanes, masks as bits)
// and query_batch_avx2.inc (8 lanes, masks as vectors; compress and expand
// by permutation tables) each provide over one register, and
// query_batch_pair.inc over two registers of either. The file is compiled
// for each, in its own namespace, and the CPU picks one at run time. The
// pairs (32 lanes with AVX-512, 16 with AVX2) run every stage with two
// registers side by side: the chains of dependent operations of the
// closest points and the entry searches are long, and two of them
// interleaved take 14% off the AVX-512 batch and a fifth off the AVX2 one
// on an Intel Xeon (on Zen 4 a fifth off the AVX-512 closest points, and
// 5-7% off the whole batch against pairs for the closest points alone:
// docs/geometry.md). Calls of fewer points than kWideMinAvx512
// or kWideMinAvx2 run the one-register stages, whose vectors the few points
// fill better, with the pairs' closest points; both give the same results
// bit for bit, so a point's result does not depend on how many points it
// is asked with.
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "knit/surface.h"

#if defined(__x86_64__) && defined(__GNUC__)
#define KNIT_HAVE_SIMD_PATHS 1
#include <immintrin.h>
#ifdef KNIT_QUERY_STAGE_PROFILE
#include <x86intrin.h>  // (__rdtsc: the stage clock of query_batch_stages.inc)
#include <cstdio>
#endif
#else
#define KNIT_HAVE_SIMD_PATHS 0
#endif

namespace knit {

namespace {

void query_scalar(const KnitSurface& s, const float* x, const float* y, size_t n, SurfaceHit* out) {
  for (size_t i = 0; i < n; ++i) out[i] = s.query(x[i], y[i]);
}

#if KNIT_HAVE_SIMD_PATHS

// (the instruction sets of the target pragmas below)
bool cpu_has_avx2() {
  static const bool ok =
      __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("popcnt");
  return ok;
}
bool cpu_has_avx512() {
  static const bool ok = cpu_has_avx2() && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
  return ok;
}

struct Work {
  // stage 1: candidates, in row and piece order for each point
  std::vector<int32_t> pt, row, piece;
  std::vector<float> cx, cy;  // (and the point's x and y, so that no later stage gathers them)
  // stage 2: each candidate's closest-point parameter (kBig: none within m),
  // whether the line passes through the tube there, and (stage 2b) whether
  // its entry is searched
  std::vector<float> t;
  std::vector<int32_t> inside, use;
  // stage 2c -> 3: the crossings to search, in candidate order: parameter,
  // the point's x and y, its index, span column, row (its centre follows from it), the
  // depth bits of the span's three cells (3 bits each), the row's offset in
  // codes[] and the span column's place in the pattern row
  std::vector<float> l_t, l_x, l_y;
  std::vector<int32_t> l_pt, l_cs, l_k, l_bits, l_off, l_csm;
  // stage 3: entries, in the order the lanes finish them, with their live
  // slot: whether a crossing was found, the entry distance below the shell
  // top, and the column, normal and tangent there
  std::vector<int32_t> o_slot, o_col;
  std::vector<float> o_sin, o_nx, o_ny, o_nz, o_tx, o_ty, o_tz;

  // Room for `need` candidates (and slack for the full-width stores and
  // loads past the end) in every array, keeping what is there.
  void reserve(size_t need) {
    const size_t cap = need + 32;
    if (pt.size() >= cap) return;
    for (auto* v : {&pt, &row, &piece, &inside, &use, &l_pt, &l_cs, &l_k, &l_bits, &o_slot, &o_col, &l_off, &l_csm})
      v->resize(2 * cap, 0);
    for (auto* v : {&cx, &cy, &t, &l_t, &l_x, &l_y, &o_sin, &o_nx, &o_ny, &o_nz, &o_tx, &o_ty, &o_tz})
      v->resize(2 * cap, 0.0f);
  }
};
constexpr float kBig = 1.0e30f;
constexpr int kBlock = 1024;  // points per pass through the stages
// The fewest points a call takes each path's pairs of registers for
// (below them one register is as fast or faster: BM_VerticalQueryBatchSmall)
constexpr int kWideMinAvx512 = 128;
constexpr int kWideMinAvx2 = 32;

// The x and y of the quadratic interpolant of piece place j (0..7) of a
// knit or purl row, in double: q0 + q1 u + q2 u^2 for u in [0, 1] through
// the curve's nodes m = 2j, 2j+1, 2j+2 at tau = m pi/8 - pi, relative to
// the piece's start t0 = tc + (j pi/4 - pi) in x and to the row's centre
// y_k in y. q = {q0x, q0y, q1x, q1y, q2x, q2y}.
void piece_interpolant_xy(double a, double h, int j, double q[6]) {
  double nx[3], ny[3];
  for (int i = 0; i < 3; ++i) {
    const double tau = (2 * j + i) * (M_PI / 8) - M_PI;
    nx[i] = (tau - (j * (M_PI / 4) - M_PI)) + a * std::sin(2 * tau);
    ny[i] = h * std::cos(tau);
  }
  q[0] = nx[0];
  q[1] = ny[0];
  q[2] = 4 * nx[1] - 3 * nx[0] - nx[2];
  q[3] = 4 * ny[1] - 3 * ny[0] - ny[2];
  q[4] = 2 * (nx[0] - 2 * nx[1] + nx[2]);
  q[5] = 2 * (ny[0] - 2 * ny[1] + ny[2]);
}

// The per-surface constants of the batched query (pattern-independent: the
// x and y of knit and purl yarns) as plain floats, per piece place j = 0..7
// (16 a table, the rest zero), from which each instruction set makes its
// vectors (make_consts, query_batch_stages.inc): the pieces' xy box offsets
// (knit_piece_offsets_xy), the xy interpolant relative to (t0, y_k), its
// chord q1 + q2, 1 / |chord|^2 (0 if none), |q2| / 4, and the unit vector
// along q2's part across the chord (0 if none; knit_quad_beyond's
// `across`). They depend on a and h alone and are kept per thread for the
// next call with the same ones, one copy for every instruction set (the
// 32-lane closest points' included): 24 double-precision sines and cosines
// are a third of the time of a call with one point.
struct PieceTables {
  alignas(64) float oxl[16], oxh[16], oyl[16], oyh[16];
  alignas(64) float q0x[16], q0y[16], q1x[16], q1y[16], q2x[16], q2y[16];
  alignas(64) float cx[16], cy[16], il2[16], hq2[16], acx[16], acy[16];
};

const PieceTables& piece_tables(const k::KnitGeom& g) {
  static thread_local float pt_a = 0.0f, pt_h = 0.0f;
  static thread_local PieceTables t;
  if (pt_a == g.a && pt_h == g.h) return t;
  t = PieceTables{};
  for (int j = 0; j < 8; ++j) {
    const k::KBox o = k::knit_piece_offsets_xy(g, j);
    t.oxl[j] = o.lo.x;
    t.oxh[j] = o.hi.x;
    t.oyl[j] = o.lo.y;
    t.oyh[j] = o.hi.y;
    double q[6];
    piece_interpolant_xy(g.a, g.h, j, q);
    t.q0x[j] = float(q[0]);
    t.q0y[j] = float(q[1]);
    t.q1x[j] = float(q[2]);
    t.q1y[j] = float(q[3]);
    t.q2x[j] = float(q[4]);
    t.q2y[j] = float(q[5]);
    t.cx[j] = t.q1x[j] + t.q2x[j];
    t.cy[j] = t.q1y[j] + t.q2y[j];
    const float l2 = t.cx[j] * t.cx[j] + t.cy[j] * t.cy[j];
    t.il2[j] = l2 > 0.0f ? 1.0f / l2 : 0.0f;
    t.hq2[j] = 0.25f * std::sqrt(t.q2x[j] * t.q2x[j] + t.q2y[j] * t.q2y[j]);
    const double along = double(t.q2x[j] * t.cx[j] + t.q2y[j] * t.cy[j]) * t.il2[j];
    const double ax = t.q2x[j] - along * t.cx[j], ay = t.q2y[j] - along * t.cy[j];
    const double la = std::sqrt(ax * ax + ay * ay);
    t.acx[j] = la > 0 ? float(ax / la) : 0.0f;
    t.acy[j] = la > 0 ? float(ay / la) : 0.0f;
  }
  pt_a = g.a;
  pt_h = g.h;
  return t;
}

// Stage 1's candidates by where a point lies in its stitch cell. Which
// (row, piece) pairs can come near a vertical line depends on the line's
// place within one period of the geometry (2 pi in x, a row spacing s in
// y) and on a, h, d and r, not on the pattern (x and y of knit and purl
// yarns are the same). The period is cut into kBinsX x kBinsY bins; each
// bin lists, as bits, the pairs (row offset, piece offset from the cell's
// first piece) that pass stage 1's box and chord culls and come within the
// closest-point threshold r + quad_margin_xy of the piece's quadratic
// interpolant, for some point of the bin. The tests are made at the bin's
// centre with the bin's half-extent (and 0.01 for float rounding) added to
// every distance, so the list is a superset of the pairs any point in the
// bin keeps: the pairs left out are ones stage 2 would have set aside
// (farther than the threshold), and results are the same as stage 1
// without the bins. A bin's bits are row-major, 2^shift bits per row, from
// its own first row and piece (base), so the pairs come out in the row and
// piece order stage 2b relies on. Built once per a, h, d, r (on each
// thread, candidate_bins below): about 0.3 ms.
struct CandidateBins {
  static constexpr int kBinsX = 32, kBinsY = 16;
  bool ok = false;  // false: some bin needs more than 32 bits (stage 1 tests the whole box)
  int shift = 0;
  std::vector<int32_t> bits, base;  // per bin (iy * kBinsX + ix): pairs, and (first row << 16) | (first piece & 0xFFFF)
};

// Lower bound of the distance from p to the quadratic q0 + q1 u + q2 u^2
// over u in [0, 1], given speed >= |q'| = |q1 + 2 q2 u|: the nearest of
// n + 1 evenly spaced points less half the gap between neighbours. A
// first bound from its chord q0 + (q1 + q2) u, which the quadratic leaves
// by at most |q2| / 4.
double quad_distance_lower(double px, double py, const double q[6], double speed, int n) {
  const double ax = px - q[0], ay = py - q[1], cx = q[2] + q[4], cy = q[3] + q[5];
  const double l2 = cx * cx + cy * cy;
  const double u = l2 > 0 ? std::min(1.0, std::max(0.0, (ax * cx + ay * cy) / l2)) : 0.0;
  const double chord = std::hypot(ax - u * cx, ay - u * cy) - 0.25 * std::hypot(q[4], q[5]);
  if (n <= 0) return chord;
  double best = 1e300;
  for (int i = 0; i <= n; ++i) {
    const double v = double(i) / n;
    const double x = q[0] + (q[2] + q[4] * v) * v - px, y = q[1] + (q[3] + q[5] * v) * v - py;
    best = std::min(best, x * x + y * y);
  }
  return std::max(chord, std::sqrt(best) - 0.5 * speed / n);
}

CandidateBins build_candidate_bins(const k::KnitGeom& g) {
  CandidateBins cb;
  const double pi4 = M_PI / 4, s = g.row_spacing, a = g.a, h = g.h;
  const double rr = double(g.r) * 1.001 + 1.0e-4;  // stage 1's box reach
  // stage 1's chord reach, larger than stage 2's threshold r + quad_margin_xy
  const double thr = (double(g.r) + g.quad_margin_xy) * 1.001 + 1.0e-4;
  const double bw = 2 * M_PI / CandidateBins::kBinsX, bh = s / CandidateBins::kBinsY;
  const double hx = 0.5 * bw, hy = 0.5 * bh, hd = std::hypot(hx, hy), eps = 0.01;
  // every pair any point of the cell could reach
  const int dk_lo = int(std::floor((-h - rr) / s - 0.5)) - 1, dk_hi = int(std::ceil((s + h + rr) / s - 0.5)) + 1;
  const int dg_lo = int(std::floor((-rr - a) / pi4)) - 1, dg_hi = int(std::ceil((2 * M_PI + rr + a) / pi4)) + 1;
  // Loops this wide (a above about 20) reach more pieces from one bin than
  // 32 bits hold: no bins, and no time spent finding that out (a = 1000
  // took 0.1 s).
  if (dg_hi - dg_lo + 1 > 64 || dk_hi - dk_lo + 1 > 16) return cb;
  // per piece place j: box offsets and interpolant (make_consts's, in double)
  struct Place {
    double oxl, oxh, oyl, oyh, q[6], speed;
  } pl[8];
  for (int j = 0; j < 8; ++j) {
    const k::KBox o = k::knit_piece_offsets_xy(g, j);
    Place& P = pl[j];
    P.oxl = o.lo.x;
    P.oxh = o.hi.x;
    P.oyl = o.lo.y;
    P.oyh = o.hi.y;
    piece_interpolant_xy(a, h, j, P.q);
    P.speed = std::hypot(P.q[2], P.q[3]) + 2.0 * std::hypot(P.q[4], P.q[5]);
  }
  const double reach = thr + hd + eps;  // (the interpolant's, grown by the bin's half-extent)
  struct Pair {
    int dk, dg;
  };
  std::vector<std::vector<Pair>> lists(size_t(CandidateBins::kBinsX * CandidateBins::kBinsY));
  std::vector<int> first_g(lists.size(), 0);  // each bin's lowest piece offset
  int span_k = 1, span_g = 1;
  for (int iy = 0; iy < CandidateBins::kBinsY; ++iy)
    for (int ix = 0; ix < CandidateBins::kBinsX; ++ix) {
      const double xc = (ix + 0.5) * bw, yc = (iy + 0.5) * bh;
      auto& L = lists[size_t(iy * CandidateBins::kBinsX + ix)];
      for (int dk = dk_lo; dk <= dk_hi; ++dk) {
        const double yk = (dk + 0.5) * s;
        for (int dg = dg_lo; dg <= dg_hi; ++dg) {
          const int j = dg & 7;
          const Place& P = pl[j];
          const double t0 = dg * pi4;
          // the box, grown by the bin's half-extent
          if (xc + hx < t0 + P.oxl - rr - eps || xc - hx > t0 + pi4 + P.oxh + rr + eps) continue;
          if (yc + hy < yk + P.oyl - rr - eps || yc - hy > yk + P.oyh + rr + eps) continue;
          // the interpolant within the threshold (which also bounds the
          // chord test): a coarse bound first, most pairs in the box being
          // far from it
          if (quad_distance_lower(xc - t0, yc - yk, P.q, P.speed, 0) > reach) continue;
          if (quad_distance_lower(xc - t0, yc - yk, P.q, P.speed, 32) > reach) continue;
          L.push_back({dk, dg});
        }
      }
      if (L.empty()) continue;
      int klo = L.front().dk, khi = L.back().dk, glo = L.front().dg, ghi = L.front().dg;
      for (const Pair& p : L) {
        glo = std::min(glo, p.dg);
        ghi = std::max(ghi, p.dg);
      }
      span_k = std::max(span_k, khi - klo + 1);
      span_g = std::max(span_g, ghi - glo + 1);
      first_g[size_t(iy * CandidateBins::kBinsX + ix)] = glo;
    }
  int shift = 0;
  while ((1 << shift) < span_g) ++shift;
  if ((span_k << shift) > 32) return cb;  // (very wide loops: no bins)
  cb.shift = shift;
  cb.bits.assign(lists.size() + 16, 0);  // (slack: a gather never reads past it, but keep the tail defined)
  cb.base.assign(lists.size() + 16, 0);
  for (size_t b = 0; b < lists.size(); ++b) {
    const auto& L = lists[b];
    if (L.empty()) continue;
    const int klo = L.front().dk, glo = first_g[b];
    uint32_t bits = 0;
    for (const Pair& p : L) bits |= 1u << (((p.dk - klo) << shift) + (p.dg - glo));
    cb.bits[b] = int32_t(bits);
    cb.base[b] = int32_t((uint32_t(klo) << 16) | (uint32_t(glo) & 0xFFFFu));
  }
  cb.ok = true;
  return cb;
}

// The bins of the stitch g (a, h, d and r): the last four stitches seen on
// this thread are kept, so calls alternating between surfaces do not build
// them again.
const CandidateBins& candidate_bins(const k::KnitGeom& g) {
  struct Slot {
    float a = 0, h = 0, d = 0, r = 0;  // (a = 0: empty; no valid stitch has it)
    CandidateBins bins;
  };
  static thread_local Slot slots[4];
  static thread_local int next = 0;
  for (Slot& sl : slots)
    if (sl.a == g.a && sl.h == g.h && sl.d == g.d && sl.r == g.r) return sl.bins;
  Slot& sl = slots[next];
  next = (next + 1) % 4;
  sl.bins = build_candidate_bins(g);
  sl.a = g.a;
  sl.h = g.h;
  sl.d = g.d;
  sl.r = g.r;
  return sl.bins;
}

// GCC 12 reports the deliberately undefined first operand of its own
// AVX-512 intrinsics (_mm512_undefined_ps) as uninitialised once inlined.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

// Each instruction set's functions are compiled for it alone: GCC's target
// pragma, or for clang (the fuzzing build, scripts/fuzz.sh) its attribute
// pragma, which gives every function declared in the region the target.
#if defined(__clang__)
#define KNIT_TARGET_BEGIN(isa) _Pragma(KNIT_TARGET_STR(clang attribute push(__attribute__((target(isa))), apply_to = function)))
#define KNIT_TARGET_END _Pragma("clang attribute pop")
#else
#define KNIT_TARGET_BEGIN(isa) _Pragma("GCC push_options") _Pragma(KNIT_TARGET_STR(GCC target(isa)))
#define KNIT_TARGET_END _Pragma("GCC pop_options")
#endif
#define KNIT_TARGET_STR(x) #x

// Each instruction set's one-register operations, then the stages over
// pairs of registers (query_batch_pair.inc on top of them), then over one
// register, with the pairs' closest points.
#define KNIT_AVX512_TARGET "avx512f,avx512dq,fma,avx2,bmi,bmi2,popcnt"
#define KNIT_AVX2_TARGET "avx2,fma,popcnt"
namespace avx512 {
KNIT_TARGET_BEGIN(KNIT_AVX512_TARGET)
#include "query_batch_avx512.inc"
KNIT_TARGET_END
}  // namespace avx512

namespace avx2 {
KNIT_TARGET_BEGIN(KNIT_AVX2_TARGET)
#include "query_batch_avx2.inc"
KNIT_TARGET_END
}  // namespace avx2

// The stages over 32 lanes (two AVX-512 registers) and over 16 (two AVX2
// registers).
namespace avx512x2 {
KNIT_TARGET_BEGIN(KNIT_AVX512_TARGET)
namespace one = avx512;
#include "query_batch_pair.inc"
#include "query_batch_stages.inc"
KNIT_TARGET_END
}  // namespace avx512x2

namespace avx2x2 {
KNIT_TARGET_BEGIN(KNIT_AVX2_TARGET)
namespace one = avx2;
#include "query_batch_pair.inc"
#include "query_batch_stages.inc"
KNIT_TARGET_END
}  // namespace avx2x2

// The stages over one register, for calls of fewer than kWideMinAvx512 or
// kWideMinAvx2 points.
namespace avx512 {
KNIT_TARGET_BEGIN(KNIT_AVX512_TARGET)
#define KNIT_CLOSEST_POINTS_WIDE avx512x2::closest_points_wide
#include "query_batch_stages.inc"
#undef KNIT_CLOSEST_POINTS_WIDE
KNIT_TARGET_END
}  // namespace avx512

namespace avx2 {
KNIT_TARGET_BEGIN(KNIT_AVX2_TARGET)
#define KNIT_CLOSEST_POINTS_WIDE avx2x2::closest_points_wide
#include "query_batch_stages.inc"
#undef KNIT_CLOSEST_POINTS_WIDE
KNIT_TARGET_END
}  // namespace avx2

#pragma GCC diagnostic pop

#endif  // KNIT_HAVE_SIMD_PATHS

}  // namespace

const char* KnitSurface::batch_isa_name(BatchIsa isa) {
  switch (isa) {
    case BatchIsa::Avx512:
      return "avx512";
    case BatchIsa::Avx2:
      return "avx2";
    default:
      return "scalar";
  }
}

KnitSurface::BatchIsa KnitSurface::batch_best_isa() {
#if KNIT_HAVE_SIMD_PATHS
  if (cpu_has_avx512()) return BatchIsa::Avx512;
  if (cpu_has_avx2()) return BatchIsa::Avx2;
#endif
  return BatchIsa::Scalar;
}

bool KnitSurface::batch_simd_available() { return batch_best_isa() != BatchIsa::Scalar; }

KnitSurface::BatchIsa KnitSurface::batch_isa(BatchPath path) const {
  if (path == BatchPath::Scalar) return BatchIsa::Scalar;
  const BatchIsa best = batch_best_isa();
  const bool loops_only = geom_.has_floats == 0 && !span_bits_.empty();
  if (path == BatchPath::Auto) return loops_only ? best : BatchIsa::Scalar;
  if (!loops_only)
    throw std::invalid_argument(
        "query_batch: the SIMD paths take knit and purl stitches only (this pattern has slip stitches)");
  if (best == BatchIsa::Scalar)
    throw std::invalid_argument("query_batch: this CPU has neither AVX-512 nor AVX2 with FMA (or the build is not "
                                "x86-64)");
  // (a CPU with AVX-512 has AVX2)
  return path == BatchPath::Avx2 ? BatchIsa::Avx2 : best;
}

void KnitSurface::query_batch(const float* x, const float* y, size_t n, SurfaceHit* out, BatchPath path) const {
  if (n == 0) return;
  if (!x || !y || !out) throw std::invalid_argument("query_batch: null array");
  const BatchIsa isa = batch_isa(path);
#if KNIT_HAVE_SIMD_PATHS
  if (isa == BatchIsa::Avx512) {
    if (n >= size_t(kWideMinAvx512))
      avx512x2::query_all(*this, x, y, n, out);
    else
      avx512::query_all(*this, x, y, n, out);
    return;
  }
  if (isa == BatchIsa::Avx2) {
    if (n >= size_t(kWideMinAvx2))
      avx2x2::query_all(*this, x, y, n, out);
    else
      avx2::query_all(*this, x, y, n, out);
    return;
  }
#else
  (void)isa;
#endif
  query_scalar(*this, x, y, n, out);
}

}  // namespace knit
