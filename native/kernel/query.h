/* Knitshade kernel: O(1) analytic intersection of a line with the yarn tubes.
 *
 * Paper Sec. 4.1, Eq. 3-4: the closest approach of a line R(s) = o + s D and a
 * yarn curve Y(t). Eliminating s leaves the distance from Y(t) to the line,
 * which is the distance in the plane perpendicular to D. On each curve piece
 * (pi/4 of t, see stitch.h) Y is replaced by its quadratic interpolant, so the
 * squared distance is a quartic in t and its stationary points are the roots
 * of a cubic, solved in closed form (cubic.h).
 *
 * That closest point is not where the line enters the tube. The tube is the
 * union of the balls of radius r centred on the curve, so along the line the
 * tube occupies [min_t (s(t) - w(t)), max_t (s(t) + w(t))] with
 * s(t) = (Y(t) - o).D and w(t) = sqrt(r^2 - rho(t)^2), rho the distance to the
 * line. Entry and exit are therefore maximisers of -s + w and s + w, not the
 * closest point plus sqrt(r^2 - rho^2) (the paper's construction, wrong where
 * the yarn slopes along the line). Both are found by safeguarded Newton steps
 * on the exact curve, started from the cubic's root after one Newton step on
 * the exact distance. The outward normal at the entry point p is
 * (p - Y(t_in)) / r, exact for the ball-swept tube.
 *
 * Work per line is bounded: the rows and pieces whose bounds come within r of
 * the line's bounding box (at most a few rows and ~8 pieces per row for a line
 * segment no longer than one stitch horizontally). */
#ifndef KNIT_KERNEL_QUERY_H
#define KNIT_KERNEL_QUERY_H

