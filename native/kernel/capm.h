/* Knitshade kernel: curvature-aware parallax mapping (CAPM).
 *
 * Paper Sec. 4.2 and 6.1, Algorithm 1. The view ray hits the base mesh at
 * pattern point (x, y) and enters the yarn shell |z| <= shell_top there. It is
 * marched through the shell in straight segments expressed in the base mesh's
 * local frame; after each segment the host fetches the frame at the new
 * (x, y) and re-expresses the (straight, world-space) ray in it, which bends
 * the ray with the surface (Chen and Chang 2008). The march ends with
 *   HIT      a tube entry inside a segment,
 *   THROUGH  the ray left the shell through the bottom: it passed through a
 *            gap between loops (delta transmission),
 *   ESCAPED  it left through the top, or bent away from a curved base before
 *            reaching any yarn (the silhouette of the paper's Fig. 4 ii),
 *   LIMIT    the step cap was reached (counted as a miss).
 *
 * What differs from the paper's Algorithm 1, and why: the paper steps a
 * point by delta-s and compares its height with a single-valued height
 * query, which cannot see the lower layer under an overhanging loop, and
 * with fixed steps can jump over a tube at grazing angles. Here each step is a
 * straight segment intersected analytically with every tube it passes
 * (query.h), so layers, gaps and grazing rays are exact up to the bending,
 * and a step is as long as the ray may travel before its frame should be
 * refreshed: at most `max_segment` of horizontal travel (one stitch width by
 * default), and never past the shell. On a flat base the march takes
 * ceil(horizontal travel / max_segment) steps: 1 at normal incidence.
 *
 * Curvature-aware metric: at height z above a base of normal curvature
 * (kx, ky) a tangential move of length l covers l / (1 + k z) of the base, so
 * with the curvature known (analytic cylinder/sphere, or estimated from the
 * mesh) the march converges to the exact offset-surface geometry as
 * segments shrink; with an unknown frame field pass 0. */
#ifndef KNIT_KERNEL_CAPM_H
#define KNIT_KERNEL_CAPM_H

#define KNIT_CAPM_MARCHING 0
#define KNIT_CAPM_HIT 1
#define KNIT_CAPM_THROUGH 2
#define KNIT_CAPM_ESCAPED 3
#define KNIT_CAPM_LIMIT 4

KNIT_STRUCT(KnitCapm)
  kvec3 p;           /* current point: pattern x, y and height z above the base */
  kvec3 D;           /* current unit direction in the local frame at p */
  int steps;         /* segments marched */
  int state;         /* KNIT_CAPM_* */
  KnitLineHit hit;   /* valid when state == KNIT_CAPM_HIT */
KNIT_STRUCT_END(KnitCapm)

/* Start at (x, y, shell_top) travelling along -wi (wi in the local frame at
 * (x, y), pointing from the surface to the viewer). */
KNIT_FN KnitCapm knit_capm_begin(KNIT_IN(KnitGeom) g, float x, float y, kvec3 wi_local) {
  KnitCapm st;
  st.p = kv3(x, y, g.shell_top);
  st.D = kv3_neg(kv3_normalize(wi_local));
  st.steps = 0;
  st.state = KZ(st.D) < KF(0.0) ? KNIT_CAPM_MARCHING : KNIT_CAPM_ESCAPED;
  st.hit = knit_line_hit_none();
  return st;
}

/* Start at pattern point p inside or on the shell travelling along dir_local
 * (any direction): for rays that reach the fabric from behind, which enter
 * the shell at its bottom (z = -shell_top) going up. Leaving through the top
 * then ends the march as ESCAPED, through the bottom as THROUGH. */
KNIT_FN KnitCapm knit_capm_begin_at(kvec3 p, kvec3 dir_local) {
  KnitCapm st;
  st.p = p;
  st.D = kv3_normalize(dir_local);
  st.steps = 0;
  st.state = KNIT_CAPM_MARCHING;
  st.hit = knit_line_hit_none();
  return st;
}

/* Length of the next segment along st.D: to the shell's bottom (descending)
 * or top (climbing), and at most max_segment of horizontal travel. */
