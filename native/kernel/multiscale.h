/* Knitshade kernel: multi-scale aggregation over a pixel's footprint.
 *
 * Paper Sec. 5.1 and 6.2. A camera ray's footprint on the fabric, from its
 * ray differentials, is the parallelogram spanned in pattern space by
 * (dx/dpx, dy/dpx) and (dx/dpy, dy/dpy) around the hit point. N points of a
 * 2D Sobol' sequence (Cranley-Patterson shifted per shading point) are placed
 * over it; each is marched with CAPM along the same view direction and the
 * results are aggregated:
 *   p_delta   fraction of the footprint the ray passes through (misses),
 *   n         mean normal of the yarn surface hit, in the base frame,
 *   sigma     LEAN covariance (Olano and Baker 2010, paper Eq. 10) of the hit
 *             normals' slopes (n.x/n.z, n.y/n.z) around their mean, to be added
 *             to the specular lobe's own slope covariance (paper Eq. 11),
 *   tangent   mean yarn tangent (sign-aligned), for the anisotropic lobe,
 *   layers    mean tube count under the hits (double-layer attenuation),
 *   color_w   share of hits per colour index (up to KNIT_MS_COLORS).
 * As the footprint shrinks to a point every sample is the same CAPM ray, so
 * the result is the near-field hit (sigma = 0, p_delta 0 or 1).
 *
 * Footprints of a stitch cell or more: the yarn repeats cell by cell, so
 * what matters for a footprint's average is where inside a cell each point
 * lands, then which cells. Points are therefore placed cell-stratified: the
 * Sobol' point gives the position inside a cell (a (0,2)-net over the cell),
 * an additive recurrence on the golden ratio picks the cell among those the
 * footprint's bounding box covers. On a uniform pattern the aggregate then
 * no longer depends on where the footprint lies, only on its size; and the
 * point count grows with the number of cells covered (x n_points per 16
 * cells, up to KNIT_MS_MAX_POINTS), so mixed patterns average too.
 *
 * Slopes of grazing normals are clamped at KNIT_MS_MAX_SLOPE (normal z >=
 * 0.24): the LEAN covariance of a field of round tubes is otherwise dominated
 * by a few silhouette samples. Seen from behind, slopes are taken against
 * -z, the side the hits face.
 *
 * Colours: color_w is a histogram over the first KNIT_MS_COLORS indices
 * (enough for most patterns; the host mixes its palette with it); for any
 * number of colours, color_pick is the colour of one hit chosen from the
 * shift, so that over a pixel's samples colours mix in proportion. */
#ifndef KNIT_KERNEL_MULTISCALE_H
#define KNIT_KERNEL_MULTISCALE_H

#define KNIT_MS_MAX_POINTS 64
#define KNIT_MS_MAX_CELLS KF(1.0e5) /* footprint extent cap per axis, in cells */
#define KNIT_MS_COLORS 8
#define KNIT_MS_MAX_SLOPE KF(4.0)

KNIT_STRUCT(KnitAggregate)
  int points;       /* footprint points marched */
  int hits;         /* of which hit a yarn */
  float p_delta;    /* (n - hits) / n */
  kvec3 n;          /* mean hit normal (unit), base frame */
  kvec3 tangent;    /* mean yarn tangent (unit), base frame */
  float sxx, sxy, syy; /* LEAN slope covariance of the hit normals */
  float layers;     /* mean tube count under the hits */
  float steps;      /* mean CAPM segments per point */
  float color_w[KNIT_MS_COLORS]; /* share of hits per colour index (last bin: >= 7) */
  int color_pick;   /* colour index of one hit chosen by the shift (any index; -1 if none) */
  kvec3 position;   /* mean hit position (pattern space) */
KNIT_STRUCT_END(KnitAggregate)

/* Slopes (n.x/n.z, n.y/n.z) of a hit normal n seen from side (+1 front, -1
 * behind: against -z), clamped at KNIT_MS_MAX_SLOPE (KZ unused). */
