/* Knitshade kernel: stitch geometry in pattern space.
 *
 * Paper Sec. 4.1, Eq. 2 (Crane 2023): a knit stitch is the curve
 *   Y(tau) = (tau + a sin 2tau, h cos tau, d cos 2tau),  tau in [-pi, pi],
 * swept by a round tube of radius r. Every pattern row is one periodic yarn.
 *
 * Pattern space (docs/geometry.md). x runs along the course, y along the wale,
 * z out of the fabric. Cell (k, c) - row k counted from the BOTTOM, column c -
 * spans x in [2 pi c, 2 pi (c+1)) and y in [k s, (k+1) s), s = row spacing.
 * Row k's yarn is parametrised by a global t: column c owns t in
 * [2 pi c, 2 pi (c+1)), its stitch centred at t_c = 2 pi c + pi, and
 *   Y_k(t) = (t_c, y_k, 0) + profile(code(k, c), t - t_c),  y_k = (k + 1/2) s.
 * Profiles by stitch code, with c = cos tau:
 *   0 knit, 1 purl  (tau + a sin 2tau, h cos tau, d P(c))
 *   2 front         (tau, -h,  D)   slip stitch: the yarn floats straight across
 *   3 back          (tau, -h, -D)   in front of / behind the fabric, D = |d| + 2r
 * Depth. Crane's single stitch has z = d cos 2tau: head (tau = 0) and sinker
 * (tau = +-pi) in front, legs (tau = +-pi/2) behind, which is what lets row
 * k's head pass in front of row k+1's legs and row k+1's sinker in front of
 * row k's legs. A purl flips the depth of its own legs, so the stitches
 * around it must flip the parts that cross them: the head of cell (k, c)
 * takes the sign of the stitch above it (k+1, c), its legs its own sign and
 * its sinker the sign of the stitch below (k-1, c). Splitting
 * cos 2tau = c^2 (1 + c)/2 - (1 - c^2) + c^2 (1 - c)/2 into head, legs and
 * sinker terms and signing each gives
 *   P(c) = (A + sl) c^2 + B c^3 - sl,  A = (sh + ss)/2, B = (sh - ss)/2,
 * with sh, sl, ss = +1 (knit) or -1 (purl) for head, legs and sinker. With
 * equal signs P = s cos 2tau: plain knit (or purl, the paper's flipped depth)
 * exactly as in Crane's model. Slip stitches do not take part: next to a
 * front or back stitch a loop keeps its own sign.
 * Where neighbouring cells differ, the two profiles are blended over
 * |t - boundary| < pi/4 with a C2 quintic smoothstep, so the yarn stays C2
 * (a knit-purl boundary passes the yarn through z = 0 at the sinker loop).
 *
 * For the analytic queries each cell is cut into 8 pieces of pi/4 in t
 * (global piece g covers t in [g pi/4, (g+1) pi/4]); pieces 0 and 7 of a cell
 * are its blend pieces. On each piece sin 2tau and cos 2tau are monotone
 * quarter periods and cos tau is monotone, which gives cheap exact bounds
 * (knit_piece_bounds) and a 3-point quadratic interpolant (knit_piece_quad). */
#ifndef KNIT_KERNEL_STITCH_H
#define KNIT_KERNEL_STITCH_H

#define KNIT_CODE_KNIT 0
#define KNIT_CODE_PURL 1
#define KNIT_CODE_FRONT 2
#define KNIT_CODE_BACK 3

#define KNIT_PIECE_LEN K_PI_4
#define KNIT_PIECES_PER_CELL 8
#define KNIT_BLEND_HALF_WIDTH K_PI_4

/* Geometry of a knit surface. Build with knit_geom_make; validated by the
 * host before (StitchParams::validate). */
KNIT_STRUCT(KnitGeom)
  float a, h, d, r;   /* Crane's parameters and tube radius */
  float row_spacing;  /* s = h + 1/2 */
  float float_depth;  /* D = |d| + 2r, depth of slip-stitch floats */
  float shell_top;    /* highest z of any tube: max(|d|, D if floats) + r */
  int rows, cols;     /* pattern size */
  int has_floats;     /* pattern uses codes 2 or 3 */
  float quad_margin;  /* bound on |quadratic interpolant - curve| over a piece */
  float quad_margin_xy; /* the same in x and y alone (vertical lines) */
