// KnitSurface::query_batch: vertical queries at many points, 16 at a time
// with AVX-512 where the CPU has it.
//
// The vertical query of query.h (knit_vertical_query) taken apart into
// stages, each run over 16 lanes at once:
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
// difference, and checks both against the double-precision tube ray casts).
// Patterns with slip stitches (codes 2, 3), machines without AVX-512 and
// non-x86 builds take the scalar kernel, point by point.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "knit/surface.h"

#if defined(__x86_64__) && defined(__GNUC__)
#define KNIT_HAVE_AVX512_PATH 1
#include <immintrin.h>
#else
#define KNIT_HAVE_AVX512_PATH 0
#endif

namespace knit {

namespace {

void query_scalar(const KnitSurface& s, const float* x, const float* y, size_t n, SurfaceHit* out) {
  for (size_t i = 0; i < n; ++i) out[i] = s.query(x[i], y[i]);
}

#if KNIT_HAVE_AVX512_PATH

bool cpu_has_avx512() {
  // (the instruction sets of the target pragma below)
  static const bool ok = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
                         __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                         __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
  return ok;
}

#pragma GCC push_options
#pragma GCC target("avx512f,avx512dq,fma,avx2,bmi,bmi2")
// GCC 12 reports the deliberately undefined first operand of its own
// AVX-512 intrinsics (_mm512_undefined_ps) as uninitialised once inlined.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

// 16 floats, 16 ints and a lane mask, with the operators the stages need.
struct F {
  __m512 v;
};
struct I {
  __m512i v;
};
using M = __mmask16;

inline F fv(float a) { return {_mm512_set1_ps(a)}; }
inline I iv(int a) { return {_mm512_set1_epi32(a)}; }
inline F operator+(F a, F b) { return {_mm512_add_ps(a.v, b.v)}; }
inline F operator-(F a, F b) { return {_mm512_sub_ps(a.v, b.v)}; }
inline F operator*(F a, F b) { return {_mm512_mul_ps(a.v, b.v)}; }
inline F operator/(F a, F b) { return {_mm512_div_ps(a.v, b.v)}; }
inline F operator-(F a) { return {_mm512_xor_ps(a.v, _mm512_set1_ps(-0.0f))}; }
inline I operator+(I a, I b) { return {_mm512_add_epi32(a.v, b.v)}; }
inline I operator-(I a, I b) { return {_mm512_sub_epi32(a.v, b.v)}; }
inline I operator*(I a, I b) { return {_mm512_mullo_epi32(a.v, b.v)}; }
inline I operator&(I a, I b) { return {_mm512_and_si512(a.v, b.v)}; }
inline M lt(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ); }
inline M le(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ); }
inline M gt(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ); }
inline M ge(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ); }
inline M eq(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ); }
inline M ne(F a, F b) { return _mm512_cmp_ps_mask(a.v, b.v, _CMP_NEQ_UQ); }
inline M ilt(I a, I b) { return _mm512_cmplt_epi32_mask(a.v, b.v); }
inline M igt(I a, I b) { return _mm512_cmpgt_epi32_mask(a.v, b.v); }
inline M ieq(I a, I b) { return _mm512_cmpeq_epi32_mask(a.v, b.v); }
inline M ile(I a, I b) { return _mm512_cmple_epi32_mask(a.v, b.v); }
// m ? a : b, lane by lane
inline F sel(M m, F a, F b) { return {_mm512_mask_blend_ps(m, b.v, a.v)}; }
inline I sel(M m, I a, I b) { return {_mm512_mask_blend_epi32(m, b.v, a.v)}; }
inline F vmin(F a, F b) { return {_mm512_min_ps(a.v, b.v)}; }
inline F vmax(F a, F b) { return {_mm512_max_ps(a.v, b.v)}; }
inline F clampv(F x, F lo, F hi) { return vmin(vmax(x, lo), hi); }
inline F vabs(F a) { return {_mm512_abs_ps(a.v)}; }
inline F vsqrt(F a) { return {_mm512_sqrt_ps(a.v)}; }
inline F vfloor(F a) { return {_mm512_roundscale_ps(a.v, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC)}; }
inline F vceil(F a) { return {_mm512_roundscale_ps(a.v, _MM_FROUND_TO_POS_INF | _MM_FROUND_NO_EXC)}; }
inline F tof(I a) { return {_mm512_cvtepi32_ps(a.v)}; }
inline I toi_trunc(F a) { return {_mm512_cvttps_epi32(a.v)}; }
inline F sgn1(F a) { return sel(lt(a, fv(0.0f)), fv(-1.0f), fv(1.0f)); }  // k_signf
// table[j] for j in 0..15 (a 16-entry table held in a register)
inline F lookup(const F& table, I j) { return {_mm512_permutexvar_ps(j.v, table.v)}; }
inline F gather(const float* base, I idx, M m) {
  return {_mm512_mask_i32gather_ps(_mm512_setzero_ps(), m, idx.v, base, 4)};
}
inline I gather(const int32_t* base, I idx, M m) {
  return {_mm512_mask_i32gather_epi32(_mm512_setzero_si512(), m, idx.v, base, 4)};
}
inline F load(const float* p) { return {_mm512_loadu_ps(p)}; }
inline void store(float* p, F a) { _mm512_storeu_ps(p, a.v); }
inline void store(int32_t* p, I a) { _mm512_storeu_si512(p, a.v); }
inline void compress_store(float* p, M m, F a) { _mm512_storeu_ps(p, _mm512_maskz_compress_ps(m, a.v)); }
// The lanes of a selected by m, packed to the front, stored at p (16 ints
// are written: p needs 16 of room). A compress in a register and a plain
// store: the compress-to-memory instruction is microcoded and slow on some
// CPUs (AMD Zen 4 among them).
inline void compress_store(int32_t* p, M m, I a) { _mm512_storeu_si512(p, _mm512_maskz_compress_epi32(m, a.v)); }
// Floor-modulo (k_modi) for |a| < 2^23 and 0 < n < 2^23 (exact: the float
// quotient is corrected by one either way).
inline I modi(I a, int n) {
  const F fa = tof(a), fn = fv(float(n));
  I q = toi_trunc(vfloor(fa / fn));
  I r = a - q * iv(n);
  r = sel(ilt(r, iv(0)), r + iv(n), r);
  r = sel(igt(r, iv(n - 1)), r - iv(n), r);
  return r;
}
inline I ifloor(F a) { return toi_trunc(vfloor(a)); }
// The first min(left, 16) lanes.
inline M tail_mask(int left) { return M(left >= 16 ? 0xFFFF : (1u << left) - 1u); }
// Lane numbers plus base: base, base + 1, ..., base + 15.
inline I lane_index(int base) {
  return {_mm512_add_epi32(_mm512_set_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0),
                           _mm512_set1_epi32(base))};
}