KNIT_FN kvec3 knit_ms_slopes(kvec3 n, float side) {
  float nz = k_fmax(side * KZ(n), KF(1.0) / k_sqrt(KF(1.0) + KNIT_MS_MAX_SLOPE * KNIT_MS_MAX_SLOPE));
  return kv3(k_clampf(KX(n) / nz, -KNIT_MS_MAX_SLOPE, KNIT_MS_MAX_SLOPE),
             k_clampf(KY(n) / nz, -KNIT_MS_MAX_SLOPE, KNIT_MS_MAX_SLOPE), KF(0.0));
}

/* Point i of the 2D Sobol' sequence in [0,1)^2, 24-bit: the first dimension
 * is the base-2 radical inverse, the second uses Sobol's direction numbers
 * v_k = v_{k-1} xor (v_{k-1} >> 1). KZ is unused. */
KNIT_FN kvec3 knit_sobol2(int i) {
  int x = 0, y = 0;
  int vx = 8388608; /* 1 << 23 */
  int vy = 8388608;
  int b = i;
  int bit;
  for (bit = 0; bit < 24 && b != 0; bit++) {
    if ((b & 1) != 0) {
      x = x ^ vx;
      y = y ^ vy;
    }
    b = b >> 1;
    vx = vx >> 1;
    vy = vy ^ (vy >> 1);
  }
  return kv3(KFLT(x) / KF(16777216.0), KFLT(y) / KF(16777216.0), KF(0.0));
}

KNIT_FN float knit_frac(float x) { return x - k_floor(x); }

/* Where the footprint's points go (see the file header). */
KNIT_STRUCT(KFootprint)
  float x, y;          /* centre, pattern space */
  kvec3 fx, fy;        /* spanning vectors (KZ unused) */
  float shift_x, shift_y;
  int stratified;      /* 1: cell-stratified placement */
  int ncx, ncy;        /* cells covered (stratified) */
  int bx0, by0;        /* first cell of the box (the ncx x ncy cells nearest the footprint) */
  int n;               /* points */
KNIT_STRUCT_END(KFootprint)

/* The footprint's box extent in cells, x (KX) and y (KY); clamped (NaN to
 * 0) so that cell indices fit an int even for the huge footprints of
 * grazing rays. */
KNIT_FN kvec3 knit_footprint_extent(KNIT_IN(KnitGeom) g, kvec3 fx, kvec3 fy) {
  float cw = K_2PI, ch = g.row_spacing;
  return kv3(k_clampf((k_fabs(KX(fx)) + k_fabs(KX(fy))) / cw, KF(0.0), KNIT_MS_MAX_CELLS),
             k_clampf((k_fabs(KY(fx)) + k_fabs(KY(fy))) / ch, KF(0.0), KNIT_MS_MAX_CELLS), KF(0.0));
}

/* Whether knit_footprint stratifies the footprint by cell (a cell or more
 * in both directions), without the rest of it. */
KNIT_FN int knit_footprint_stratified(KNIT_IN(KnitGeom) g, kvec3 fx, kvec3 fy) {
  kvec3 e = knit_footprint_extent(g, fx, fy);
  return (KX(e) >= KF(1.0) && KY(e) >= KF(1.0)) ? 1 : 0;
}

KNIT_FN KFootprint knit_footprint(KNIT_IN(KnitGeom) g, float x, float y, kvec3 fx, kvec3 fy, int n_points,
                                  float shift_x, float shift_y) {
  KFootprint f;
  float cw = K_2PI, ch = g.row_spacing;
  kvec3 e = knit_footprint_extent(g, fx, fy); /* the box, in cells */
  float ex = KX(e), ey = KY(e);
  f.x = x;
  f.y = y;
  f.fx = fx;
  f.fy = fy;
  f.shift_x = shift_x;
  f.shift_y = shift_y;
  f.stratified = (ex >= KF(1.0) && ey >= KF(1.0)) ? 1 : 0;
  f.ncx = KINT(k_floor(ex));
  f.ncy = KINT(k_floor(ey));
  /* The ncx x ncy whole cells nearest the footprint: the box's first cell
   * rounded (not floored) from x / cw - ncx / 2, so that the box is centred
   * on the footprint within half a cell (a floor put it up to a whole cell
   * left of and below it, half a cell on average). */
  f.bx0 = KINT(k_floor(x / cw - KF(0.5) * KFLT(f.ncx) + KF(0.5)));
  f.by0 = KINT(k_floor(y / ch - KF(0.5) * KFLT(f.ncy) + KF(0.5)));
  f.n = k_maxi(1, k_mini(n_points, KNIT_MS_MAX_POINTS));
  if (f.stratified != 0) {
    /* n_points per 16 cells, at most KNIT_MS_MAX_POINTS: the factor is capped
     * before the product, which overflowed an int for boxes of 10^10 cells. */
    float cells = KFLT(f.ncx) * KFLT(f.ncy);
    int per16 = KINT(k_ceil(k_fmin(cells / KF(16.0), KFLT(KNIT_MS_MAX_POINTS))));
    f.n = k_mini(KNIT_MS_MAX_POINTS, f.n * k_maxi(1, per16));
  }
  return f;
}