KNIT_STRUCT_END(KnitGeom)
/* KnitGeom is passed by value in C and OSL (KNIT_IN: by const reference in
 * C++): keep it small (no arrays), or the C host spends its time copying it. */

KNIT_FN KnitGeom knit_geom_make(float a, float h, float d, float r, int rows, int cols,
                                int has_floats) {
  KnitGeom g;
  g.a = a;
  g.h = h;
  g.d = d;
  g.r = r;
  g.row_spacing = h + KF(0.5);
  g.float_depth = k_fabs(d) + KF(2.0) * r;
  g.has_floats = has_floats;
  g.shell_top = (has_floats ? g.float_depth : k_fabs(d)) + r;
  g.rows = rows;
  g.cols = cols;
  /* Interpolation error of 3 equispaced nodes, spacing e = pi/8:
   * |f - p| <= max|f'''| e^3 / (9 sqrt 3), with f''' bounded by 8a (a sin 2t),
   * h (h cos t) and 8|d| (d cos 2t). Doubled for the blend pieces, whose
   * smoothstep adds third-derivative terms; tests/native/test_stitch.cpp
   * measures the real maximum against this bound. */
  g.quad_margin = KF(2.0) * (KF(0.0311) * (g.a + k_fabs(g.d)) + KF(0.0039) * g.h) +
                  KF(0.05) * (has_floats ? g.float_depth + g.h : KF(0.0));
  /* A vertical line's distance lies in x and y, where knit and purl rows
   * do not blend: the x and y errors are each within the bound above
   * (0.003885 max|f'''|), without the doubling, so their length within
   * 0.0039 sqrt(64 a^2 + h^2): 0.049 for Crane's stitch, against 0.19 for
   * quad_margin (the real maximum is 0.038). With floats, quad_margin. */
  g.quad_margin_xy = has_floats ? g.quad_margin : KF(0.0039) * k_sqrt(KF(64.0) * g.a * g.a + g.h * g.h);
  return g;
}

/* Stitch code and colour index of cell (k from the bottom, c), both periodic. */
KNIT_FN int knit_cell_index(KNIT_IN(KnitGeom) g, int k, int c) {
  int pr = g.rows - 1 - k_modi(k, g.rows); /* pattern rows are written top first */
  return pr * g.cols + k_modi(c, g.cols);
}
KNIT_FN int knit_cell_code(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), int k, int c) {
  return codes[knit_cell_index(g, k, c)];
}
KNIT_FN int knit_column_of(float t) { return KINT(k_floor(t / K_2PI)); }
KNIT_FN float knit_row_centre_y(KNIT_IN(KnitGeom) g, int k) { return (KFLT(k) + KF(0.5)) * g.row_spacing; }

/* A row with its pattern-row offsets precomputed (and those of the rows
 * above and below, for the depth signs): evaluations along one row then need
 * one modulo per column instead of six. */
KNIT_STRUCT(KRow)
  int k;                  /* row, counted from the bottom */
  int off, off_up, off_dn; /* offsets into codes[] of rows k, k+1, k-1 */
  float yk;               /* centre y of the row */
KNIT_STRUCT_END(KRow)

KNIT_FN KRow knit_row(KNIT_IN(KnitGeom) g, int k) {
  KRow rw;
  rw.k = k;
  rw.off = (g.rows - 1 - k_modi(k, g.rows)) * g.cols;
  rw.off_up = (g.rows - 1 - k_modi(k + 1, g.rows)) * g.cols;
  rw.off_dn = (g.rows - 1 - k_modi(k - 1, g.rows)) * g.cols;
  rw.yk = knit_row_centre_y(g, k);
  return rw;
}

/* What the geometry needs of a cell: its code and depth signs. */
KNIT_STRUCT(KCell)
  int code;
  kvec3 sg; /* head, legs, sinker depth signs */
KNIT_STRUCT_END(KCell)

/* A point of a curve with its first and second derivative in t. */
KNIT_STRUCT(KCurve)
  kvec3 p, d1, d2;
KNIT_STRUCT_END(KCurve)