// The Taylor polynomials of sin and cos to y^9 and y^10 (knit_sincos's):
// truncation below 2e-9 on [-pi/4, pi/4], below 4e-8 on [0, pi/3].
inline void sincos_taylor(F y, F& s, F& c) {
  const F y2 = y * y;
  s = y + y * y2 *
              (fv(-1.0f / 6.0f) +
               y2 * (fv(1.0f / 120.0f) + y2 * (fv(-1.0f / 5040.0f) + y2 * fv(1.0f / 362880.0f))));
  c = fv(1.0f) +
      y2 * (fv(-0.5f) +
            y2 * (fv(1.0f / 24.0f) +
                  y2 * (fv(-1.0f / 720.0f) + y2 * (fv(1.0f / 40320.0f) + y2 * fv(-1.0f / 3628800.0f)))));
}

// knit_sincos, lane by lane (the same reduction and polynomials).
inline void sincos_v(F x, F& s_out, F& c_out) {
  const F qf = tof(toi_trunc(x * fv(0.63661977236758134308f) + sel(ge(x, fv(0.0f)), fv(0.5f), fv(-0.5f))));
  const F y = ((x - qf * fv(1.5703125f)) - qf * fv(4.837512969970703125e-4f)) - qf * fv(7.549789954891882e-8f);
  F s, c;
  sincos_taylor(y, s, c);
  const I n = toi_trunc(qf) & iv(3);
  const M q1 = ieq(n, iv(1)), q2 = ieq(n, iv(2)), q3 = ieq(n, iv(3));
  s_out = sel(q1, c, sel(q2, -s, sel(q3, -c, s)));
  c_out = sel(q1, -s, sel(q2, -c, sel(q3, s, c)));
}

// acos on [-1, 1]: sqrt(1 - |x|) times a degree-7 polynomial in |x|
// (Abramowitz and Stegun 4.4.46, |error| <= 2e-8), reflected for x < 0.
inline F acos_v(F x) {
  const F ax = vabs(x);
  const F p =
      fv(1.5707963050f) +
      ax * (fv(-0.2145988016f) +
            ax * (fv(0.0889789874f) +
                  ax * (fv(-0.0501743046f) +
                        ax * (fv(0.0308918810f) +
                              ax * (fv(-0.0170881256f) + ax * (fv(0.0066700901f) + ax * fv(-0.0012624911f)))))));
  const F r = vsqrt(vmax(fv(1.0f) - ax, fv(0.0f))) * p;
  return sel(lt(x, fv(0.0f)), fv(3.14159265358979f) - r, r);
}

// Cube root: a first guess from the bits and three Newton steps
// (knit_host_cbrt's method); 0 stays 0.
inline F cbrt_v(F x) {
  const F ax = vabs(x);
  const M pos = gt(ax, fv(1.0e-30f));
  const F axs = sel(pos, ax, fv(1.0f));
  const __m512i bits = _mm512_castps_si512(axs.v);
  // i / 3 + 709921077 with the division in float (close enough for a guess)
  const __m512i third = _mm512_cvttps_epi32(_mm512_mul_ps(_mm512_cvtepu32_ps(bits), _mm512_set1_ps(1.0f / 3.0f)));
  F y = {_mm512_castsi512_ps(_mm512_add_epi32(third, _mm512_set1_epi32(709921077)))};
  for (int it = 0; it < 3; ++it) y = y - (y * y * y - axs) / (fv(3.0f) * y * y);
  y = sel(pos, y, fv(0.0f));
  return sel(lt(x, fv(0.0f)), -y, y);
}

inline F cubic_newton_v(F a3, F a2, F a1, F a0, F x) {
  const F f = ((a3 * x + a2) * x + a1) * x + a0;
  const F df = (fv(3.0f) * a3 * x + fv(2.0f) * a2) * x + a1;
  const F nx = x - f / df;
  const M ok = ne(df, fv(0.0f)) & _mm512_cmp_ps_mask(nx.v, nx.v, _CMP_ORD_Q) & lt(vabs(nx), fv(1.0e30f));
  return sel(ok, nx, x);
}

