/* Knitshade kernel: small vector and scalar maths shared by every kernel file.
 * Kernel subset (docs/kernel-subset.md): no pointers, no overloading. */
#ifndef KNIT_KERNEL_KMATH_H
#define KNIT_KERNEL_KMATH_H

#define K_PI KF(3.14159265358979323846)
#define K_2PI KF(6.28318530717958647692)
#define K_PI_2 KF(1.57079632679489661923)
#define K_PI_4 KF(0.78539816339744830962)
#define K_INV_PI KF(0.31830988618379067154)
#define K_BIG KF(1.0e30)

KNIT_FN float k_sqr(float x) { return x * x; }
KNIT_FN float k_clampf(float x, float lo, float hi) { return k_fmin(k_fmax(x, lo), hi); }
KNIT_FN float k_safe_sqrt(float x) { return k_sqrt(k_fmax(x, KF(0.0))); }
KNIT_FN float k_safe_acos(float x) { return k_acos(k_clampf(x, KF(-1.0), KF(1.0))); }
KNIT_FN float k_safe_asin(float x) { return k_asin(k_clampf(x, KF(-1.0), KF(1.0))); }
KNIT_FN float k_signf(float x) { return x < KF(0.0) ? KF(-1.0) : KF(1.0); }
KNIT_FN float k_lerp(float a, float b, float t) { return a + (b - a) * t; }
KNIT_FN int k_mini(int a, int b) { return a < b ? a : b; }
KNIT_FN int k_maxi(int a, int b) { return a > b ? a : b; }

/* sin x (KX) and cos x (KY) for |x| <= 16, in plain arithmetic (no libm
 * call, the same operations on every host): x is reduced by the nearest
 * multiple q of pi/2, pi/2 split in three parts so that q times the first two
 * is exact, and the Taylor polynomials of sin and cos to x^9 and x^10 are
 * used on [-pi/4, pi/4] (truncation below 2e-9 there). tests/native/
 * test_cubic.cpp checks it against double precision. The stitch curve
 * evaluates it at every Newton step (stitch.h). */
KNIT_FN kvec3 knit_sincos(float x) {
  float qf = KFLT(KINT(x * KF(0.63661977236758134308) + (x >= KF(0.0) ? KF(0.5) : KF(-0.5))));
  float y = ((x - qf * KF(1.5703125)) - qf * KF(4.837512969970703125e-4)) - qf * KF(7.549789954891882e-8);
  float y2 = y * y;
  float s = y + y * y2 * (KF(-1.0) / KF(6.0) +
                          y2 * (KF(1.0) / KF(120.0) + y2 * (KF(-1.0) / KF(5040.0) + y2 * (KF(1.0) / KF(362880.0)))));
  float c = KF(1.0) + y2 * (KF(-0.5) + y2 * (KF(1.0) / KF(24.0) +
                                           y2 * (KF(-1.0) / KF(720.0) +
                                                 y2 * (KF(1.0) / KF(40320.0) + y2 * (KF(-1.0) / KF(3628800.0))))));
  int n = KINT(qf) & 3; /* quadrant, also for negative q */
  if (n == 1) return kv3(c, -s, KF(0.0));
  if (n == 2) return kv3(-s, -c, KF(0.0));
  if (n == 3) return kv3(-c, s, KF(0.0));
  return kv3(s, c, KF(0.0));
}

/* Floor-modulo for integers: result in [0, n) for n > 0, also for negative a. */
KNIT_FN int k_modi(int a, int n) {
  int m = a % n;
  return m < 0 ? m + n : m;
}

KNIT_FN kvec3 kv3_add(kvec3 a, kvec3 b) { return kv3(KX(a) + KX(b), KY(a) + KY(b), KZ(a) + KZ(b)); }
KNIT_FN kvec3 kv3_sub(kvec3 a, kvec3 b) { return kv3(KX(a) - KX(b), KY(a) - KY(b), KZ(a) - KZ(b)); }
KNIT_FN kvec3 kv3_scale(kvec3 a, float s) { return kv3(KX(a) * s, KY(a) * s, KZ(a) * s); }
KNIT_FN kvec3 kv3_mul(kvec3 a, kvec3 b) { return kv3(KX(a) * KX(b), KY(a) * KY(b), KZ(a) * KZ(b)); }
KNIT_FN kvec3 kv3_madd(kvec3 a, kvec3 b, float s) {
  return kv3(KX(a) + KX(b) * s, KY(a) + KY(b) * s, KZ(a) + KZ(b) * s);
}
KNIT_FN kvec3 kv3_neg(kvec3 a) { return kv3(-KX(a), -KY(a), -KZ(a)); }
KNIT_FN float kv3_dot(kvec3 a, kvec3 b) { return KX(a) * KX(b) + KY(a) * KY(b) + KZ(a) * KZ(b); }
KNIT_FN kvec3 kv3_cross(kvec3 a, kvec3 b) {
  return kv3(KY(a) * KZ(b) - KZ(a) * KY(b), KZ(a) * KX(b) - KX(a) * KZ(b), KX(a) * KY(b) - KY(a) * KX(b));
}
KNIT_FN float kv3_len2(kvec3 a) { return kv3_dot(a, a); }
KNIT_FN float kv3_len(kvec3 a) { return k_sqrt(kv3_dot(a, a)); }
KNIT_FN kvec3 kv3_normalize(kvec3 a) {
  float l = kv3_len(a);
  return l > KF(0.0) ? kv3_scale(a, KF(1.0) / l) : kv3(KF(0.0), KF(0.0), KF(1.0));
}
KNIT_FN kvec3 kv3_lerp(kvec3 a, kvec3 b, float t) { return kv3_add(a, kv3_scale(kv3_sub(b, a), t)); }
/* Components of w in the orthonormal frame (t, b, n). */
KNIT_FN kvec3 kv3_to_local(kvec3 w, kvec3 t, kvec3 b, kvec3 n) {
  return kv3(kv3_dot(w, t), kv3_dot(w, b), kv3_dot(w, n));
}
KNIT_FN kvec3 kv3_from_local(kvec3 w, kvec3 t, kvec3 b, kvec3 n) {
  return kv3_add(kv3_add(kv3_scale(t, KX(w)), kv3_scale(b, KY(w))), kv3_scale(n, KZ(w)));
}

#endif /* KNIT_KERNEL_KMATH_H */