/* Depth signs (head, legs, sinker) of cell (k, c), see the file header. */
KNIT_FN float knit_code_sign(int code) { return code == KNIT_CODE_PURL ? KF(-1.0) : KF(1.0); }
KNIT_FN int knit_code_is_loop(int code) { return code == KNIT_CODE_KNIT || code == KNIT_CODE_PURL; }
/* Cell of row rw at column index cm, already reduced to [0, cols). */
KNIT_FN KCell knit_cell_m(KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, int cm) {
  KCell cl;
  int above = codes[rw.off_up + cm];
  int below = codes[rw.off_dn + cm];
  float sl;
  cl.code = codes[rw.off + cm];
  sl = knit_code_sign(cl.code);
  cl.sg = kv3(knit_code_is_loop(above) ? knit_code_sign(above) : sl, sl,
              knit_code_is_loop(below) ? knit_code_sign(below) : sl);
  return cl;
}
KNIT_FN KCell knit_cell(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, int c) {
  return knit_cell_m(codes, rw, k_modi(c, g.cols));
}

/* Row rw's cells at columns c - 1, c and c + 1: all that the curve needs
 * anywhere within a column of column c. A search that stays near one piece
 * (the Newton steps of query.h) looks them up once, instead of taking a
 * modulo and three pattern reads at every evaluation. */
KNIT_STRUCT(KSpan)
  KRow rw;
  int c;              /* centre column (unwrapped) */
  int im, il, ir;     /* pattern-row indices of columns c, c - 1, c + 1 */
  KCell mid, left, right;
KNIT_STRUCT_END(KSpan)

KNIT_FN KSpan knit_span(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, int c) {
  KSpan sp;
  sp.rw = rw;
  sp.c = c;
  sp.im = k_modi(c, g.cols);
  sp.il = sp.im == 0 ? g.cols - 1 : sp.im - 1;
  sp.ir = sp.im == g.cols - 1 ? 0 : sp.im + 1;
  sp.mid = knit_cell_m(codes, rw, sp.im);
  sp.left = knit_cell_m(codes, rw, sp.il);
  sp.right = knit_cell_m(codes, rw, sp.ir);
  return sp;
}
KNIT_FN int knit_span_covers(KNIT_IN(KSpan) sp, int c) { return c >= sp.c - 1 && c <= sp.c + 1 ? 1 : 0; }
/* The cell and pattern-row index of column c, which the span covers. */
KNIT_FN KCell knit_span_cell(KNIT_IN(KSpan) sp, int c) {
  if (c < sp.c) return sp.left;
  if (c > sp.c) return sp.right;
  return sp.mid;
}
KNIT_FN int knit_span_index(KNIT_IN(KSpan) sp, int c) { return c < sp.c ? sp.il : (c > sp.c ? sp.ir : sp.im); }

/* Depth polynomial P(c) = (A + sl) c^2 + B c^3 - sl and its derivatives in
 * c: KX = P, KY = P', KZ = P''. */
KNIT_FN kvec3 knit_depth_poly(kvec3 sg, float c) {
  float A = KF(0.5) * (KX(sg) + KZ(sg)) + KY(sg);
  float B = KF(0.5) * (KX(sg) - KZ(sg));
  return kv3((A + B * c) * c * c - KY(sg), (KF(2.0) * A + KF(3.0) * B * c) * c,
             KF(2.0) * A + KF(6.0) * B * c);
}

/* profile(code, tau) of a cell with depth signs sg, placed at the cell centre (tc, yk). */
KNIT_FN KCurve knit_profile(KNIT_IN(KnitGeom) g, int code, kvec3 sg, float tau, float tc, float yk) {
  KCurve cv;
  if (knit_code_is_loop(code)) {
    kvec3 sc = knit_sincos(tau);
    float s1 = KX(sc), c1 = KY(sc);
    float s2 = KF(2.0) * s1 * c1, c2 = c1 * c1 - s1 * s1;
    kvec3 dp = knit_depth_poly(sg, c1);
    cv.p = kv3(tc + tau + g.a * s2, yk + g.h * c1, g.d * KX(dp));
    cv.d1 = kv3(KF(1.0) + KF(2.0) * g.a * c2, -g.h * s1, -g.d * KY(dp) * s1);
    cv.d2 = kv3(KF(-4.0) * g.a * s2, -g.h * c1, g.d * (KZ(dp) * s1 * s1 - KY(dp) * c1));
  } else {
    float zz = code == KNIT_CODE_FRONT ? g.float_depth : -g.float_depth;
    cv.p = kv3(tc + tau, yk - g.h, zz);
    cv.d1 = kv3(KF(1.0), KF(0.0), KF(0.0));
    cv.d2 = kv3(KF(0.0), KF(0.0), KF(0.0));
  }
  return cv;
}