/* Point i of the footprint (KZ unused). */
KNIT_FN kvec3 knit_footprint_point(KNIT_IN(KnitGeom) g, KNIT_IN(KFootprint) f, int i) {
  kvec3 q = knit_sobol2(i);
  float ox = knit_frac(KX(q) + f.shift_x);
  float oy = knit_frac(KY(q) + f.shift_y);
  if (f.stratified != 0) {
    /* golden-ratio recurrences pick the cell; the net places the point in it */
    int cx = KINT(k_floor(KFLT(f.ncx) * knit_frac(KF(0.61803398875) * KFLT(i) + f.shift_y)));
    int cy = KINT(k_floor(KFLT(f.ncy) * knit_frac(KF(0.75487766625) * KFLT(i) + f.shift_x)));
    return kv3((KFLT(f.bx0 + cx) + ox) * K_2PI, (KFLT(f.by0 + cy) + oy) * g.row_spacing, KF(0.0));
  }
  return kv3(f.x + (ox - KF(0.5)) * KX(f.fx) + (oy - KF(0.5)) * KX(f.fy),
             f.y + (ox - KF(0.5)) * KY(f.fx) + (oy - KF(0.5)) * KY(f.fy), KF(0.0));
}

/* Only p_delta of knit_aggregate (same points, same marches): what a shadow
 * ray crossing a multi-scale fabric needs. */
KNIT_FN float knit_footprint_p_delta(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                     KNIT_IN(KFootprint) f, kvec3 wi_local, float kx, float ky, float max_segment,
                                     int max_steps) {
  int i, hits = 0;
  for (i = 0; i < f.n; i++) {
    kvec3 pt = knit_footprint_point(g, f, i);
    KnitCapm st = knit_capm_curved(g, codes, colors, KX(pt), KY(pt), wi_local, kx, ky, max_segment, max_steps);
    if (st.state == KNIT_CAPM_HIT) hits = hits + 1;
  }
  return KFLT(f.n - hits) / KFLT(f.n);
}

/* The running sums of an aggregate, point by point: knit_agg_begin, then
 * knit_agg_add for each footprint point in order with its march (and, for a
 * hit, the layer count under it), then knit_agg_finish. knit_aggregate is
 * that loop; a host that marches the points itself (the OSL shader, whose
 * near field is a footprint of one point) calls the three and keeps one
 * march in its code. */
KNIT_STRUCT(KAggSum)
  int n;            /* the footprint's point count */
  int hits;
  int pick;         /* the point whose hit gives color_pick (knit_aggregate) */
  int color_pick;
  float side;       /* +1 front, -1 behind */
  float sx, sy, sxx, sxy, syy; /* slope sums */
  float lsum, ssum; /* layers over hits, steps over points */
  kvec3 nsum, tsum, psum;
  float color_w[KNIT_MS_COLORS];
KNIT_STRUCT_END(KAggSum)