#define KNIT_NEWTON_CLOSEST 1  /* Newton steps on the distance before the extremes */
#define KNIT_NEWTON_EXTREME 10 /* Newton steps for each of entry and exit, at most: the
                                  search stops once a step is below 1e-4. Most searches
                                  stop within 5, but 8.5% of a CAPM ground-truth run's
                                  did not (long climbs along a grazing tube at the 0.25
                                  step limit, or creeping back from a step that landed
                                  near the tube's edge), and left 115 of 46,280 entries
                                  over 0.01 r from the tube ray casts; with 10, 39
                                  searches in 96,143 reach the cap, 8 entries are over
                                  0.01 r, for 2.5% more curve evaluations */
/* Largest |x|, |y| a line query looks at: beyond it the row and piece
 * indices would overflow an int, so the query reports a miss (the hosts
 * reject far smaller coordinates, see kMaxPatternCoord in knit/surface.h). */
#define KNIT_MAX_COORD KF(1.0e7)

/* Result of a line query: the first tube entry with s in [s_min, s_max]. */
KNIT_STRUCT(KnitLineHit)
  int hit;        /* 1 when an entry lies in [s_min, s_max] */
  int crossings;  /* tube crossings overlapping [s_min, s_max] */
  float s_in, s_out; /* entry and exit distances of the first crossing */
  float t;        /* curve parameter of the entry point */
  kvec3 p;        /* entry point, pattern space */
  kvec3 n;        /* outward tube normal at p */
  kvec3 tangent;  /* unit yarn tangent at Y(t) */
  int row, col;   /* cell owning the curve point (row from the bottom, unwrapped) */
  int code, colour; /* stitch code and colour index of that cell */
KNIT_STRUCT_END(KnitLineHit)

KNIT_FN KnitLineHit knit_line_hit_none(KNIT_NOARGS) {
  KnitLineHit h;
  h.hit = 0;
  h.crossings = 0;
  h.s_in = K_BIG;
  h.s_out = K_BIG;
  h.t = KF(0.0);
  h.p = kv3(KF(0.0), KF(0.0), KF(0.0));
  h.n = kv3(KF(0.0), KF(0.0), KF(1.0));
  h.tangent = kv3(KF(1.0), KF(0.0), KF(0.0));
  h.row = 0;
  h.col = 0;
  h.code = 0;
  h.colour = 0;
  return h;
}

/* Reciprocal of a segment direction for knit_segment_box_entry: 0 marks an
 * axis the segment does not move along. */
KNIT_FN kvec3 knit_segment_inv(kvec3 dv) {
  return kv3(k_fabs(KX(dv)) < KF(1.0e-12) ? KF(0.0) : KF(1.0) / KX(dv),
             k_fabs(KY(dv)) < KF(1.0e-12) ? KF(0.0) : KF(1.0) / KY(dv),
             k_fabs(KZ(dv)) < KF(1.0e-12) ? KF(0.0) : KF(1.0) / KZ(dv));
}

/* Slab test of the segment pa + u dv, u in [0, 1], against box b grown by m:
 * the entry parameter u, or -1 when the segment misses the box. inv is
 * knit_segment_inv(dv). */
KNIT_FN float knit_segment_box_entry(kvec3 pa, kvec3 inv, KNIT_IN(KBox) b, float m) {
  float t0 = KF(0.0), t1 = KF(1.0);
  float iv[3], lo[3], hi[3], pv[3];
  int i;
  iv[0] = KX(inv); iv[1] = KY(inv); iv[2] = KZ(inv);
  lo[0] = KX(b.lo) - m; lo[1] = KY(b.lo) - m; lo[2] = KZ(b.lo) - m;
  hi[0] = KX(b.hi) + m; hi[1] = KY(b.hi) + m; hi[2] = KZ(b.hi) + m;
  pv[0] = KX(pa); pv[1] = KY(pa); pv[2] = KZ(pa);
  for (i = 0; i < 3; i++) {
    if (iv[i] == KF(0.0)) {
      if (pv[i] < lo[i] || pv[i] > hi[i]) return KF(-1.0);
    } else {
      float ta = (lo[i] - pv[i]) * iv[i], tb = (hi[i] - pv[i]) * iv[i];
      t0 = k_fmax(t0, k_fmin(ta, tb));
      t1 = k_fmin(t1, k_fmax(ta, tb));
      if (t0 > t1) return KF(-1.0);
    }
  }
  return t0;
}

/* The range of u over which pa + u dv lies inside the slab [lo, hi] of
 * one axis (p = that axis of pa, iv = of knit_segment_inv): KX..KY, empty
 * when KX > KY. Unbounded ([-K_BIG, K_BIG]) for an axis the segment does not
 * move along and starts inside. knit_segment_box_entry's test, one axis. */
KNIT_FN kvec3 knit_slab_range(float lo, float hi, float p, float iv) {
  float ta, tb;
  if (iv == KF(0.0)) {
    if (p < lo || p > hi) return kv3(K_BIG, -K_BIG, KF(0.0));
    return kv3(-K_BIG, K_BIG, KF(0.0));
  }
  ta = (lo - p) * iv;
  tb = (hi - p) * iv;
  return kv3(k_fmin(ta, tb), k_fmax(ta, tb), KF(0.0));
}

/* Whether min |A + B u + C u^2| over u in [0, 1] (a quadratic piece
 * relative to a point, or projected across a line) is sure to exceed m,
 * by two lower bounds of it, the cheaper first:
 *  - the distance of the chord A + u ch (ch = B + C) less |C| / 4, the most
 *    the piece strays from its chord (Q - chord = C (u^2 - u));
 *  - one-sided: with n the unit vector along the part of -C across the
 *    chord, Q(u).n = A.n + |C_across| u (1 - u) >= A.n, so a point on the
 *    far side of the chord from the bulge is at least A.n from every point
 *    of the piece (where the first bound gives away up to |C| / 4).
 * A few operations against the cubic of knit_quad_closest_within, for
 * pieces a line passes far from. The second bound (one_sided != 0) takes
 * an eighth of the cubics of vertical lines away (5% of the batched
 * query's time); on slanted CAPM segments, whose pieces mostly lie near
 * their line, it costs more than it saves (2% more instructions in their
 * line queries on the half cylinder). */
KNIT_FN int knit_quad_beyond(kvec3 A, kvec3 B, kvec3 C, float m, int one_sided) {
  kvec3 ch = kv3_add(B, C);
  float l2 = kv3_len2(ch);
  float uc = l2 > KF(0.0) ? k_clampf(-kv3_dot(A, ch) / l2, KF(0.0), KF(1.0)) : KF(0.0);
  kvec3 across;
  float la;
  if (k_sqrt(kv3_len2(kv3_madd(A, ch, uc))) - KF(0.25) * k_sqrt(kv3_len2(C)) > m) return 1;
  if (one_sided == 0) return 0;
  across = l2 > KF(0.0) ? kv3_madd(C, ch, -kv3_dot(C, ch) / l2) : C;
  la = kv3_len2(across);
  return la > KF(0.0) && -kv3_dot(A, across) > m * k_sqrt(la) ? 1 : 0;
}

/* knit_quad_beyond in x and y from (px, py) to the interpolant q (z
 * ignored), for vertical lines. */
KNIT_FN int knit_quad_xy_beyond(KNIT_IN(KQuad) q, float px, float py, float m) {
  return knit_quad_beyond(kv3(KX(q.q0) - px, KY(q.q0) - py, KF(0.0)), kv3(KX(q.q1), KY(q.q1), KF(0.0)),
                          kv3(KX(q.q2), KY(q.q2), KF(0.0)), m, 1);
}

/* Closest point of a quadratic piece to the line (o, D): u in [0, 1] and the
 * squared distance, from the cubic d/du |P_perp(Q(u) - o)|^2 = 0. KX = u, KY = rho^2.
 * With m < K_BIG, a piece sure to stay farther than m from the line is
 * dismissed before the cubic (KY = K_BIG; knit_quad_beyond, on its
 * projection). */
KNIT_FN kvec3 knit_quad_closest_within(KNIT_IN(KQuad) q, kvec3 o, kvec3 D, float m) {
  kvec3 A0 = kv3_sub(q.q0, o);
  kvec3 A = kv3_madd(A0, D, -kv3_dot(A0, D));
  kvec3 B = kv3_madd(q.q1, D, -kv3_dot(q.q1, D));
  kvec3 C = kv3_madd(q.q2, D, -kv3_dot(q.q2, D));
  KRoots rt;
  float best_u = KF(0.0);
  float best = kv3_len2(A);
  float cand[4];
  float d1;
  int i;
  /* (with a margin, so that rounding never dismisses a piece the cubic keeps) */
  if (m < K_BIG && knit_quad_beyond(A, B, C, m * KF(1.001) + KF(1.0e-4), 0) != 0) return kv3(KF(0.0), K_BIG, KF(0.0));
  rt = solve_cubic(KF(2.0) * kv3_dot(C, C), KF(3.0) * kv3_dot(B, C), kv3_dot(B, B) + KF(2.0) * kv3_dot(A, C),
                   kv3_dot(A, B));
  d1 = kv3_len2(kv3_add(kv3_add(A, B), C));
  if (d1 < best) { best = d1; best_u = KF(1.0); }
  cand[0] = rt.r0; cand[1] = rt.r1; cand[2] = rt.r2; cand[3] = KF(0.0);
  for (i = 0; i < rt.n; i++) {
    float x = cand[i];
    if (x > KF(0.0) && x < KF(1.0)) {
      float dd = kv3_len2(kv3_add(A, kv3_scale(kv3_add(B, kv3_scale(C, x)), x)));
      if (dd < best) { best = dd; best_u = x; }
    }
  }
  return kv3(best_u, best, KF(0.0));
}
KNIT_FN kvec3 knit_quad_closest(KNIT_IN(KQuad) q, kvec3 o, kvec3 D) { return knit_quad_closest_within(q, o, D, K_BIG); }

/* Distance geometry of curve point cv relative to the line (o, D). */
KNIT_STRUCT(KLineRel)
  float s;     /* (Y - o).D, position of the foot point along the line */
  float rho2;  /* squared distance to the line */
  float sd1;   /* Y'.D */
  float sd2;   /* Y''.D */
  float phi1;  /* d/dt rho^2 / 2 */
  float phi2;  /* d2/dt2 rho^2 / 2 */
KNIT_STRUCT_END(KLineRel)

KNIT_FN KLineRel knit_line_rel(KNIT_IN(KCurve) cv, kvec3 o, kvec3 D) {
  KLineRel lr;
  kvec3 q = kv3_sub(cv.p, o);
  kvec3 e;
  lr.s = kv3_dot(q, D);
  e = kv3_madd(q, D, -lr.s);
  lr.rho2 = kv3_len2(e);
  lr.sd1 = kv3_dot(cv.d1, D);
  lr.sd2 = kv3_dot(cv.d2, D);
  lr.phi1 = kv3_dot(e, cv.d1);
  lr.phi2 = kv3_len2(cv.d1) - lr.sd1 * lr.sd1 + kv3_dot(e, cv.d2);
  return lr;
}

/* Newton on the exact squared distance to the line. */
KNIT_FN float knit_newton_closest(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KSpan) sp, kvec3 o, kvec3 D,
                                  float t_start, int iters) {
  float t = t_start;
  int i;
  for (i = 0; i < iters; i++) {
    KLineRel lr = knit_line_rel(knit_span_curve_at(g, codes, sp, t), o, D);
    if (lr.phi2 <= KF(0.0)) break;
    t = t - k_clampf(lr.phi1 / lr.phi2, KF(-0.4), KF(0.4));
  }
  return t;
}