/* Quintic smoothstep weight and its derivatives in t, for a blend over
 * [tb - w, tb + w]: KX = weight, KY = d/dt, KZ = d2/dt2. */
KNIT_FN kvec3 knit_blend_weight(float t, float tb) {
  float w2 = KF(2.0) * KNIT_BLEND_HALF_WIDTH;
  float x = k_clampf((t - (tb - KNIT_BLEND_HALF_WIDTH)) / w2, KF(0.0), KF(1.0));
  float x2 = x * x;
  float w = x2 * x * (KF(10.0) + x * (KF(-15.0) + KF(6.0) * x));
  float dw = KF(30.0) * x2 * (x - KF(1.0)) * (x - KF(1.0)) / w2;
  float ddw = KF(60.0) * x * (x - KF(1.0)) * (KF(2.0) * x - KF(1.0)) / (w2 * w2);
  return kv3(w, dw, ddw);
}

/* Whether two cells have the same profile (then no blend is needed). */
KNIT_FN int knit_same_profile(KNIT_IN(KCell) a, KNIT_IN(KCell) b) {
  if (knit_code_is_loop(a.code) == 0 || knit_code_is_loop(b.code) == 0) return a.code == b.code;
  return KX(a.sg) == KX(b.sg) && KY(a.sg) == KY(b.sg) && KZ(a.sg) == KZ(b.sg);
}

/* The column a point at phase tau of a cell blends with: -1 (left), +1
 * (right) or 0 (none: tau is not within the blend half-width of the cell's
 * ends). */
KNIT_FN int knit_blend_side(float tau) {
  if (tau > K_PI - KNIT_BLEND_HALF_WIDTH) return 1;
  if (tau < KNIT_BLEND_HALF_WIDTH - K_PI) return -1;
  return 0;
}

/* The curve at t in column c, whose own profile there is `self`, blended
 * with the profile of neighbour column nc (cell ncl) across their boundary. */
KNIT_FN KCurve knit_blend_curve(KNIT_IN(KnitGeom) g, KNIT_IN(KCurve) self, KNIT_IN(KCell) ncl, int c, int nc,
                                float t, float yk) {
  float ntc = K_2PI * KFLT(nc) + K_PI;
  float tb = K_2PI * KFLT(k_maxi(c, nc)); /* the boundary between the columns */
  KCurve other = knit_profile(g, ncl.code, ncl.sg, t - ntc, ntc, yk);
  KCurve lo, hi, out;
  kvec3 w, dp, dd1, dd2;
  if (nc > c) { /* lo: the cell left of the boundary */
    lo = self;
    hi = other;
  } else {
    lo = other;
    hi = self;
  }
  w = knit_blend_weight(t, tb);
  dp = kv3_sub(hi.p, lo.p);
  dd1 = kv3_sub(hi.d1, lo.d1);
  dd2 = kv3_sub(hi.d2, lo.d2);
  out.p = kv3_madd(lo.p, dp, KX(w));
  out.d1 = kv3_madd(kv3_madd(lo.d1, dd1, KX(w)), dp, KY(w));
  out.d2 = kv3_madd(kv3_madd(kv3_madd(lo.d2, dd2, KX(w)), dd1, KF(2.0) * KY(w)), dp, KZ(w));
  return out;
}

/* The curve at t in column c (centre tc), whose cell is cl, next to column
 * nc (c itself, or the neighbour t is within the blend half-width of, see
 * knit_blend_side) whose cell is ncl. */
KNIT_FN KCurve knit_cells_curve(KNIT_IN(KnitGeom) g, KNIT_IN(KCell) cl, KNIT_IN(KCell) ncl, int c, int nc,
                                float tc, float t, float yk) {
  KCurve self = knit_profile(g, cl.code, cl.sg, t - tc, tc, yk);
  if (nc == c || knit_same_profile(cl, ncl)) return self;
  return knit_blend_curve(g, self, ncl, c, nc, t, yk);
}