KNIT_FN float knit_capm_segment(KNIT_IN(KnitGeom) g, KNIT_IN(KnitCapm) st, float max_segment) {
  float dz = KZ(st.D);
  float hs = k_sqrt(KX(st.D) * KX(st.D) + KY(st.D) * KY(st.D));
  float len = K_BIG;
  if (dz < KF(0.0)) len = (KZ(st.p) + g.shell_top) / -dz;
  else if (dz > KF(0.0)) len = (g.shell_top - KZ(st.p)) / dz;
  if (hs > KF(0.0)) len = k_fmin(len, max_segment / hs);
  return k_fmax(len, KF(0.0));
}

/* The segment of length len along st.D in pattern units (tangential travel
 * shrinks by the metric at mid-segment height; kx, ky: base curvature, 0
 * when unknown): KX..KZ of the result's direction times its length lp, i.e.
 * the segment is st.p + u dp, u in [0, len]. */
KNIT_FN kvec3 knit_capm_pattern_step(KNIT_IN(KnitCapm) st, float len, float kx, float ky) {
  float dz = KZ(st.D);
  float z = KZ(st.p) + len * dz;
  float zm = KF(0.5) * (KZ(st.p) + z); /* metric at mid-segment height */
  float mx = KF(1.0) / k_fmax(KF(1.0) + kx * zm, KF(0.1));
  float my = KF(1.0) / k_fmax(KF(1.0) + ky * zm, KF(0.1));
  return kv3(KX(st.D) * mx, KY(st.D) * my, dz);
}

/* One segment of length len along st.D (see knit_capm_segment); kx, ky: base
 * curvature for the metric (0 when unknown). any_hit != 0: a hit need only
 * be a hit, not the nearest (KNIT_QUERY_ANY, for shadow rays). */
KNIT_FN KnitCapm knit_capm_step_len(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                    KNIT_IN(KnitCapm) in, float len, int max_steps, float kx, float ky,
                                    int any_hit) {
  KnitCapm st = in;
  float dz = KZ(st.D);
  float eps = KF(1.0e-4) * g.shell_top;
  kvec3 dp = knit_capm_pattern_step(st, len, kx, ky);
  float lp = kv3_len(dp);
  KnitLineHit h;
  if (st.state != KNIT_CAPM_MARCHING) return st;
  h = knit_line_query(g, codes, colors, st.p, kv3_scale(dp, KF(1.0) / lp), KF(0.0), len * lp,
                      any_hit != 0 ? KNIT_QUERY_ANY : KNIT_QUERY_FIRST);
  st.steps = st.steps + 1;
  if (h.hit != 0) {
    st.state = KNIT_CAPM_HIT;
    st.hit = h;
    return st;
  }
  st.p = kv3_madd(st.p, dp, len);
  if (KZ(st.p) <= eps - g.shell_top) st.state = KNIT_CAPM_THROUGH;
  else if (KZ(st.p) >= g.shell_top - eps && dz >= KF(0.0)) st.state = KNIT_CAPM_ESCAPED;
  else if (st.steps >= max_steps) st.state = KNIT_CAPM_LIMIT;
  return st;
}

KNIT_FN KnitCapm knit_capm_step(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                KNIT_IN(KnitCapm) st, float max_segment, int max_steps, float kx, float ky,
                                int any_hit) {
  return knit_capm_step_len(g, codes, colors, st, knit_capm_segment(g, st, max_segment), max_steps,
                            kx, ky, any_hit);
}

/* Midpoint of the next segment (where a second-order march fetches the frame). */
KNIT_FN kvec3 knit_capm_midpoint(KNIT_IN(KnitGeom) g, KNIT_IN(KnitCapm) st, float max_segment) {
  return kv3_madd(st.p, st.D, KF(0.5) * knit_capm_segment(g, st, max_segment));
}

/* Use dir_local (the ray in the frame at the segment's midpoint) for the
 * segment about to be marched: the midpoint rule, second order in the
 * segment length on a curved base. */
KNIT_FN KnitCapm knit_capm_aim(KNIT_IN(KnitCapm) in, kvec3 dir_local) {
  KnitCapm st = in;
  if (st.state == KNIT_CAPM_MARCHING) st.D = kv3_normalize(dir_local);
  return st;
}