/* A curve point found by a Newton search, with its relation to the line. */
KNIT_STRUCT(KExtreme)
  float t;
  KCurve cv;
  KLineRel lr;
  int capped;  /* the search stopped above f_cap (knit_newton_extreme) */
KNIT_STRUCT_END(KExtreme)

/* Maximise sgn * s(t) + w(t), w = sqrt(r^2 - rho^2): sgn = -1 gives the entry,
 * +1 the exit. Safeguarded Newton: a step that leaves the tube (rho >= r) or
 * lowers the objective is halved. Returns the last point evaluated (rho may be
 * >= r when t_start was outside the tube). The objective only grows, so once
 * it exceeds f_cap the result would too: the search stops there with
 * capped = 1 (K_BIG: never). */
KNIT_FN KExtreme knit_newton_extreme(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KSpan) sp, kvec3 o, kvec3 D,
                                     float t_start, float sgn, int iters, float f_cap) {
  KExtreme e;
  float r2 = g.r * g.r;
  int i;
  float t_prev = KF(0.0), f1_prev = KF(0.0); /* the last accepted point before this one */
  e.t = t_start;
  e.capped = 0;
  e.cv = knit_span_curve_at(g, codes, sp, e.t);
  e.lr = knit_line_rel(e.cv, o, D);
  if (e.lr.rho2 >= r2) return e;
  for (i = 0; i < iters; i++) {
    float w = k_sqrt(r2 - e.lr.rho2);
    float f = sgn * e.lr.s + w;
    float f1, f2, step;
    int tries;
    int moved = 0;
    if (f > f_cap) {
      e.capped = 1;
      return e;
    }
    f1 = sgn * e.lr.sd1 - e.lr.phi1 / w;
    f2 = sgn * e.lr.sd2 - e.lr.phi2 / w - e.lr.phi1 * e.lr.phi1 / (w * w * w);
    if (f2 < KF(0.0)) step = -f1 / f2;
    else step = f1 * KF(0.05);  /* not concave here: small uphill step */
    step = k_clampf(step, KF(-0.25), KF(0.25));
    /* At the tube's edge (w < 0.05 r: rho within 0.13% of r) w's square
     * root makes f'' grow faster than f', and Newton's step can fall below
     * the tolerance far from the maximum. When f' has changed sign since
     * the last point, the maximum lies between the two: bisect instead of
     * stopping. */
    if (k_fabs(step) < KF(1.0e-4) && i > 0 && w < KF(0.05) * g.r && (f1 < KF(0.0)) != (f1_prev < KF(0.0)))
      step = KF(0.5) * (t_prev - e.t);
    if (k_fabs(step) < KF(1.0e-4)) break;
    t_prev = e.t;
    f1_prev = f1;
    for (tries = 0; tries < 4 && moved == 0; tries++) {
      KCurve nc = knit_span_curve_at(g, codes, sp, e.t + step);
      KLineRel nl = knit_line_rel(nc, o, D);
      if (nl.rho2 < r2 && sgn * nl.s + k_sqrt(r2 - nl.rho2) >= f) {
        e.t = e.t + step;
        e.cv = nc;
        e.lr = nl;
        moved = 1;
      } else {
        step = step * KF(0.5);
      }
    }
    if (moved == 0) break;
  }
  return e;
}