// Real roots of a3 x^3 + a2 x^2 + a1 x + a0 (solve_cubic and
// solve_quadratic, every branch evaluated and the lane's one kept): roots
// r0..r2 with n of them valid, in ascending order.
inline void solve_cubic_v(F a3, F a2, F a1, F a0, M m, F& r0, F& r1, F& r2, I& nroots) {
  const F big = fv(1.0e30f);
  const F scale = vmax(vmax(vabs(a2), vabs(a1)), vabs(a0));
  const M quad = m & (le(vabs(a3), fv(1.0e-6f) * scale) | eq(a3, fv(0.0f)));
  // cubic branch (each case only when a lane takes it)
  const F a3s = sel(quad, fv(1.0f), a3);
  const F inv3 = fv(1.0f) / a3s;
  const F b = a2 * inv3, c = a1 * inv3, d = a0 * inv3;
  const F b3 = b * fv(1.0f / 3.0f);
  const F p = c - b * b3;
  const F q = fv(2.0f) * b3 * b3 * b3 - b3 * c + d;
  const F hq = fv(0.5f) * q;
  const F tp = p * fv(1.0f / 3.0f);
  const F disc = hq * hq + tp * tp * tp;
  const M one = gt(disc, fv(0.0f));
  const M triple = ~one & eq(tp, fv(0.0f));
  const M three = m & ~quad & ~one & ~triple;
  F c0 = -b3, c1 = big, c2 = big;  // the triple root
  if (m & ~quad & one) {
    const F A = -sgn1(q) * cbrt_v(vabs(hq) + vsqrt(vmax(disc, fv(0.0f))));
    const F Bc = sel(ne(A, fv(0.0f)), -tp / sel(ne(A, fv(0.0f)), A, fv(1.0f)), fv(0.0f));
    c0 = sel(one, A + Bc - b3, c0);
  }
  if (three) {
    const F mm = fv(2.0f) * vsqrt(vmax(-tp, fv(0.0f)));
    const F den = p * mm;
    const F phi = acos_v(clampv(fv(3.0f) * q / sel(ne(den, fv(0.0f)), den, fv(1.0f)), fv(-1.0f), fv(1.0f))) *
                  fv(1.0f / 3.0f);
    // phi in [0, pi/3]: sin and cos by the polynomials directly, without
    // the quadrant reduction
    F sp, cp;
    sincos_taylor(phi, sp, cp);
    const F hc = fv(-0.5f) * cp, hs = fv(0.86602540378443864676f) * sp;
    c0 = sel(three, mm * cp - b3, c0);
    c1 = cubic_newton_v(a3s, a2, a1, a0, mm * (hc + hs) - b3);
    c2 = cubic_newton_v(a3s, a2, a1, a0, mm * (hc - hs) - b3);
  }
  c0 = cubic_newton_v(a3s, a2, a1, a0, c0);
  // cubic roots sorted (three) or the one
  const F s0 = vmin(vmin(c0, c1), c2), s2 = vmax(vmax(c0, c1), c2);
  const F s1 = vmax(vmin(c0, c1), vmin(vmax(c0, c1), c2));
  r0 = sel(three, s0, c0);
  r1 = sel(three, s1, big);
  r2 = sel(three, s2, big);
  nroots = sel(three, iv(3), iv(1));
  if (quad) {  // a2 x^2 + a1 x + a0 (solve_quadratic)
    const M qnone = eq(scale, fv(0.0f));
    const M lin = le(vabs(a2), fv(1.0e-7f) * scale);
    const F qdisc = a1 * a1 - fv(4.0f) * a2 * a0;
    const F qq = fv(-0.5f) * (a1 + sgn1(a1) * vsqrt(vmax(qdisc, fv(0.0f))));
    const M qzero = eq(qq, fv(0.0f));
    const F qr0 = qq / sel(lin, fv(1.0f), a2);
    const F qr1 = a0 / sel(qzero, fv(1.0f), qq);
    const F lr = -a0 / sel(eq(a1, fv(0.0f)), fv(1.0f), a1);
    const I nq = sel(qnone, iv(0),
                     sel(lin, sel(eq(a1, fv(0.0f)), iv(0), iv(1)),
                         sel(lt(qdisc, fv(0.0f)), iv(0), sel(qzero, iv(1), iv(2)))));
    r0 = sel(quad, sel(lin, lr, sel(qzero, fv(0.0f), vmin(qr0, qr1))), r0);
    r1 = sel(quad, vmax(qr0, qr1), r1);
    r2 = sel(quad, big, r2);
    nroots = sel(quad, nq, nroots);
  }
}

// Per-surface constants of the batched query (pattern-independent: the
// x and y of knit and purl yarns), per piece place j = 0..7 in its cell.
struct BatchConsts {
  F oxl, oxh, oyl, oyh;     // knit_piece_offsets_xy
  F q0x, q0y, q1x, q1y, q2x, q2y;  // interpolant relative to (t0, y_k)
  F cx, cy, il2, hq2;       // its chord q1 + q2, 1 / |chord|^2 (0 if none), |q2| / 4
};

BatchConsts make_consts(const k::KnitGeom& g) {
  alignas(64) float oxl[16] = {}, oxh[16] = {}, oyl[16] = {}, oyh[16] = {};
  alignas(64) float q0x[16] = {}, q0y[16] = {}, q1x[16] = {}, q1y[16] = {}, q2x[16] = {}, q2y[16] = {};
  alignas(64) float cx[16] = {}, cy[16] = {}, il2[16] = {}, hq2[16] = {};
  for (int j = 0; j < 8; ++j) {
    const k::KBox o = k::knit_piece_offsets_xy(g, j);
    oxl[j] = o.lo.x;
    oxh[j] = o.hi.x;
    oyl[j] = o.lo.y;
    oyh[j] = o.hi.y;
    // nodes m = 2j, 2j+1, 2j+2 at tau = m pi/8 - pi, relative to the piece's
    // start t0 = tc + (j pi/4 - pi) in x and to y_k in y, in double
    double nx[3], ny[3];
    for (int i = 0; i < 3; ++i) {
      const int m = 2 * j + i;
      const double tau = m * (M_PI / 8) - M_PI;
      nx[i] = (tau - (j * (M_PI / 4) - M_PI)) + double(g.a) * std::sin(2 * tau);
      ny[i] = double(g.h) * std::cos(tau);
    }
    q0x[j] = float(nx[0]);
    q0y[j] = float(ny[0]);
    q1x[j] = float(4 * nx[1] - 3 * nx[0] - nx[2]);
    q1y[j] = float(4 * ny[1] - 3 * ny[0] - ny[2]);
    q2x[j] = float(2 * (nx[0] - 2 * nx[1] + nx[2]));
    q2y[j] = float(2 * (ny[0] - 2 * ny[1] + ny[2]));
    cx[j] = q1x[j] + q2x[j];
    cy[j] = q1y[j] + q2y[j];
    const float l2 = cx[j] * cx[j] + cy[j] * cy[j];
    il2[j] = l2 > 0.0f ? 1.0f / l2 : 0.0f;
    hq2[j] = 0.25f * std::sqrt(q2x[j] * q2x[j] + q2y[j] * q2y[j]);
  }
  return {load(oxl), load(oxh), load(oyl), load(oyh), load(q0x), load(q0y), load(q1x),
          load(q1y), load(q2x), load(q2y), load(cx),  load(cy),  load(il2), load(hq2)};
}

// The curve of a lane's row at t: x and y relative to the lane's point
// (qx, qy), z, and their first and second derivatives in t.
struct CurveV {
  F qx, qy, z;
  F d1x, d1y, z1;
  F d2x, d2y, z2;
};