/* The exact yarn curve of a row at global parameter t (see the file header). */
KNIT_FN KCurve knit_row_curve_at(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, float t) {
  int c = knit_column_of(t);
  float tc = K_2PI * KFLT(c) + K_PI;
  int nc = c + knit_blend_side(t - tc);
  KCell cl = knit_cell(g, codes, rw, c);
  KCell ncl = cl;
  if (nc != c) ncl = knit_cell(g, codes, rw, nc);
  return knit_cells_curve(g, cl, ncl, c, nc, tc, t, rw.yk);
}

/* The same through a span's cells (knit_span): t should lie within a column
 * of the span's centre; elsewhere the row is looked up as above. */
KNIT_FN KCurve knit_span_curve_at(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KSpan) sp, float t) {
  int c = knit_column_of(t);
  float tc = K_2PI * KFLT(c) + K_PI;
  int nc = c + knit_blend_side(t - tc);
  if (knit_span_covers(sp, c) == 0 || knit_span_covers(sp, nc) == 0) return knit_row_curve_at(g, codes, sp.rw, t);
  return knit_cells_curve(g, knit_span_cell(sp, c), knit_span_cell(sp, nc), c, nc, tc, t, sp.rw.yk);
}

KNIT_FN KCurve knit_row_curve(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), int k, float t) {
  return knit_row_curve_at(g, codes, knit_row(g, k), t);
}

/* cos(m pi / 8) and sin(m pi / 8) for any integer m, without libm. */
KNIT_FN float knit_cos_pi8(int m) {
  int q = m & 15;                 /* m mod 16, also for negative m */
  int r = q > 8 ? 16 - q : q;     /* cos is even: fold to 0..8 */
  float sgn = r > 4 ? KF(-1.0) : KF(1.0);
  int e = r > 4 ? 8 - r : r;      /* cos(pi - x) = -cos x: fold to 0..4 */
  float val = e == 0 ? KF(1.0)
          : e == 1 ? KF(0.92387953251128675613)
          : e == 2 ? KF(0.70710678118654752440)
          : e == 3 ? KF(0.38268343236508977173)
          : KF(0.0);
  return sgn * val;
}
KNIT_FN float knit_sin_pi8(int m) { return knit_cos_pi8(m - 4); }

/* x and y of node m (tau = m pi/8 - pi) of a knit or purl cell centred at
 * (tc, yk), which do not depend on the code; KZ = cos tau, for the depth. */
KNIT_FN kvec3 knit_loop_node_xy(KNIT_IN(KnitGeom) g, int m, float tc, float yk) {
  float tau = KFLT(m) * (K_PI / KF(8.0)) - K_PI;
  /* tau = m pi/8 - pi: cos tau = -cos(m pi/8); 2 tau = m pi/4 - 2 pi */
  float c1 = -knit_cos_pi8(m);
  return kv3(tc + tau + g.a * knit_sin_pi8(2 * m), yk + g.h * c1, c1);
}

/* Position on the unblended profile at tau = m pi/8 - pi (node m of a cell). */
KNIT_FN kvec3 knit_profile_node(KNIT_IN(KnitGeom) g, int code, kvec3 sg, int m, float tc, float yk) {
  if (knit_code_is_loop(code)) {
    kvec3 n = knit_loop_node_xy(g, m, tc, yk);
    return kv3(KX(n), KY(n), g.d * KX(knit_depth_poly(sg, KZ(n))));
  }
  return kv3(tc + (KFLT(m) * (K_PI / KF(8.0)) - K_PI), yk - g.h,
             code == KNIT_CODE_FRONT ? g.float_depth : -g.float_depth);
}

/* An axis-aligned box. */
KNIT_STRUCT(KBox)
  kvec3 lo, hi;
KNIT_STRUCT_END(KBox)

/* Bounds of the unblended profile of `code` over piece j of a cell. Over a
 * piece cos tau is monotone and sin 2tau is a monotone quarter period, so x, y
 * bounds come from the ends (x as [tau0, tau1] + a [min, max] sin 2tau); the
 * depth cubic P(c) is bounded by its values at the ends and at its
 * stationary points inside. */