KNIT_FN KAggSum knit_agg_begin(int n, float shift_x, float shift_y, kvec3 wi_local) {
  KAggSum a;
  int c;
  /* which hit gives color_pick: a fraction of the (unknown) hit count */
  float pf = knit_frac(shift_x * KF(7.0) + shift_y * KF(3.0) + KF(0.5));
  a.n = n;
  a.hits = 0;
  a.pick = KINT(k_floor(pf * KFLT(n)));
  a.color_pick = -1;
  a.side = KZ(wi_local) < KF(0.0) ? KF(-1.0) : KF(1.0);
  a.sx = KF(0.0);
  a.sy = KF(0.0);
  a.sxx = KF(0.0);
  a.sxy = KF(0.0);
  a.syy = KF(0.0);
  a.lsum = KF(0.0);
  a.ssum = KF(0.0);
  a.nsum = kv3(KF(0.0), KF(0.0), KF(0.0));
  a.tsum = kv3(KF(0.0), KF(0.0), KF(0.0));
  a.psum = kv3(KF(0.0), KF(0.0), KF(0.0));
  for (c = 0; c < KNIT_MS_COLORS; c++) a.color_w[c] = KF(0.0);
  return a;
}

/* Point i's march st; layers: the tubes under its hit (unused on a miss). */
KNIT_FN KAggSum knit_agg_add(KNIT_IN(KAggSum) in, int i, KNIT_IN(KnitCapm) st, int layers) {
  KAggSum a = in;
  a.ssum = a.ssum + KFLT(st.steps);
  if (st.state == KNIT_CAPM_HIT) {
    kvec3 nn = st.hit.n;
    kvec3 tt = st.hit.tangent;
    kvec3 sl = knit_ms_slopes(nn, a.side);
    float bx = KX(sl), by = KY(sl);
    int ci = k_mini(k_maxi(st.hit.colour, 0), KNIT_MS_COLORS - 1);
    a.hits = a.hits + 1;
    if (a.color_pick < 0 || i <= a.pick) a.color_pick = st.hit.colour;
    a.nsum = kv3_add(a.nsum, nn);
    /* Tangents are lines, not arrows: align each with the running sum. */
    a.tsum = kv3_dot(a.tsum, tt) < KF(0.0) ? kv3_sub(a.tsum, tt) : kv3_add(a.tsum, tt);
    a.psum = kv3_add(a.psum, st.hit.p);
    a.sx = a.sx + bx;
    a.sy = a.sy + by;
    a.sxx = a.sxx + bx * bx;
    a.sxy = a.sxy + bx * by;
    a.syy = a.syy + by * by;
    a.lsum = a.lsum + KFLT(layers);
    a.color_w[ci] = a.color_w[ci] + KF(1.0);
  }
  return a;
}

/* The aggregate of the sums; (x, y) is the footprint's centre (the mean hit
 * position when nothing was hit). */
KNIT_FN KnitAggregate knit_agg_finish(KNIT_IN(KAggSum) s, float x, float y) {
  KnitAggregate a;
  int c;
  a.points = s.n;
  a.hits = s.hits;
  a.color_pick = s.color_pick;
  a.p_delta = KFLT(s.n - s.hits) / KFLT(s.n);
  a.steps = s.ssum / KFLT(s.n);
  if (s.hits > 0) {
    float inv = KF(1.0) / KFLT(s.hits);
    float mx = s.sx * inv, my = s.sy * inv;
    a.n = kv3_normalize(s.nsum);
    a.tangent = kv3_normalize(s.tsum);
    a.position = kv3_scale(s.psum, inv);
    a.sxx = k_fmax(s.sxx * inv - mx * mx, KF(0.0));
    a.syy = k_fmax(s.syy * inv - my * my, KF(0.0));
    a.sxy = s.sxy * inv - mx * my;
    a.layers = s.lsum * inv;
    for (c = 0; c < KNIT_MS_COLORS; c++) a.color_w[c] = s.color_w[c] * inv;
  } else {
    a.n = kv3(KF(0.0), KF(0.0), KF(1.0));
    a.tangent = kv3(KF(1.0), KF(0.0), KF(0.0));
    a.position = kv3(x, y, KF(0.0));
    a.sxx = KF(0.0);
    a.syy = KF(0.0);
    a.sxy = KF(0.0);
    a.layers = KF(0.0);
    for (c = 0; c < KNIT_MS_COLORS; c++) a.color_w[c] = KF(0.0);
  }
  return a;
}