// Depth polynomial coefficients of a cell from its head, legs and sinker
// signs packed as bits (1: purl sign): A, B, sl.
inline void depth_coeffs(I bits, F& A, F& B, F& sl) {
  // by bits 0..7: sh, sl, ss = 1 - 2 bit, A = (sh + ss) / 2 + sl, B = (sh - ss) / 2
  const F tA = {_mm512_setr_ps(2, 1, 0, -1, 1, 0, -1, -2, 0, 0, 0, 0, 0, 0, 0, 0)};
  const F tB = {_mm512_setr_ps(0, -1, 0, -1, 1, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0)};
  const F tL = {_mm512_setr_ps(1, 1, -1, -1, 1, 1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0)};
  A = lookup(tA, bits);
  B = lookup(tB, bits);
  sl = lookup(tL, bits);
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

// KnitSurface::span_bits at cell index idx (9 bits: the depth signs of
// the cells left of, at and right of it), for the lanes of m. The table
// holds 16-bit entries: a 32-bit gather at byte offset 2 idx, masked (the
// table ends with a padding entry).
inline I span_bits_at(const uint16_t* span, I idx, M m) {
  const __m512i raw =
      _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), m, idx.v, reinterpret_cast<const int*>(span), 2);
  return I{_mm512_and_si512(raw, _mm512_set1_epi32(0x1FF))};
}

// A chunk of candidates in stage 3: each lane's row, span (the cells
// around the piece's column cs) and point.
struct SpanV {
  I cs, k;
  I bits;  // span bits of column cs (KnitSurface::span_bits): cs - 1, cs, cs + 1
  F yk, X, Y;
};

// Depth bits of column c for each lane: from the span when c is within a
// column of cs, looked up otherwise (rare: a search that left the span).
inline I bits_of(const k::KnitGeom& g, const uint16_t* span, const SpanV& sp, I c, M m) {
  const I d = c - sp.cs;
  I b = I{_mm512_srlv_epi32(sp.bits.v, (d * iv(3) + iv(3)).v)} & iv(7);
  const M far = m & (ilt(d, iv(-1)) | igt(d, iv(1)));
  if (far) {
    const I off = (iv(g.rows - 1) - modi(sp.k, g.rows)) * iv(g.cols);
    b = sel(far, I{_mm512_srli_epi32(span_bits_at(span, off + modi(c, g.cols), far).v, 3)} & iv(7), b);
  }
  return b;
}

// x and y of each lane's row at t (the same for knit and purl cells),
// relative to its point, with their derivatives; and what the depth needs:
// t's column c, tau = t - its centre, sin and cos of tau.
struct CurveXY {
  I c;
  F tau, s1, c1;
  F qx, qy, d1x, d1y, d2x, d2y;
};

inline CurveXY curve_xy_at(const k::KnitGeom& g, F t, F yk, F X, F Y) {
  const F two_pi = fv(6.28318530717958647692f), pi = fv(3.14159265358979323846f);
  CurveXY r;
  r.c = ifloor(t * fv(0.15915494309189533577f));
  const F tc = two_pi * tof(r.c) + pi;
  r.tau = t - tc;
  sincos_v(r.tau, r.s1, r.c1);
  const F s2 = fv(2.0f) * r.s1 * r.c1, c2 = r.c1 * r.c1 - r.s1 * r.s1;
  const F a = fv(g.a), h = fv(g.h);
  r.qx = ((tc + r.tau) + a * s2) - X;
  r.qy = (yk + h * r.c1) - Y;
  r.d1x = fv(1.0f) + fv(2.0f) * a * c2;
  r.d1y = -h * r.s1;
  r.d2x = fv(-4.0f) * a * s2;
  r.d2y = -h * r.c1;
  return r;
}

// z = d P(cos tau) and its first two derivatives in t for a cell whose
// depth-sign bits are `bits` (knit_depth_poly and knit_profile).
inline void depth_at(I bits, F d, F s1, F c1, F& z, F& z1, F& z2) {
  F A, B, sl;
  depth_coeffs(bits, A, B, sl);
  const F P = (A + B * c1) * (c1 * c1) - sl, P1 = (fv(2.0f) * A + fv(3.0f) * B * c1) * c1,
          P2 = fv(2.0f) * A + fv(6.0f) * B * c1;
  z = d * P;
  z1 = -d * P1 * s1;
  z2 = d * (P2 * s1 * s1 - P1 * c1);
}

// The exact curve of each lane's row at t, relative to its point in x and
// y (knit_span_curve_at for knit and purl cells: the profile of t's column,
// blended with its neighbour's near their boundary; x and y do not depend
// on the cells, so the neighbour's profile shares sin and cos).
inline CurveV curve_at(const k::KnitGeom& g, const uint16_t* span, const SpanV& sp, F t, M m) {
  const F two_pi = fv(6.28318530717958647692f), pi = fv(3.14159265358979323846f), pi4 = fv(0.78539816339744830962f);
  const CurveXY xy = curve_xy_at(g, t, sp.yk, sp.X, sp.Y);
  const I c = xy.c;
  const I side = sel(gt(xy.tau, pi - pi4), iv(1), sel(lt(xy.tau, pi4 - pi), iv(-1), iv(0)));
  const I nc = c + side;
  const I bself = bits_of(g, span, sp, c, m);
  const I bnb = bits_of(g, span, sp, nc, m & ~ieq(side, iv(0)));
  const F d = fv(g.d);
  CurveV cv{xy.qx, xy.qy, fv(0.0f), xy.d1x, xy.d1y, fv(0.0f), xy.d2x, xy.d2y, fv(0.0f)};
  F zs, z1s, z2s;
  depth_at(bself, d, xy.s1, xy.c1, zs, z1s, z2s);
  const M blend = m & ~ieq(side, iv(0)) & ~ieq(bnb, bself);
  if (!blend) {  // no lane near a boundary with a cell of other signs: its own profile
    cv.z = zs;
    cv.z1 = z1s;
    cv.z2 = z2s;
    return cv;
  }
  F zn, z1n, z2n;
  depth_at(sel(ieq(side, iv(0)), bself, bnb), d, xy.s1, xy.c1, zn, z1n, z2n);
  const M self_lo = igt(nc, c);  // the neighbour is on the right: self is left of the boundary
  const F zlo = sel(self_lo, zs, zn), z1lo = sel(self_lo, z1s, z1n), z2lo = sel(self_lo, z2s, z2n);
  const F e0 = sel(self_lo, zn, zs) - zlo, e1 = sel(self_lo, z1n, z1s) - z1lo, e2 = sel(self_lo, z2n, z2s) - z2lo;
  const F tb = two_pi * tof(sel(igt(nc, c), nc, c));
  const F iw2 = fv(0.63661977236758134308f);  // 1 / w2
  const F xw = clampv((t - (tb - pi4)) * iw2, fv(0.0f), fv(1.0f));
  const F xw2 = xw * xw;
  const F w = xw2 * xw * (fv(10.0f) + xw * (fv(-15.0f) + fv(6.0f) * xw));
  const F dw = fv(30.0f) * xw2 * (xw - fv(1.0f)) * (xw - fv(1.0f)) * iw2;
  const F ddw = fv(60.0f) * xw * (xw - fv(1.0f)) * (fv(2.0f) * xw - fv(1.0f)) * (iw2 * iw2);
  cv.z = zlo + e0 * w;
  cv.z1 = (z1lo + e1 * w) + e0 * dw;
  cv.z2 = ((z2lo + e2 * w) + e1 * (fv(2.0f) * dw)) + e0 * ddw;
  return cv;
}