KNIT_FN KBox knit_profile_piece_bounds(KNIT_IN(KnitGeom) g, int code, kvec3 sg, int j, float tc, float yk) {
  KBox b;
  float t0 = KFLT(j) * K_PI_4 - K_PI, t1 = t0 + K_PI_4;
  if (knit_code_is_loop(code)) {
    float sa = g.a * knit_sin_pi8(4 * j), sb = g.a * knit_sin_pi8(4 * j + 4);
    float ca = -knit_cos_pi8(2 * j), cb = -knit_cos_pi8(2 * j + 2);
    float clo = k_fmin(ca, cb), chi = k_fmax(ca, cb);
    float pa = KX(knit_depth_poly(sg, ca)), pb = KX(knit_depth_poly(sg, cb));
    float plo = k_fmin(pa, pb), phi = k_fmax(pa, pb);
    float A = KF(0.5) * (KX(sg) + KZ(sg)) + KY(sg);
    float B = KF(0.5) * (KX(sg) - KZ(sg));
    float cs = B != KF(0.0) ? KF(-2.0) * A / (KF(3.0) * B) : KF(0.0);
    if (clo < KF(0.0) && chi > KF(0.0)) {
      float p0 = KX(knit_depth_poly(sg, KF(0.0)));
      plo = k_fmin(plo, p0);
      phi = k_fmax(phi, p0);
    }
    if (cs > clo && cs < chi) {
      float p1 = KX(knit_depth_poly(sg, cs));
      plo = k_fmin(plo, p1);
      phi = k_fmax(phi, p1);
    }
    b.lo = kv3(tc + t0 + k_fmin(sa, sb), yk + g.h * clo, k_fmin(g.d * plo, g.d * phi));
    b.hi = kv3(tc + t1 + k_fmax(sa, sb), yk + g.h * chi, k_fmax(g.d * plo, g.d * phi));
  } else {
    float zz = code == KNIT_CODE_FRONT ? g.float_depth : -g.float_depth;
    b.lo = kv3(tc + t0, yk - g.h, zz);
    b.hi = kv3(tc + t1, yk - g.h, zz);
  }
  return b;
}

/* knit_piece_bounds_xy's box of a piece j (0..7) of a cell, relative to
 * the piece's start t0 in x (its hi.x to t0 + pi/4) and to the row's centre
 * y_k in y; z absolute. */
KNIT_FN KBox knit_piece_offsets_xy(KNIT_IN(KnitGeom) g, int j) {
  KBox b;
  int q = j & 3;
  float zmax = g.has_floats != 0 ? g.float_depth : k_fabs(g.d);
  /* sin 2tau runs 0 -> 1 -> 0 -> -1 -> 0 over pieces q = 0..3 of a half
   * period; cos tau between the values at the piece's ends. */
  float slo = q == 3 ? KF(-1.0) : (q == 2 ? KF(-1.0) : KF(0.0));
  float shi = q == 0 ? KF(1.0) : (q == 1 ? KF(1.0) : KF(0.0));
  float ca = -knit_cos_pi8(2 * j), cb = -knit_cos_pi8(2 * j + 2);
  float ylo = g.h * k_fmin(ca, cb), yhi = g.h * k_fmax(ca, cb);
  float xlo = g.a * slo, xhi = g.a * shi;
  if (g.has_floats != 0) {
    xlo = k_fmin(xlo, KF(0.0));
    xhi = k_fmax(xhi, KF(0.0));
    ylo = -g.h;
  }
  b.lo = kv3(xlo, ylo, -zmax);
  b.hi = kv3(xhi, yhi, zmax);
  return b;
}

/* Bounds of row k's curve over global piece gp in x and y only, without
 * looking at the pattern: x and y of knit and purl profiles do not depend on
 * the code (nor on a blend between them); slip-stitch floats lie on
 * y = y_k - h, x = t. z is bounded by the depth of the deepest profile.
 * The box is the piece's start (t0, y_k) plus offsets that depend only on
 * the piece's place j = gp mod 8 in its cell (knit_piece_offsets_xy). */
KNIT_FN KBox knit_piece_bounds_xy(KNIT_IN(KnitGeom) g, float yk, int gp) {
  KBox o = knit_piece_offsets_xy(g, gp & 7);
  KBox b;
  float t0 = KFLT(gp) * K_PI_4;
  b.lo = kv3(t0 + KX(o.lo), yk + KY(o.lo), KZ(o.lo));
  b.hi = kv3(t0 + K_PI_4 + KX(o.hi), yk + KY(o.hi), KZ(o.hi));
  return b;
}