/* The crossing of span sp's row tube found from curve parameter t_close
 * (the exact curve's point closest to the line, knit_piece_closest_t).
 * Fills s_in, s_out, t, p, n, tangent, row, col, code, color; hit = 1 when
 * the line does pass through the tube. Without the exit (need_exit = 0),
 * a crossing whose entry is sure to come before s_floor is not searched
 * for and reported as a miss: every point the search passes bounds the
 * entry from above (s_in <= s(t) - w(t), the entry maximising w - s), so
 * it stops once that bound is below s_floor (-K_BIG: never). A start
 * point on or inside a tube, the next step of a path, thus skips that
 * tube's crossing behind it. */
KNIT_FN KnitLineHit knit_crossing(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                  KNIT_IN(KSpan) sp, kvec3 o, kvec3 D, float t_close, int need_exit, float s_floor) {
  KnitLineHit h = knit_line_hit_none();
  float r2 = g.r * g.r;
  KExtreme ein = knit_newton_extreme(g, codes, sp, o, D, t_close, KF(-1.0), KNIT_NEWTON_EXTREME,
                                     need_exit != 0 ? K_BIG : -s_floor);
  int c, ci;
  if (ein.lr.rho2 >= r2 || ein.capped != 0) return h;
  if (need_exit != 0) {
    KExtreme eout = knit_newton_extreme(g, codes, sp, o, D, t_close, KF(1.0), KNIT_NEWTON_EXTREME, K_BIG);
    if (eout.lr.rho2 >= r2) return h;
    h.s_out = eout.lr.s + k_sqrt(r2 - eout.lr.rho2);
  }
  h.hit = 1;
  h.s_in = ein.lr.s - k_sqrt(r2 - ein.lr.rho2);
  h.t = ein.t;
  h.p = kv3_madd(o, D, h.s_in);
  h.n = kv3_normalize(kv3_sub(h.p, ein.cv.p));
  h.tangent = kv3_normalize(ein.cv.d1);
  c = knit_column_of(ein.t);
  ci = knit_span_covers(sp, c) != 0 ? knit_span_index(sp, c) : k_modi(c, g.cols);
  h.row = sp.rw.k;
  h.col = c;
  h.code = codes[sp.rw.off + ci];
  h.colour = colors[sp.rw.off + ci];
  return h;
}