/* Corrector for a segment that hit: `before` is the state the segment
 * started from, `hit` the state after it. The host fetches the frame at
 * knit_capm_hit_midpoint(before, hit) and passes the ray's direction in it;
 * the segment is then re-marched to just past the hit with that direction,
 * which is right to second order in the (shorter) distance to the hit. The
 * original hit is kept if the re-marched segment misses.
 *
 * The corrected ray differs from the first by the frame's turn over half
 * the distance to the hit (a few hundredths of a radian at most, with the
 * segment length bounded by max_bend), so it enters the same tube a little
 * further on: that crossing is refined from the first entry (the entry's
 * Newton search, knit_crossing, on that row's curve: a fraction of a line
 * query). The whole segment is queried again only when the refined entry
 * is not in the segment or moved by more than the tube radius; a tube met
 * first only by the corrected ray would lie within that turn of the first
 * ray's silhouette. */
KNIT_FN kvec3 knit_capm_hit_midpoint(KNIT_IN(KnitCapm) before, KNIT_IN(KnitCapm) hit) {
  return kv3_madd(before.p, before.D, KF(0.5) * k_fmax(hit.hit.s_in, KF(0.0)));
}
/* Length of the corrected segment `again` (knit_capm_aim of the segment's
 * start): to just past the first hit. */
KNIT_FN float knit_capm_correct_len(KNIT_IN(KnitGeom) g, KNIT_IN(KnitCapm) again, KNIT_IN(KnitCapm) hit,
                                    float max_segment) {
  return k_fmin(knit_capm_segment(g, again, max_segment), KF(1.5) * k_fmax(hit.hit.s_in, KF(0.0)) + g.r);
}
KNIT_FN KnitCapm knit_capm_correct(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                   KNIT_IN(KnitCapm) before, KNIT_IN(KnitCapm) hit, kvec3 dir_local, float max_segment,
                                   float kx, float ky) {
  KnitCapm again = knit_capm_aim(before, dir_local);
  float len = knit_capm_correct_len(g, again, hit, max_segment);
  kvec3 dp = knit_capm_pattern_step(again, len, kx, ky);
  float lp = kv3_len(dp);
  if (again.state == KNIT_CAPM_MARCHING && lp > KF(0.0)) {
    kvec3 D = kv3_scale(dp, KF(1.0) / lp);
    KSpan sp = knit_span(g, codes, knit_row(g, hit.hit.row), knit_column_of(hit.hit.t));
    KnitLineHit h = knit_crossing(g, codes, colors, sp, again.p, D, hit.hit.t, 0, KF(0.0));
    if (h.hit != 0 && h.s_in >= KF(0.0) && h.s_in <= len * lp && k_fabs(h.s_in - hit.hit.s_in) <= g.r) {
      again.state = KNIT_CAPM_HIT;
      again.hit = h;
      again.steps = hit.steps;
      return again;
    }
  }
  again = knit_capm_step_len(g, codes, colors, again, len, hit.steps + 1, kx, ky, 0);
  if (again.state != KNIT_CAPM_HIT) return hit;
  again.steps = hit.steps;
  return again;
}

/* Re-express the ray in the frame at the new point: the host passes the
 * world ray direction's components in that frame. A ray that now climbs
 * while already at the shell top has bent away. */
KNIT_FN KnitCapm knit_capm_bend(KNIT_IN(KnitGeom) g, KNIT_IN(KnitCapm) in, kvec3 dir_local) {
  KnitCapm st = in;
  if (st.state != KNIT_CAPM_MARCHING) return st;
  st.D = kv3_normalize(dir_local);
  if (KZ(st.D) >= KF(0.0) && KZ(st.p) >= g.shell_top * KF(0.9999)) st.state = KNIT_CAPM_ESCAPED;
  return st;
}

/* Local direction at pattern offset (dx, dy) from the entry point on a base of
 * constant curvature (kx along x, ky along y): the entry-frame direction d0
 * rotated by the frame's turn, first about the b axis (angle kx dx), then
 * about the t axis (angle ky dy). Exact for a cylinder (ky = 0). */