/* The cell and code of the neighbour a piece blends with (or the cell itself). */
KNIT_FN int knit_piece_neighbour(int j) { return j == 0 ? -1 : (j == 7 ? 1 : 0); }

/* Column of global piece gp. */
KNIT_FN int knit_piece_column(int gp) { return (gp - (gp & 7)) / 8; } /* exact: a multiple of 8 */

/* Conservative bounds of the exact curve of span sp's row over global piece
 * gp of its centre column. A blended piece lies in the union of both
 * profiles' boxes (convex weights). */
KNIT_FN KBox knit_span_piece_bounds(KNIT_IN(KnitGeom) g, KNIT_IN(KSpan) sp, int gp) {
  int j = gp - 8 * sp.c;
  float tc = K_2PI * KFLT(sp.c) + K_PI, yk = sp.rw.yk;
  KBox b = knit_profile_piece_bounds(g, sp.mid.code, sp.mid.sg, j, tc, yk);
  int dn = knit_piece_neighbour(j);
  if (dn != 0) {
    KCell ncl = knit_span_cell(sp, sp.c + dn);
    if (knit_same_profile(sp.mid, ncl) == 0) {
      /* The neighbour's profile over the same t range: its piece 8 (just past
       * its right end) when it is on the left, piece -1 when on the right. */
      float ntc = tc + KFLT(dn) * K_2PI;
      KBox nb = knit_profile_piece_bounds(g, ncl.code, ncl.sg, dn < 0 ? 8 : -1, ntc, yk);
      b.lo = kv3(k_fmin(KX(b.lo), KX(nb.lo)), k_fmin(KY(b.lo), KY(nb.lo)), k_fmin(KZ(b.lo), KZ(nb.lo)));
      b.hi = kv3(k_fmax(KX(b.hi), KX(nb.hi)), k_fmax(KY(b.hi), KY(nb.hi)), k_fmax(KZ(b.hi), KZ(nb.hi)));
    }
  }
  return b;
}

/* The same for row rw (any global piece). */
KNIT_FN KBox knit_piece_bounds(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, int gp) {
  return knit_span_piece_bounds(g, knit_span(g, codes, rw, knit_piece_column(gp)), gp);
}

/* Quadratic interpolant Q(u) = q0 + q1 u + q2 u^2, u in [0, 1], of the exact
 * curve of row k over global piece gp (t = t0 + u pi/4), through the piece's
 * ends and midpoint. */
KNIT_STRUCT(KQuad)
  kvec3 q0, q1, q2;
  float t0;
KNIT_STRUCT_END(KQuad)

KNIT_FN KQuad knit_quad_from_nodes(kvec3 f0, kvec3 f1, kvec3 f2, float t0) {
  KQuad q;
  q.q0 = f0;
  q.q1 = kv3_sub(kv3_sub(kv3_scale(f1, KF(4.0)), kv3_scale(f0, KF(3.0))), f2);
  q.q2 = kv3_scale(kv3_add(kv3_sub(f0, kv3_scale(f1, KF(2.0))), f2), KF(2.0));
  q.t0 = t0;
  return q;
}