/* What a line query computes (its `mode`). */
#define KNIT_QUERY_ENTRY 0  /* first entry and crossing count (s_out not computed) */
#define KNIT_QUERY_EXIT 1   /* also the exit of the first crossing */
#define KNIT_QUERY_COUNT 2  /* crossing count only: no entry points (hit stays 0) */
#define KNIT_QUERY_FIRST 3  /* first entry only (crossings stays 0): the pieces are
                               visited nearest first and the search stops at the
                               first piece the line reaches beyond the best entry */
#define KNIT_QUERY_ANY 4    /* whether the line enters a tube in [s_min, s_max] (a
                               shadow ray): FIRST's search, stopped at the first
                               entry found, which need not be the nearest */

/* Candidate pieces a FIRST query can order; more are processed unordered. */
#define KNIT_QUERY_MAX_CAND 48

/* Curve parameter of the point of span sp's row closest to the line (o, D)
 * found from piece gp of the span's centre column (quadratic interpolant,
 * cubic, one Newton step on the exact curve), or K_BIG when the interpolant
 * stays farther than m from the line. */
KNIT_FN float knit_piece_closest_t(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_IN(KSpan) sp, int gp,
                                   kvec3 o, kvec3 D, float m) {
  KQuad q = knit_span_piece_quad(g, sp, gp);
  kvec3 cu = knit_quad_closest_within(q, o, D, m);
  if (KY(cu) > m * m) return K_BIG;
  return knit_newton_closest(g, codes, sp, o, D, q.t0 + KX(cu) * KNIT_PIECE_LEN, KNIT_NEWTON_CLOSEST);
}

/* First tube entry along o + s D with s in [s_min, s_max] (D unit), and the
 * number of tube crossings overlapping that range; see KNIT_QUERY_* for
 * `mode`. Without exits (ENTRY) s_out is K_BIG and crossings counts entries
 * up to s_max whose tube may reach s_min; COUNT counts the tubes the line
 * passes within r of, from the closest points alone (what the layer count
 * under a point needs, at a fraction of the cost). */
