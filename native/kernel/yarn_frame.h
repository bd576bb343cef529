/* Knitshade kernel: the shading frame at a yarn hit, for hosts that shade
 * the hit where the view ray met the base mesh (the OSL shader, and the
 * native renderer's "as Cycles renders it" option).
 *
 *   knit_curved_frame   the base mesh's frame at pattern offset (dx, dy)
 *                       from the base hit, on a base of constant normal
 *                       curvature (kx along t, ky along b; pattern units):
 *                       the entry frame turned as knit_curved_frame_dir
 *                       turns directions (capm.h). Flat: the entry frame.
 *   knit_ply_arc        the ply's length coordinate at curve parameter t of
 *                       row `row`: t times the mean arc length per unit t,
 *                       plus the row's own phase (the golden-ratio sequence
 *                       of the row times a stitch's length), so plies of
 *                       rows above one another are not in step.
 *   knit_arc_per_t      mean |dY/dt| over one stitch of knit, Y(t) = (t + a
 *                       sin 2t, h cos t, d cos 2t): midpoint rule over n
 *                       points, which converges geometrically for this
 *                       smooth periodic integrand: with 32, within 1.2e-7 of
 *                       the exact mean for a, h, d from (0.3, 0.5, 0.1) to
 *                       (3, 10, 5) (within float rounding of the library's
 *                       256 in double).
 *   knit_yarn_azimuth   the azimuth of the tube normal around the yarn,
 *                       measured from the fabric normal's projection (the
 *                       ply profile's phi). */
#ifndef KNIT_KERNEL_YARN_FRAME_H
#define KNIT_KERNEL_YARN_FRAME_H

#define KNIT_GOLDEN KF(0.6180339887498949)

KNIT_STRUCT(KFrame)
  kvec3 t;
  kvec3 b;
  kvec3 n;
KNIT_STRUCT_END(KFrame)

KNIT_FN KFrame knit_frame_make(kvec3 t, kvec3 b, kvec3 n) {
  KFrame f;
  f.t = t;
  f.b = b;
  f.n = n;
  return f;
}

KNIT_FN KFrame knit_curved_frame(KNIT_IN(KFrame) f0, float kx, float ky, float dx, float dy) {
  float ax = kx * dx, ay = ky * dy;
  float cx = k_cos(ax), sx = k_sin(ax), cy = k_cos(ay), sy = k_sin(ay);
  kvec3 t1 = kv3_sub(kv3_scale(f0.t, cx), kv3_scale(f0.n, sx));
  kvec3 n1 = kv3_add(kv3_scale(f0.t, sx), kv3_scale(f0.n, cx));
  return knit_frame_make(t1, kv3_sub(kv3_scale(f0.b, cy), kv3_scale(n1, sy)),
                         kv3_add(kv3_scale(f0.b, sy), kv3_scale(n1, cy)));
}

KNIT_FN float knit_arc_per_t(float a, float h, float d, int n) {
  float sum = KF(0.0);
  int i;
  for (i = 0; i < n; i++) {
    float t = K_2PI * (KFLT(i) + KF(0.5)) / KFLT(n);
    float dx = KF(1.0) + KF(2.0) * a * k_cos(KF(2.0) * t);
    float dy = -h * k_sin(t);
    float dz = KF(-2.0) * d * k_sin(KF(2.0) * t);
    sum = sum + k_sqrt(dx * dx + dy * dy + dz * dz);
  }
  return sum / KFLT(n);
}

KNIT_FN float knit_ply_arc(float t, int row, float arc_per_t) {
  float g = KFLT(row) * KNIT_GOLDEN;
  return t * arc_per_t + (g - k_floor(g)) * (K_2PI * arc_per_t);
}

/* n: unit tube normal, tangent: unit yarn tangent (pattern-local). */
KNIT_FN float knit_yarn_azimuth(kvec3 n, kvec3 tangent) {
  kvec3 ref = kv3_sub(kv3(KF(0.0), KF(0.0), KF(1.0)), kv3_scale(tangent, KZ(tangent)));
  if (k_sqrt(kv3_len2(ref)) < KF(1.0e-4)) ref = kv3(KF(1.0), KF(0.0), KF(0.0));
  ref = kv3_normalize(ref);
  return k_atan2(kv3_dot(n, kv3_cross(kv3_normalize(tangent), ref)), kv3_dot(n, ref));
}

#endif /* KNIT_KERNEL_YARN_FRAME_H */