KNIT_FN kvec3 knit_curved_frame_dir(kvec3 d0, float kx, float ky, float dx, float dy) {
  float ax = kx * dx, ay = ky * dy;
  float cx = k_cos(ax), sx = k_sin(ax), cy = k_cos(ay), sy = k_sin(ay);
  /* frame turned about b by ax: t' = c t - s n, n' = s t + c n */
  float x1 = cx * KX(d0) - sx * KZ(d0);
  float z1 = sx * KX(d0) + cx * KZ(d0);
  /* then about t' by ay: b'' = c b - s n', n'' = s b + c n' */
  return kv3(x1, cy * KY(d0) - sy * z1, sy * KY(d0) + cy * z1);
}

/* Where a view ray enters the shell, for either side of the fabric: wi_local
 * points from the surface to the viewer in the frame at the base hit (x, y).
 * wi.z > 0: the viewer is in front, the ray enters at (x, y, shell_top)
 * going down (knit_capm_begin). wi.z < 0: the viewer is behind the base mesh
 * (the mesh is the shell's top), so the ray crossed the shell before reaching
 * (x, y, shell_top): it is marched from where it entered the shell's bottom,
 * going up; leaving through the top (ESCAPED) means it passed through. */
KNIT_FN KnitCapm knit_capm_start(KNIT_IN(KnitGeom) g, float x, float y, kvec3 wi_local) {
  kvec3 d = kv3_neg(kv3_normalize(wi_local));
  if (KZ(d) > KF(1.0e-6)) {
    float back = KF(2.0) * g.shell_top / KZ(d);
    return knit_capm_begin_at(kv3_madd(kv3(x, y, g.shell_top), d, -back), d);
  }
  return knit_capm_begin(g, x, y, wi_local);
}

/* March st on a base of constant curvature (flat: kx = ky = 0) whose frame at
 * (x, y) sees the ray as d0: midpoint rule and hit corrector as in the host
 * loop (KnitSurface::march). blocked_only != 0: the caller only asks whether
 * the ray is blocked (a shadow ray), so each segment's query stops at the
 * first entry it finds (KNIT_QUERY_ANY), and a hit ends the march as found,
 * without the corrector that places it. */
KNIT_FN KnitCapm knit_capm_march_curved(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                        KNIT_IN(KnitCapm) start, float x, float y, kvec3 d0, float kx, float ky,
                                        float max_segment, int max_steps, int blocked_only) {
  KnitCapm st = start;
  int curved = (kx != KF(0.0) || ky != KF(0.0)) ? 1 : 0;
  int i;
  for (i = 0; i < max_steps && st.state == KNIT_CAPM_MARCHING; i++) {
    KnitCapm before;
    if (curved != 0) {
      kvec3 m = knit_capm_midpoint(g, st, max_segment);
      st = knit_capm_aim(st, knit_curved_frame_dir(d0, kx, ky, KX(m) - x, KY(m) - y));
    }
    before = st;
    st = knit_capm_step(g, codes, colors, st, max_segment, max_steps, kx, ky, blocked_only);
    if (curved != 0 && st.state == KNIT_CAPM_HIT && blocked_only == 0) {
      kvec3 mh = knit_capm_hit_midpoint(before, st);
      st = knit_capm_correct(g, codes, colors, before, st,
                             knit_curved_frame_dir(d0, kx, ky, KX(mh) - x, KY(mh) - y), max_segment,
                             kx, ky);
    }
    if (curved != 0)
      st = knit_capm_bend(g, st, knit_curved_frame_dir(d0, kx, ky, KX(st.p) - x, KY(st.p) - y));
  }
  return st;
}

/* The whole march for a view ray hitting the base at (x, y), either side
 * (knit_capm_start), on a base of constant curvature (flat: kx = ky = 0):
 * what hosts without a frame field run (OSL, with the shading point's
 * curvature). */
KNIT_FN KnitCapm knit_capm_curved(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                  float x, float y, kvec3 wi_local, float kx, float ky,
                                  float max_segment, int max_steps) {
  KnitCapm st = knit_capm_start(g, x, y, wi_local);
  return knit_capm_march_curved(g, codes, colors, st, x, y, kv3_neg(kv3_normalize(wi_local)), kx, ky,
                                max_segment, max_steps, 0);
}

#endif /* KNIT_KERNEL_CAPM_H */