KNIT_FN KnitLineHit knit_line_query(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                    kvec3 o, kvec3 D, float s_min, float s_max, int mode) {
  KnitLineHit best = knit_line_hit_none();
  kvec3 pa = kv3_madd(o, D, s_min), pb = kv3_madd(o, D, s_max);
  kvec3 inv = knit_segment_inv(kv3_sub(pb, pa));
  float rr = g.r * KF(1.001) + KF(1.0e-4);
  float m = g.r + g.quad_margin;
  float mxy = g.r + g.quad_margin_xy; /* (vertical lines, below) */
  /* Clamped (NaN included) so that the index conversions below stay defined;
   * a segment reaching beyond KNIT_MAX_COORD returns a miss. */
  float xmin = k_clampf(k_fmin(KX(pa), KX(pb)), -KNIT_MAX_COORD, KNIT_MAX_COORD);
  float xmax = k_clampf(k_fmax(KX(pa), KX(pb)), -KNIT_MAX_COORD, KNIT_MAX_COORD);
  float ymin = k_clampf(k_fmin(KY(pa), KY(pb)), -KNIT_MAX_COORD, KNIT_MAX_COORD);
  float ymax = k_clampf(k_fmax(KY(pa), KY(pb)), -KNIT_MAX_COORD, KNIT_MAX_COORD);
  int inside = k_fabs(KX(pa)) < KNIT_MAX_COORD && k_fabs(KX(pb)) < KNIT_MAX_COORD &&
                       k_fabs(KY(pa)) < KNIT_MAX_COORD && k_fabs(KY(pb)) < KNIT_MAX_COORD
                   ? 1 : 0;
  int k0 = KINT(k_ceil((ymin - g.h - rr) / g.row_spacing - KF(0.5)));
  int k1 = KINT(k_floor((ymax + g.h + rr) / g.row_spacing - KF(0.5)));
  float xa = g.has_floats != 0 ? k_fmax(g.a, KF(0.0)) : g.a;
  int g0 = KINT(k_floor((xmin - rr - xa) / KNIT_PIECE_LEN));
  int g1 = KINT(k_floor((xmax + rr + xa) / KNIT_PIECE_LEN));
  int count = 0;
  int k, gp, i, j;
  /* The cheap cull (knit_segment_box_entry against knit_piece_bounds_xy,
   * grown by rr), taken apart by axis: the z slab is the same for every
   * piece, the y slab depends on the row and the piece's place j in its
   * cell, the x slab on the piece. Same values, same result, without
   * recomputing the boxes and the z and y slabs for every piece. */
  float oxl[8], oxh[8], oyl[8], oyh[8]; /* knit_piece_offsets_xy by j */
  float uyl[8], uyh[8];                 /* y slab's u range by j, current row */
  kvec3 uz;
  float ul0, ul1;
  /* FIRST: candidates (row, piece, entry distance of their box) */
  float cand_s[KNIT_QUERY_MAX_CAND];
  int cand_k[KNIT_QUERY_MAX_CAND], cand_g[KNIT_QUERY_MAX_CAND];
  int ncand = 0;
  int next_bi = -1; /* FIRST: the candidate to visit next, when known */
  /* FIRST: the crossings whose search gave an entry (row, closest-point
   * parameter), so that one found again from a neighbouring piece is not
   * searched twice */
  float done_t[KNIT_QUERY_MAX_CAND];
  int done_k[KNIT_QUERY_MAX_CAND];
  int ndone = 0;
  /* The span of the last candidate (row sp.rw.k, column sp.c, once have_sp):
   * pieces of one cell share it. */
  KSpan sp;
  int have_sp = 0;
  int first = mode == KNIT_QUERY_FIRST || mode == KNIT_QUERY_ANY ? 1 : 0; /* ordered search */
  /* The exact piece bounds refine only z (and slip-stitch floats): skip
   * them when the segment is vertical and spans the whole shell in z (FIRST
   * then visits the pieces unordered: their boxes would not order them). */
  int vertical = g.has_floats == 0 && KX(inv) == KF(0.0) && KY(inv) == KF(0.0) ? 1 : 0; /* no floats either */
  int skip_exact = vertical != 0 && k_fmin(KZ(pa), KZ(pb)) <= -g.shell_top && k_fmax(KZ(pa), KZ(pb)) >= g.shell_top
                       ? 1 : 0;
  /* Vertical lines through knit and purl rows test the distance in x and y
   * before looking at the pattern (FIRST and ANY queries order their pieces
   * first, unless they skip the exact bounds). */
  int xy_first = vertical != 0 && (first == 0 || skip_exact != 0) ? 1 : 0;
  if (inside == 0) return best;
  for (j = 0; j < 8; j++) {
    KBox off = knit_piece_offsets_xy(g, j);
    oxl[j] = KX(off.lo);
    oxh[j] = KX(off.hi);
    oyl[j] = KY(off.lo);
    oyh[j] = KY(off.hi);
    if (j == 0) uz = knit_slab_range(KZ(off.lo) - rr, KZ(off.hi) + rr, KZ(pa), KZ(inv));
  }
  ul0 = k_fmax(KF(0.0), KX(uz));
  ul1 = k_fmin(KF(1.0), KY(uz));
  if (ul0 > ul1) return best;
  for (k = k0; k <= k1; k++) {
    float last_t = -K_BIG, prev_t = -K_BIG;
    KRow rw = knit_row(g, k);
    float ru0 = K_BIG, ru1 = -K_BIG, xr0, xr1, xm;
    int rg0, rg1;
    for (j = 0; j < 8; j++) {
      kvec3 uy = knit_slab_range((rw.yk + oyl[j]) - rr, (rw.yk + oyh[j]) + rr, KY(pa), KY(inv));
      uyl[j] = k_fmax(ul0, KX(uy));
      uyh[j] = k_fmin(ul1, KY(uy));
      if (uyl[j] <= uyh[j]) {
        ru0 = k_fmin(ru0, uyl[j]);
        ru1 = k_fmax(ru1, uyh[j]);
      }
    }
    if (ru0 > ru1) continue; /* the segment misses the row's band */
    /* The pieces of this row the slab tests below can pass: those within
     * the segment's x extent over the part of it in the row's band, widened
     * by r, the loop's reach a and, against rounding, two pieces and 1e-6 of
     * the coordinates. Without it a long slanted segment would test every
     * piece of its bounding box in every row (rows x pieces, not rows +
     * pieces); the pieces skipped all fail the x slab test. */
    xr0 = KX(pa) + (KX(pb) - KX(pa)) * ru0;
    xr1 = KX(pa) + (KX(pb) - KX(pa)) * ru1;
    xm = rr + xa + KF(2.0) * KNIT_PIECE_LEN + KF(1.0e-6) * (k_fabs(KX(pa)) + k_fabs(KX(pb)));
    rg0 = KINT(k_floor((k_fmin(xr0, xr1) - xm) / KNIT_PIECE_LEN));
    rg1 = KINT(k_floor((k_fmax(xr0, xr1) + xm) / KNIT_PIECE_LEN));
    for (gp = k_maxi(g0, rg0); gp <= k_mini(g1, rg1); gp++) {
      float t, u, t0 = KFLT(gp) * K_PI_4, t_start = KF(0.0);
      int jp = gp & 7;
      kvec3 ux;
      KnitLineHit h;
      int c;
      /* Cheap cull first (no pattern lookups), then (unordered queries) the
       * exact piece box. */
      if (uyl[jp] > uyh[jp]) continue;
      ux = knit_slab_range((t0 + oxl[jp]) - rr, (t0 + K_PI_4 + oxh[jp]) + rr, KX(pa), KX(inv));
      u = k_fmax(uyl[jp], KX(ux));
      if (u > k_fmin(uyh[jp], KY(ux))) continue;
      if (first != 0 && skip_exact == 0 && ncand < KNIT_QUERY_MAX_CAND) {
        /* ordered below by this entry (a lower bound of any entry into the
         * piece's tube) */
        cand_s[ncand] = s_min + u * (s_max - s_min);
        cand_k[ncand] = k;
        cand_g[ncand] = gp;
        ncand = ncand + 1;
        continue;
      }
      if (xy_first != 0) {
        /* A vertical line's distance to a knit or purl yarn lies in x and
         * y, which do not depend on the codes: the interpolant's closest
         * point, without looking at the pattern (the same as
         * knit_piece_closest_t's up to rounding in blended pieces). */
        KQuad qx = knit_loop_piece_quad_xy(g, rw.yk, gp);
        kvec3 cu;
        /* (with a margin, so that rounding never drops a piece the cubic
         * keeps; and the margin in x and y alone, quad_margin_xy: a piece
         * farther than r plus it from the line has no point in the tube) */
        if (knit_quad_xy_beyond(qx, KX(o), KY(o), mxy * KF(1.001) + KF(1.0e-4)) != 0) continue;
        cu = knit_quad_closest(qx, o, D);
        if (KY(cu) > mxy * mxy) continue;
        t_start = qx.t0 + KX(cu) * KNIT_PIECE_LEN;
      }
      c = knit_piece_column(gp);
      if (have_sp == 0 || sp.rw.k != k || sp.c != c) {
        sp = knit_span(g, codes, rw, c);
        have_sp = 1;
      }
      if (skip_exact == 0) {
        u = knit_segment_box_entry(pa, inv, knit_span_piece_bounds(g, sp, gp), rr);
        if (u < KF(0.0)) continue;
      }
      /* A crossing found again from the neighbouring piece has the same
       * closest point: counted once. */
      t = xy_first != 0 ? knit_newton_closest(g, codes, sp, o, D, t_start, KNIT_NEWTON_CLOSEST)
                        : knit_piece_closest_t(g, codes, sp, gp, o, D, m);
      if (t == K_BIG || k_fabs(t - last_t) < KF(0.1) || k_fabs(t - prev_t) < KF(0.1)) continue;
      if (mode == KNIT_QUERY_COUNT) {
        KCurve cc = knit_span_curve_at(g, codes, sp, t);
        KLineRel lc = knit_line_rel(cc, o, D);
        if (lc.rho2 < g.r * g.r) {
          prev_t = last_t;
          last_t = t;
          count = count + 1;
        }
        continue;
      }
      h = knit_crossing(g, codes, colors, sp, o, D, t, mode == KNIT_QUERY_EXIT ? 1 : 0,
                        first != 0 ? s_min : -K_BIG);
      if (h.hit == 0) continue;
      prev_t = last_t;
      last_t = t;
      if (h.s_out >= s_min && h.s_in <= s_max) count = count + 1;
      if (h.s_in >= s_min && h.s_in <= s_max && h.s_in < best.s_in) best = h;
      if (mode == KNIT_QUERY_ANY && best.hit != 0) return best;
    }
  }
  /* FIRST: nearest box first; no later box can hold an entry before the best.
   * A scan finds the nearest box left and the one after it (ties in index
   * order), which is the next visited without another scan. */
  for (j = 0; j < ncand; j++) {
    int bi = -1;
    float bs = K_BIG;
    KnitLineHit h;
    float t;
    int c, dup;
    if (next_bi >= 0) {
      bi = next_bi;
      bs = cand_s[bi];
      next_bi = -1;
    } else {
      float bs2 = K_BIG;
      for (i = 0; i < ncand; i++) {
        float v = cand_s[i];
        if (v < bs) {
          bs2 = bs;
          next_bi = bi;
          bs = v;
          bi = i;
        } else if (v < bs2) {
          bs2 = v;
          next_bi = i;
        }
      }
    }
    if (bi < 0 || bs > best.s_in) break;
    cand_s[bi] = K_BIG;
    /* No exact piece box here (knit_span_piece_bounds): on near-field
     * renders it culled a fifth of these candidates at twice the cost of the
     * closest points it saved. */
    c = knit_piece_column(cand_g[bi]);
    if (have_sp == 0 || sp.rw.k != cand_k[bi] || sp.c != c) {
      sp = knit_span(g, codes, knit_row(g, cand_k[bi]), c);
      have_sp = 1;
    }
    t = knit_piece_closest_t(g, codes, sp, cand_g[bi], o, D, m);
    if (t == K_BIG) continue;
    /* A crossing found again from another piece of its row (closest points
     * within 0.1, the unordered loop's test) that gave an entry was
     * searched already: the entry is in best or beyond it. (Not in patterns
     * with slip stitches, where a search from the other piece found a
     * better entry in 3 of 40,000 segments: docs/geometry.md.) */
    dup = 0;
    for (i = 0; i < ndone && dup == 0; i++)
      if (done_k[i] == cand_k[bi] && k_fabs(t - done_t[i]) < KF(0.1)) dup = 1;
    if (dup != 0) continue;
    h = knit_crossing(g, codes, colors, sp, o, D, t, 0, s_min);
    if (h.hit != 0 && g.has_floats == 0) {
      done_k[ndone] = cand_k[bi];
      done_t[ndone] = t;
      ndone = ndone + 1;
    }
    if (h.hit != 0 && h.s_in >= s_min && h.s_in <= s_max && h.s_in < best.s_in) {
      best = h;
      if (mode == KNIT_QUERY_ANY) break;
    }
  }
  best.crossings = first != 0 ? 0 : count;
  return best;
}

/* Vertical query at (x, y): the first tube surface seen from above, and the
 * number of tubes the vertical line crosses (paper's height query, made right
 * for overlapping layers). */
KNIT_FN KnitLineHit knit_vertical_query(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                        float x, float y) {
  float top = g.shell_top + KF(0.01);
  return knit_line_query(g, codes, colors, kv3(x, y, top), kv3(KF(0.0), KF(0.0), KF(-1.0)),
                         KF(0.0), KF(2.0) * top, KNIT_QUERY_ENTRY);
}

/* Number of tubes the vertical line through (x, y) crosses (the layer count
 * of the double-layer attenuation), without computing entry points. */
KNIT_FN int knit_vertical_layers(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors), float x,
                                 float y) {
  float top = g.shell_top + KF(0.01);
  KnitLineHit h = knit_line_query(g, codes, colors, kv3(x, y, top), kv3(KF(0.0), KF(0.0), KF(-1.0)), KF(0.0),
                                  KF(2.0) * top, KNIT_QUERY_COUNT);
  return h.crossings;
}

#endif /* KNIT_KERNEL_QUERY_H */