// m ? a : b for every field.
inline CurveV sel(M m, const CurveV& a, const CurveV& b) {
  return {sel(m, a.qx, b.qx),   sel(m, a.qy, b.qy),   sel(m, a.z, b.z),    sel(m, a.d1x, b.d1x), sel(m, a.d1y, b.d1y),
          sel(m, a.z1, b.z1),   sel(m, a.d2x, b.d2x), sel(m, a.d2y, b.d2y), sel(m, a.z2, b.z2)};
}

constexpr float kBig = 1.0e30f;
constexpr int kBlock = 1024;  // points per pass through the stages

// Stages 1-5 for points [0, n) of a block (n <= kBlock).
void query_block_avx512(const KnitSurface& surf, const BatchConsts& kc, const float* xs, const float* ys, int n,
                        SurfaceHit* out, Work& wk) {
  const k::KnitGeom& g = surf.geom();
  const int32_t* codes = surf.codes();
  const int32_t* colors = surf.colors();
  const uint16_t* span = surf.span_bits().data();
  const float rr_s = g.r * 1.001f + 1.0e-4f;
  const float m_s = g.r + g.quad_margin;
  const float r2_s = g.r * g.r;
  const float top_s = g.shell_top + 0.01f;
  const F rr = fv(rr_s), pi4 = fv(0.78539816339744830962f), s = fv(g.row_spacing);
  const F thr = fv(m_s * 1.001f + 1.0e-4f);
  alignas(64) float xb[kBlock + 16], yb[kBlock + 16];
  std::memcpy(xb, xs, sizeof(float) * size_t(n));
  std::memcpy(yb, ys, sizeof(float) * size_t(n));
  for (int i = n; i < kBlock + 16; ++i) xb[i] = yb[i] = 0.0f;

  // Stage 1: candidates.
  int ncand = 0;
  for (int base = 0; base < n; base += 16) {
    const M lanes = tail_mask(n - base);
    const F X = load(xb + base), Y = load(yb + base);
    const M vm = lanes & lt(vabs(X), fv(1.0e7f)) & lt(vabs(Y), fv(1.0e7f));
    if (!vm) continue;
    const I k0 = toi_trunc(vceil(((Y - fv(g.h)) - rr) / s - fv(0.5f)));
    const I k1 = ifloor(((Y + fv(g.h)) + rr) / s - fv(0.5f));
    const I g0 = ifloor(((X - rr) - fv(g.a)) / pi4);
    const I g1 = ifloor(((X + rr) + fv(g.a)) / pi4);
    const int nk = _mm512_mask_reduce_max_epi32(vm, (k1 - k0).v) + 1;
    const int ng = _mm512_mask_reduce_max_epi32(vm, (g1 - g0).v) + 1;
    wk.reserve(size_t(ncand) + 16 * size_t(nk) * size_t(ng));  // (no pointer into wk is held across this)
    const I lane_id = lane_index(base);
    for (int dk = 0; dk < nk; ++dk) {
      const I kk = k0 + iv(dk);
      const M vk = vm & ile(kk, k1);
      if (!vk) continue;
      const F yk = (tof(kk) + fv(0.5f)) * s;
      const F Yl = Y - yk;
      for (int dg = 0; dg < ng; ++dg) {
        const I gp = g0 + iv(dg);
        M v = vk & ile(gp, g1);
        const I j = gp & iv(7);
        const F t0 = tof(gp) * pi4;
        v &= ge(Y, (yk + lookup(kc.oyl, j)) - rr) & le(Y, (yk + lookup(kc.oyh, j)) + rr);
        v &= ge(X, (t0 + lookup(kc.oxl, j)) - rr) & le(X, ((t0 + pi4) + lookup(kc.oxh, j)) + rr);
        if (!v) continue;
        // knit_quad_xy_distance_bound, relative to (t0, y_k), its per-piece
        // parts from the table: |d| - |q2|/4 <= thr, taken squared
        const F cx = lookup(kc.cx, j), cy = lookup(kc.cy, j);
        const F ax = (X - t0) - lookup(kc.q0x, j), ay = Yl - lookup(kc.q0y, j);
        const F u = clampv((ax * cx + ay * cy) * lookup(kc.il2, j), fv(0.0f), fv(1.0f));
        const F dx = ax - u * cx, dy = ay - u * cy;
        const F reach = thr + lookup(kc.hq2, j);
        v &= le(dx * dx + dy * dy, reach * reach);
        if (!v) continue;
        compress_store(wk.pt.data() + ncand, v, lane_id);
        compress_store(wk.row.data() + ncand, v, kk);
        compress_store(wk.piece.data() + ncand, v, gp);
        ncand += __builtin_popcount(unsigned(v));
      }
    }
  }

  // Stage 2: closest points (cubic of the interpolant, one Newton step).
  for (int c0 = 0; c0 < ncand; c0 += 16) {
    const M m = tail_mask(ncand - c0);
    const I pt = {_mm512_maskz_loadu_epi32(m, wk.pt.data() + c0)};
    const I kk = {_mm512_maskz_loadu_epi32(m, wk.row.data() + c0)};
    const I gp = {_mm512_maskz_loadu_epi32(m, wk.piece.data() + c0)};
    const F X = gather(xb, pt, m), Y = gather(yb, pt, m);
    const I j = gp & iv(7);
    const F t0 = tof(gp) * pi4;
    const F yk = (tof(kk) + fv(0.5f)) * s;
    const F Ax = lookup(kc.q0x, j) - (X - t0), Ay = lookup(kc.q0y, j) - (Y - yk);
    const F Bx = lookup(kc.q1x, j), By = lookup(kc.q1y, j), Cx = lookup(kc.q2x, j), Cy = lookup(kc.q2y, j);
    F r0, r1, r2;
    I nr;
    solve_cubic_v(fv(2.0f) * (Cx * Cx + Cy * Cy), fv(3.0f) * (Bx * Cx + By * Cy),
                  (Bx * Bx + By * By) + fv(2.0f) * (Ax * Cx + Ay * Cy), Ax * Bx + Ay * By, m, r0, r1, r2, nr);
    F best = Ax * Ax + Ay * Ay, bu = fv(0.0f);
    {
      const F ex = Ax + Bx + Cx, ey = Ay + By + Cy;
      const F d1 = ex * ex + ey * ey;
      const M b = lt(d1, best);
      best = sel(b, d1, best);
      bu = sel(b, fv(1.0f), bu);
    }
    const F roots[3] = {r0, r1, r2};
    for (int i = 0; i < 3; ++i) {
      const F x = roots[i];
      const F ex = Ax + (Bx + Cx * x) * x, ey = Ay + (By + Cy * x) * x;
      const F dd = ex * ex + ey * ey;
      const M b = igt(nr, iv(i)) & gt(x, fv(0.0f)) & lt(x, fv(1.0f)) & lt(dd, best);
      best = sel(b, dd, best);
      bu = sel(b, x, bu);
    }
    const M near = m & le(best, fv(m_s * m_s));
    F t = t0 + bu * pi4;
    const CurveXY at = curve_xy_at(g, t, yk, X, Y);
    const F phi1 = at.qx * at.d1x + at.qy * at.d1y;
    const F phi2 = (at.d1x * at.d1x + at.d1y * at.d1y) + (at.qx * at.d2x + at.qy * at.d2y);
    const M step = gt(phi2, fv(0.0f));
    t = sel(step, t - clampv(phi1 / sel(step, phi2, fv(1.0f)), fv(-0.4f), fv(0.4f)), t);
    store(wk.t.data() + c0, sel(near, t, fv(kBig)));
    // Whether the line passes through the tube at t: the entry search's
    // first test (knit_newton_extreme), which is the hit the kernel's
    // de-duplication below goes by
    const CurveXY at2 = curve_xy_at(g, t, yk, X, Y);
    store(wk.inside.data() + c0, sel(near & lt(at2.qx * at2.qx + at2.qy * at2.qy, fv(r2_s)), iv(1), iv(0)));
  }

  // Stage 2b: per point, in row and piece order, knit_line_query's
  // de-duplication: a crossing found again from the next piece has the same
  // closest point (within 0.1 of the row's last two crossings); only the
  // first goes on to the entry search, and only if the line passes through
  // its tube. A quarter of the candidates within reach are such repeats.
  int cur_row[kBlock];
  float last_t[kBlock], prev_t[kBlock];
  for (int i = 0; i < n; ++i) cur_row[i] = INT32_MIN;
  for (int c = 0; c < ncand; ++c) {
    const size_t cz = size_t(c);
    wk.use[cz] = 0;
    const float t = wk.t[cz];
    if (t == kBig) continue;
    const int p = wk.pt[cz];
    if (wk.row[cz] != cur_row[p]) {
      cur_row[p] = wk.row[cz];
      last_t[p] = prev_t[p] = -kBig;
    }
    if (std::fabs(t - last_t[p]) < 0.1f || std::fabs(t - prev_t[p]) < 0.1f) continue;
    if (!wk.inside[cz]) continue;
    prev_t[p] = last_t[p];
    last_t[p] = t;
    wk.use[cz] = 1;
  }

  // Stage 2c: the crossings to search, with what stage 3 needs of them.
  int nlive = 0;
  for (int c0 = 0; c0 < ncand; c0 += 16) {
    const M m = tail_mask(ncand - c0);
    const I use = {_mm512_maskz_loadu_epi32(m, wk.use.data() + c0)};
    const M live = m & _mm512_test_epi32_mask(use.v, use.v);
    if (!live) continue;
    const I pt = {_mm512_maskz_loadu_epi32(live, wk.pt.data() + c0)};
    const I kk = {_mm512_maskz_loadu_epi32(live, wk.row.data() + c0)};
    const I gp = {_mm512_maskz_loadu_epi32(live, wk.piece.data() + c0)};
    const I cs = {_mm512_srai_epi32(gp.v, 3)};
    const I off = (iv(g.rows - 1) - modi(kk, g.rows)) * iv(g.cols);
    compress_store(wk.l_c.data() + nlive, live, lane_index(c0));
    compress_store(wk.l_t.data() + nlive, live, F{_mm512_maskz_loadu_ps(live, wk.t.data() + c0)});
    compress_store(wk.l_x.data() + nlive, live, gather(xb, pt, live));
    compress_store(wk.l_y.data() + nlive, live, gather(yb, pt, live));
    compress_store(wk.l_yk.data() + nlive, live, (tof(kk) + fv(0.5f)) * s);
    compress_store(wk.l_cs.data() + nlive, live, cs);
    compress_store(wk.l_k.data() + nlive, live, kk);
    compress_store(wk.l_bits.data() + nlive, live, span_bits_at(span, off + modi(cs, g.cols), live));
    nlive += __builtin_popcount(unsigned(live));
  }

  // Stage 3: entries (knit_newton_extreme, sgn = -1, on the exact curve).
  // Each lane runs one candidate's search and takes the next live one as
  // soon as it is done, so a vector is never held up by its slowest lane.
  // Every round evaluates the curve once per lane: a new candidate's start,
  // or the trial point of a Newton step (which is accepted, or halved).
  const F r2 = fv(r2_s), top = fv(top_s);
  int nout = 0;
  {
    enum { kIdle = 0, kInit = 1, kStep = 2, kTrial = 3 };
    I phase = iv(kIdle), slot = iv(-1), it = iv(0), tries = iv(0);
    F t = fv(0.0f), f = fv(0.0f), step = fv(0.0f), rho2 = fv(0.0f);
    CurveV cv{fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f), fv(0.0f)};
    SpanV sp{iv(0), iv(0), iv(0), fv(0.0f), fv(0.0f), fv(0.0f)};
    int next = 0;
    M done = 0, done_hit = 0;  // lanes whose search has ended (with a crossing), not yet written
    for (;;) {
      // lanes with an accepted point: the next Newton step, or done
      const M st = ieq(phase, iv(kStep));
      if (st) {
        const F w = vsqrt(vmax(r2 - rho2, fv(0.0f)));
        const F iws = fv(1.0f) / sel(gt(w, fv(0.0f)), w, fv(1.0f));
        const F phi1 = cv.qx * cv.d1x + cv.qy * cv.d1y;
        const F phi2 = (cv.d1x * cv.d1x + cv.d1y * cv.d1y) + (cv.qx * cv.d2x + cv.qy * cv.d2y);
        const F f1 = cv.z1 - phi1 * iws;
        const F f2 = (cv.z2 - phi2 * iws) - phi1 * phi1 * (iws * iws * iws);
        const M concave = lt(f2, fv(0.0f));
        F sn = sel(concave, -f1 / sel(concave, f2, fv(-1.0f)), f1 * fv(0.05f));
        sn = clampv(sn, fv(-0.25f), fv(0.25f));
        const M stop = st & (ieq(it, iv(5)) | lt(vabs(sn), fv(1.0e-4f)));  // KNIT_NEWTON_EXTREME
        done |= stop;
        done_hit |= stop;
        const M go = st & ~stop;
        f = sel(go, (cv.z - top) + w, f);
        step = sel(go, sn, step);
        it = sel(go, it + iv(1), it);
        tries = sel(go, iv(0), tries);
        phase = sel(go, iv(kTrial), phase);
      }
      // write the ended searches and free their lanes before the refill, so
      // that the evaluation below runs on as many lanes as there is work
      if (done) {
        // the entry distance orders the crossings; the point, normal and
        // tangent are only needed for each point's first one (stage 5)
        const F s_in = (top - cv.z) - vsqrt(vmax(r2 - rho2, fv(0.0f)));
        compress_store(wk.o_slot.data() + nout, done, slot);
        compress_store(wk.o_hit.data() + nout, done, sel(done_hit, iv(1), iv(0)));
        compress_store(wk.o_sin.data() + nout, done, s_in);
        compress_store(wk.o_t.data() + nout, done, t);
        nout += __builtin_popcount(unsigned(done));
        phase = sel(done, iv(kIdle), phase);
        done = 0;
        done_hit = 0;
      }
      // refill idle lanes, in live order
      const M idle = ieq(phase, iv(kIdle));
      const int take = std::min(__builtin_popcount(unsigned(idle)), nlive - next);
      if (take > 0) {
        const M nw = M(_pdep_u32((1u << take) - 1u, unsigned(idle)));
        auto ex_f = [&](const std::vector<float>& a, F old) {
          return F{_mm512_mask_expand_ps(old.v, nw, _mm512_loadu_ps(a.data() + next))};
        };
        auto ex_i = [&](const std::vector<int32_t>& a, I old) {
          return I{_mm512_mask_expand_epi32(old.v, nw, _mm512_loadu_si512(a.data() + next))};
        };
        t = ex_f(wk.l_t, t);
        sp.X = ex_f(wk.l_x, sp.X);
        sp.Y = ex_f(wk.l_y, sp.Y);
        sp.yk = ex_f(wk.l_yk, sp.yk);
        sp.cs = ex_i(wk.l_cs, sp.cs);
        sp.k = ex_i(wk.l_k, sp.k);
        sp.bits = ex_i(wk.l_bits, sp.bits);
        slot = I{_mm512_mask_expand_epi32(slot.v, nw, lane_index(next).v)};
        phase = sel(nw, iv(kInit), phase);
        it = sel(nw, iv(0), it);
        next += take;
      }
      // one curve evaluation for the lanes at a start or a trial point
      const M init = ieq(phase, iv(kInit)), trial = ieq(phase, iv(kTrial));
      const M ev = init | trial;
      if (!ev) break;  // (every lane idle: nothing left)
      const F tn = sel(trial, t + step, t);
      const CurveV nc = curve_at(g, span, sp, tn, ev);
      const F nrho2 = nc.qx * nc.qx + nc.qy * nc.qy;
      const M inside = lt(nrho2, r2);
      const M ok = (init & inside) | (trial & inside & ge((nc.z - top) + vsqrt(vmax(r2 - nrho2, fv(0.0f))), f));
      t = sel(ok, tn, t);
      cv = sel(ok, nc, cv);
      rho2 = sel(ok, nrho2, rho2);
      phase = sel(ok, iv(kStep), phase);
      done |= init & ~inside;  // the start is outside the tube: no crossing
      const M rej = trial & ~ok;
      tries = sel(rej, tries + iv(1), tries);
      step = sel(rej, step * fv(0.5f), step);
      const M gave_up = rej & ieq(tries, iv(4));
      done |= gave_up;
      done_hit |= gave_up;
    }
  }
  for (int i = 0; i < nout; ++i) wk.pos_of[size_t(wk.o_slot[size_t(i)])] = i;

  // Stage 4: per point, over its crossings in row and piece order: the
  // layer count and the first entry.
  int best_i[kBlock], best_row[kBlock], count[kBlock];
  float best_s[kBlock];
  for (int i = 0; i < n; ++i) {
    best_i[i] = -1;
    count[i] = 0;
    best_s[i] = kBig;
  }
  const float s_max = 2.0f * top_s;
  for (int l = 0; l < nlive; ++l) {
    const int o = wk.pos_of[size_t(l)];
    if (!wk.o_hit[size_t(o)]) continue;  // (cannot happen: the line passes through the tube at the start)
    const size_t cz = size_t(wk.l_c[size_t(l)]);
    const int p = wk.pt[cz];
    const float si = wk.o_sin[size_t(o)];
    if (si <= s_max) ++count[p];
    if (si >= 0.0f && si <= s_max && si < best_s[p]) {
      best_s[p] = si;
      best_i[p] = o;
      best_row[p] = wk.row[cz];
    }
  }

  // Stage 5: each point's first entry, evaluated again at its final t (the
  // same curve point the search ended on): position, normal, tangent, cell.
  int nb = 0;
  for (int i = 0; i < n; ++i) {
    if (best_i[i] < 0) {
      SurfaceHit h;
      h.layers = count[i];
      out[i] = h;
      continue;
    }
    wk.b_pt[size_t(nb)] = i;
    wk.b_o[size_t(nb)] = best_i[i];
    wk.b_row[size_t(nb)] = best_row[i];
    ++nb;
  }
  for (int c0 = 0; c0 < nb; c0 += 16) {
    const M m = tail_mask(nb - c0);
    const I o = {_mm512_maskz_loadu_epi32(m, wk.b_o.data() + c0)};
    const I sl = gather(wk.o_slot.data(), o, m);
    const F t = gather(wk.o_t.data(), o, m);
    SpanV sp;
    sp.X = gather(wk.l_x.data(), sl, m);
    sp.Y = gather(wk.l_y.data(), sl, m);
    sp.yk = gather(wk.l_yk.data(), sl, m);
    sp.cs = gather(wk.l_cs.data(), sl, m);
    sp.k = gather(wk.l_k.data(), sl, m);
    sp.bits = gather(wk.l_bits.data(), sl, m);
    const CurveV cv = curve_at(g, span, sp, t, m);
    const F rho2 = cv.qx * cv.qx + cv.qy * cv.qy;
    const F w = vsqrt(vmax(r2 - rho2, fv(0.0f)));
    const F s_in = (top - cv.z) - w;
    const F pz = top - s_in;
    const F nzv = pz - cv.z;  // normal: (p - Y(t)) / |.|, tangent: Y'(t) / |.|
    const F nl = vsqrt(cv.qx * cv.qx + cv.qy * cv.qy + nzv * nzv);
    const F nli = fv(1.0f) / sel(gt(nl, fv(0.0f)), nl, fv(1.0f));
    const F tl = vsqrt(cv.d1x * cv.d1x + cv.d1y * cv.d1y + cv.z1 * cv.z1);
    const F tli = fv(1.0f) / sel(gt(tl, fv(0.0f)), tl, fv(1.0f));
    const I col = ifloor(t * fv(0.15915494309189533577f));
    const I row = {_mm512_maskz_loadu_epi32(m, wk.b_row.data() + c0)};
    const I at = (iv(g.rows - 1) - modi(row, g.rows)) * iv(g.cols) + modi(col, g.cols);
    store(wk.b_col.data() + c0, col);
    store(wk.b_code.data() + c0, gather(codes, at, m));
    store(wk.b_colour.data() + c0, gather(colors, at, m));
    store(wk.b_pz.data() + c0, pz);
    store(wk.b_nx.data() + c0, -cv.qx * nli);
    store(wk.b_ny.data() + c0, -cv.qy * nli);
    store(wk.b_nz.data() + c0, nzv * nli);
    store(wk.b_tx.data() + c0, cv.d1x * tli);
    store(wk.b_ty.data() + c0, cv.d1y * tli);
    store(wk.b_tz.data() + c0, cv.z1 * tli);
  }
  for (int b = 0; b < nb; ++b) {
    const size_t bz = size_t(b);
    const int i = wk.b_pt[bz];
    SurfaceHit h;
    h.hit = true;
    h.layers = count[i];
    h.position = k::kv3(xb[i], yb[i], wk.b_pz[bz]);
    h.normal = k::kv3(wk.b_nx[bz], wk.b_ny[bz], wk.b_nz[bz]);
    h.tangent = k::kv3(wk.b_tx[bz], wk.b_ty[bz], wk.b_tz[bz]);
    h.row = wk.b_row[bz];
    h.col = wk.b_col[bz];
    h.stitch = wk.b_code[bz];
    h.color = wk.b_colour[bz];
    out[i] = h;
  }
}

