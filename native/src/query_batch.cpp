// KnitSurface::query_batch: vertical queries at many points, 16 at a time
// with AVX-512 or 8 at a time with AVX2, whichever the CPU has.
//
// The vertical query of query.h (knit_vertical_query) taken apart into
// stages, each run over a vector of lanes at once:
//   1. candidates: for every point, the (row, piece) pairs whose piece box
//      comes within r of the vertical line and whose quadratic interpolant's
//      chord bound does not rule it out (knit_line_query's culls, in the
//      same order). Lanes that pass are compressed into a list, so the
//      costly stages below run on full vectors of live work.
//   2. closest points: the cubic of the piece's interpolant (Cardano or
//      Viete, as cubic.h), one Newton step on the exact curve, and whether
//      the line passes through the tube there.
//   2b. per point, in row and piece order, the kernel's de-duplication: a
//      crossing found again from the next piece, or a closest point outside
//      the tube, is not searched.
//   3. entries: the safeguarded Newton search of knit_newton_extreme for the
//      entry (the maximum of z(t) + sqrt(r^2 - rho(t)^2)) on the exact curve,
//      depth signs and blends included. Each lane takes the next crossing
//      as soon as its search ends (one curve evaluation per lane per round).
//   4. per point: the layer count and the first entry.
//   5. each point's first entry evaluated again at its final parameter:
//      position, normal, tangent and cell.
// A vertical line's distance to a knit or purl yarn lies in x and y, which
// do not depend on the codes (stitch.h), so stages 1-2 never read the
// pattern; the crossings take the depth signs of the three cells around
// their piece from KnitSurface::span_bits, one gather each.
//
// The same mathematics as the scalar kernel, evaluated in a different
// order and with fused multiply-adds: results agree with query() up to float
// rounding, not bit for bit (tests/native/test_query_batch.cpp bounds the
// difference for both vector widths, and checks them against the
// double-precision tube ray casts). Patterns with slip stitches (codes 2,
// 3), CPUs without AVX2 and FMA, and non-x86 builds take the scalar kernel,
// point by point.
//
// The stages are written once (query_batch_stages.inc) over a small set of
// vector operations, which query_batch_avx512.inc (16 lanes, masks as bits)
// and query_batch_avx2.inc (8 lanes, masks as vectors; compress and expand
// by permutation tables) each provide; the file is compiled once per
// instruction set, in its own namespace, and the CPU picks one at run time.
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
  // stage 2: each candidate's closest-point parameter (kBig: none within m),
  // whether the line passes through the tube there, and (stage 2b) whether
  // its entry is searched
  std::vector<float> t;
  std::vector<int32_t> inside, use;
  // stage 2c -> 3: the crossings to search, in candidate order: candidate,
  // parameter, point, row centre, span column, row and the depth bits of
  // the span's three cells (3 bits each)
  std::vector<float> l_t, l_x, l_y, l_yk;
  std::vector<int32_t> l_c, l_cs, l_k, l_bits;
  // stage 3: entries, in the order the lanes finish them, with their live slot
  std::vector<int32_t> o_slot, o_hit;
  std::vector<float> o_sin, o_t;
  // stage 5: the entry each point keeps (by point, in point order)
  std::vector<int32_t> b_pt, b_o, b_row, b_col, b_code, b_colour;
  std::vector<float> b_pz, b_nx, b_ny, b_nz, b_tx, b_ty, b_tz;
  std::vector<int32_t> pos_of;  // live slot -> index in the o_ arrays

  // Room for `need` candidates (and slack for the full-width stores and
  // loads past the end) in every array, keeping what is there.
  void reserve(size_t need) {
    const size_t cap = need + 32;
    if (pt.size() >= cap) return;
    for (auto* v : {&pt, &row, &piece, &inside, &use, &l_c, &l_cs, &l_k, &l_bits, &o_slot, &o_hit, &pos_of, &b_pt,
                    &b_o, &b_row, &b_col, &b_code, &b_colour})
      v->resize(2 * cap, 0);
    for (auto* v : {&t, &l_t, &l_x, &l_y, &l_yk, &o_sin, &o_t, &b_pz, &b_nx, &b_ny, &b_nz, &b_tx, &b_ty, &b_tz})
      v->resize(2 * cap, 0.0f);
  }
};
constexpr float kBig = 1.0e30f;
constexpr int kBlock = 1024;  // points per pass through the stages

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

namespace avx512 {
KNIT_TARGET_BEGIN("avx512f,avx512dq,fma,avx2,bmi,bmi2,popcnt")
#include "query_batch_avx512.inc"
#include "query_batch_stages.inc"
KNIT_TARGET_END
}  // namespace avx512

namespace avx2 {
KNIT_TARGET_BEGIN("avx2,fma,popcnt")
#include "query_batch_avx2.inc"
#include "query_batch_stages.inc"
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
    avx512::query_all(*this, x, y, n, out);
    return;
  }
  if (isa == BatchIsa::Avx2) {
    avx2::query_all(*this, x, y, n, out);
    return;
  }
#else
  (void)isa;
#endif
  query_scalar(*this, x, y, n, out);
}

}  // namespace knit