/* Interpolant of span sp's row over global piece gp of its centre column. */
KNIT_FN KQuad knit_span_piece_quad(KNIT_IN(KnitGeom) g, KNIT_IN(KSpan) sp, int gp) {
  int j = gp - 8 * sp.c;
  float t0 = KFLT(gp) * K_PI_4;
  int dn = knit_piece_neighbour(j);
  if (dn == 0 || knit_same_profile(sp.mid, knit_span_cell(sp, sp.c + dn))) {
    float tc = K_2PI * KFLT(sp.c) + K_PI;
    return knit_quad_from_nodes(knit_profile_node(g, sp.mid.code, sp.mid.sg, 2 * j, tc, sp.rw.yk),
                                knit_profile_node(g, sp.mid.code, sp.mid.sg, 2 * j + 1, tc, sp.rw.yk),
                                knit_profile_node(g, sp.mid.code, sp.mid.sg, 2 * j + 2, tc, sp.rw.yk), t0);
  }
  {
    /* Blended piece: interpolate the blended curve at the piece's nodes,
     * lo + w (hi - lo) with lo, hi the profiles left and right of the
     * boundary (knit_blend_curve). The nodes are nodes of both profiles (in
     * the neighbour's numbering 16 apart from the cell's own: its phase is
     * 2 pi off), and the smoothstep's
     * weight there is exact in float: x = (t - tb + pi/4) / (pi/2) is
     * 0, 1/4, 1/2 on piece 7 and 1/2, 3/4, 1 on piece 0, where
     * w(x) = x^3 (10 - 15 x + 6 x^2) is 0, 53/512, 1/2 and 1/2, 459/512, 1.
     * Same nodes as evaluating the blended curve there, without a sine or
     * a cosine. */
    float tc = K_2PI * KFLT(sp.c) + K_PI;
    float ntc = tc + KFLT(dn) * K_2PI;
    KCell ncl = knit_span_cell(sp, sp.c + dn);
    int m0 = 2 * j, nm0 = 2 * j - 16 * dn; /* node of the piece's start, own and neighbour's */
    float w0 = dn > 0 ? KF(0.0) : KF(0.5);
    float w1 = dn > 0 ? KF(0.103515625) : KF(0.896484375);
    float w2 = dn > 0 ? KF(0.5) : KF(1.0);
    kvec3 s0 = knit_profile_node(g, sp.mid.code, sp.mid.sg, m0, tc, sp.rw.yk);
    kvec3 s1 = knit_profile_node(g, sp.mid.code, sp.mid.sg, m0 + 1, tc, sp.rw.yk);
    kvec3 s2 = knit_profile_node(g, sp.mid.code, sp.mid.sg, m0 + 2, tc, sp.rw.yk);
    kvec3 o0 = knit_profile_node(g, ncl.code, ncl.sg, nm0, ntc, sp.rw.yk);
    kvec3 o1 = knit_profile_node(g, ncl.code, ncl.sg, nm0 + 1, ntc, sp.rw.yk);
    kvec3 o2 = knit_profile_node(g, ncl.code, ncl.sg, nm0 + 2, ntc, sp.rw.yk);
    if (dn > 0) { /* the centre cell is left of the boundary */
      return knit_quad_from_nodes(kv3_madd(s0, kv3_sub(o0, s0), w0), kv3_madd(s1, kv3_sub(o1, s1), w1),
                                  kv3_madd(s2, kv3_sub(o2, s2), w2), t0);
    }
    return knit_quad_from_nodes(kv3_madd(o0, kv3_sub(s0, o0), w0), kv3_madd(o1, kv3_sub(s1, o1), w1),
                                kv3_madd(o2, kv3_sub(s2, o2), w2), t0);
  }
}

/* x and y of the interpolant of a row of knit and purl cells over global
 * piece gp (z = 0): the same as knit_span_piece_quad's for any codes (a
 * blend between loops changes z only), without looking at the pattern. */
KNIT_FN KQuad knit_loop_piece_quad_xy(KNIT_IN(KnitGeom) g, float yk, int gp) {
  int j = gp & 7;
  float tc = K_2PI * KFLT(knit_piece_column(gp)) + K_PI;
  kvec3 n0 = knit_loop_node_xy(g, 2 * j, tc, yk);
  kvec3 n1 = knit_loop_node_xy(g, 2 * j + 1, tc, yk);
  kvec3 n2 = knit_loop_node_xy(g, 2 * j + 2, tc, yk);
  return knit_quad_from_nodes(kv3(KX(n0), KY(n0), KF(0.0)), kv3(KX(n1), KY(n1), KF(0.0)),
                              kv3(KX(n2), KY(n2), KF(0.0)), KFLT(gp) * K_PI_4);
}

/* The same for row rw (any global piece). */
KNIT_FN KQuad knit_piece_quad(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KRow) rw, int gp) {
  return knit_span_piece_quad(g, knit_span(g, codes, rw, knit_piece_column(gp)), gp);
}

KNIT_FN kvec3 knit_quad_eval(KNIT_IN(KQuad) q, float x) {
  return kv3_add(q.q0, kv3_scale(kv3_add(q.q1, kv3_scale(q.q2, x)), x));
}

#endif /* KNIT_KERNEL_STITCH_H */