/* Aggregates n_points CAPM marches over the footprint centred at (x, y).
 * fx = (dx/dpx, dy/dpx), fy = (dx/dpy, dy/dpy) in pattern units (KZ unused);
 * shift_x/y in [0,1): per-shading-point Cranley-Patterson shift. The base is
 * of constant curvature (kx, ky) (flat: 0); every footprint point uses the
 * same local view direction wi_local (the frame is treated as constant across
 * the footprint, which the footprint's smallness justifies); wi_local.z < 0
 * views the fabric from behind (knit_capm_start). */
KNIT_FN KnitAggregate knit_aggregate(KNIT_IN(KnitGeom) g, KNIT_ARRAY(int, codes), KNIT_ARRAY(int, colors),
                                     float x, float y, kvec3 fx, kvec3 fy, kvec3 wi_local,
                                     int n_points, float shift_x, float shift_y, float kx, float ky,
                                     float max_segment, int max_steps) {
  KFootprint f = knit_footprint(g, x, y, fx, fy, n_points, shift_x, shift_y);
  KAggSum s = knit_agg_begin(f.n, shift_x, shift_y, wi_local);
  int i;
  for (i = 0; i < f.n; i++) {
    kvec3 pt = knit_footprint_point(g, f, i);
    KnitCapm st = knit_capm_curved(g, codes, colors, KX(pt), KY(pt), wi_local, kx, ky, max_segment, max_steps);
    int layers = st.state == KNIT_CAPM_HIT ? knit_vertical_layers(g, codes, colors, KX(st.hit.p), KY(st.hit.p)) : 0;
    s = knit_agg_add(s, i, st, layers);
  }
  return knit_agg_finish(s, x, y);
}

/* ---- A footprint from ray differentials of known size only ---------------
 * Cycles gives a shader its UV derivatives from a ray cone: two tangent
 * vectors of the cone's width at the hit, in directions of no meaning
 * (differential_dudv_compact). Their lengths say how large a pixel is on the
 * surface across the view, not how it is stretched along it. The footprint
 * is then taken as isotropic, of side L = uv_scale (len_x + len_y) / 2, and
 * stretched by 1 / cos(theta) along the view direction's projection on the
 * surface (theta the view's angle to the base normal, the cosine clamped at
 * KNIT_FOOTPRINT_MIN_COS so that grazing views do not get footprints of
 * thousands of cells).
 *   len_x, len_y  lengths of the two UV differentials, |(du/dx, dv/dx)| and
 *                 |(du/dy, dv/dy)| (UV units)
 *   view_local    the view (or ray) direction in the base frame: x along +u,
 *                 y along +v, z the normal; sign and length do not matter
 *   uv_scale      pattern units per UV unit
 * Returns fx (stretched, along the view's projection) and fy (across it), in
 * pattern units (KZ 0): knit_aggregate's footprint vectors. A view along the
 * normal gives fx along x. Used by the OSL shader and by the native
 * renderer's "cycles" option (docs/cycles.md). */
#define KNIT_FOOTPRINT_MIN_COS KF(0.1)

KNIT_STRUCT(KFootprintAxes)
  kvec3 fx;
  kvec3 fy;
KNIT_STRUCT_END(KFootprintAxes)

KNIT_FN KFootprintAxes knit_footprint_isotropic(float len_x, float len_y, kvec3 view_local, float uv_scale) {
  KFootprintAxes f;
  float side = KF(0.5) * uv_scale * (k_fabs(len_x) + k_fabs(len_y));
  float vl = kv3_len(view_local);
  float t = k_sqrt(KX(view_local) * KX(view_local) + KY(view_local) * KY(view_local));
  float c = vl > KF(0.0) ? k_fabs(KZ(view_local)) / vl : KF(1.0);
  float ex = KF(1.0), ey = KF(0.0);
  float along;
  if (t > KF(1.0e-6) * vl) {
    ex = KX(view_local) / t;
    ey = KY(view_local) / t;
  }
  along = side / k_fmax(c, KNIT_FOOTPRINT_MIN_COS);
  f.fx = kv3(along * ex, along * ey, KF(0.0));
  f.fy = kv3(-side * ey, side * ex, KF(0.0));
  return f;
}

#endif /* KNIT_KERNEL_MULTISCALE_H */