void query_avx512(const KnitSurface& surf, const float* x, const float* y, size_t n, SurfaceHit* out) {
  const k::KnitGeom& g = surf.geom();
  const BatchConsts kc = make_consts(g);
  // Reused between calls (no allocation per call once grown); stage 1
  // grows it when a vector of points could overflow it.
  static thread_local Work wk;
  wk.reserve(size_t(kBlock) * 4);  // 2.5 candidates per point on average with Crane's stitch
  for (size_t b = 0; b < n; b += kBlock) {
    const int nb = int(std::min<size_t>(kBlock, n - b));
    query_block_avx512(surf, kc, x + b, y + b, nb, out + b, wk);
  }
}

#pragma GCC diagnostic pop
#pragma GCC pop_options

#endif  // KNIT_HAVE_AVX512_PATH

}  // namespace

bool KnitSurface::batch_simd_available() {
#if KNIT_HAVE_AVX512_PATH
  return cpu_has_avx512();
#else
  return false;
#endif
}

bool KnitSurface::batch_uses_simd(BatchPath path) const {
  if (path == BatchPath::Scalar) return false;
  const bool ok = batch_simd_available() && geom_.has_floats == 0 && !span_bits_.empty();
  if (path == BatchPath::Simd && !ok)
    throw std::invalid_argument(batch_simd_available()
                                    ? "query_batch: the SIMD path takes knit and purl stitches only (this "
                                      "pattern has slip stitches)"
                                    : "query_batch: this CPU has no AVX-512 (or the build is not x86-64)");
  return ok;
}

void KnitSurface::query_batch(const float* x, const float* y, size_t n, SurfaceHit* out, BatchPath path) const {
  if (n == 0) return;
  if (!x || !y || !out) throw std::invalid_argument("query_batch: null array");
#if KNIT_HAVE_AVX512_PATH
  if (batch_uses_simd(path)) {
    query_avx512(*this, x, y, n, out);
    return;
  }
#else
  (void)batch_uses_simd(path);
#endif
  query_scalar(*this, x, y, n, out);
}

}  // namespace knit
