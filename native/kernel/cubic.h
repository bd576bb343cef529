/* Knitshade kernel: real roots of quadratics and cubics in closed form.
 *
 * Cubic: Cardano's formula for one real root (with the cancellation-free
 * choice of the cube root's sign) and Viete's trigonometric form for three
 * real roots (Nickalls 1993 gives the same split), each root then polished by
 * one Newton step on the original polynomial. Quadratic: the stable form
 * q = -(b + sign(b) sqrt(disc)) / 2, roots q/a and c/q.
 *
 * Accuracy against a double-precision reference is asserted in
 * tests/native/test_cubic.cpp. */
#ifndef KNIT_KERNEL_CUBIC_H
#define KNIT_KERNEL_CUBIC_H

KNIT_STRUCT(KRoots)
  int n;          /* number of real roots, 0..3 */
  float r0, r1, r2; /* in ascending order; unused ones are 0 */
KNIT_STRUCT_END(KRoots)

KNIT_FN KRoots kroots_none(KNIT_NOARGS) {
  KRoots r;
  r.n = 0;
  r.r0 = KF(0.0);
  r.r1 = KF(0.0);
  r.r2 = KF(0.0);
  return r;
}

KNIT_FN KRoots kroots_sort(KNIT_IN(KRoots) in) {
  KRoots r = in;
  float t;
  if (r.n >= 2 && r.r1 < r.r0) { t = r.r0; r.r0 = r.r1; r.r1 = t; }
  if (r.n == 3) {
    if (r.r2 < r.r1) { t = r.r1; r.r1 = r.r2; r.r2 = t; }
    if (r.r1 < r.r0) { t = r.r0; r.r0 = r.r1; r.r1 = t; }
  }
  return r;
}

/* Real roots of a x^2 + b x + c = 0 (a may be 0). */
KNIT_FN KRoots solve_quadratic(float a, float b, float c) {
  KRoots r = kroots_none();
  float scale = k_fmax(k_fmax(k_fabs(a), k_fabs(b)), k_fabs(c));
  if (scale == KF(0.0)) return r;
  if (k_fabs(a) <= KF(1.0e-7) * scale) {
    if (b != KF(0.0)) { r.n = 1; r.r0 = -c / b; }
    return r;
  }
  {
    float disc = b * b - KF(4.0) * a * c;
    float q;
    if (disc < KF(0.0)) return r;
    q = KF(-0.5) * (b + k_signf(b) * k_sqrt(disc));
    if (q == KF(0.0)) { r.n = 1; r.r0 = KF(0.0); return r; }
    r.n = 2;
    r.r0 = q / a;
    r.r1 = c / q;
    return kroots_sort(r);
  }
}

KNIT_FN float cubic_newton(float a3, float a2, float a1, float a0, float x) {
  /* x is only read: OSL passes parameters by reference */
  float f = ((a3 * x + a2) * x + a1) * x + a0;
  float df = (KF(3.0) * a3 * x + KF(2.0) * a2) * x + a1;
  if (df != KF(0.0)) {
    float nx = x - f / df;
    if (k_isfinite(nx)) return nx;
  }
  return x;
}

/* Real roots of a3 x^3 + a2 x^2 + a1 x + a0 = 0. */
KNIT_FN KRoots solve_cubic(float a3, float a2, float a1, float a0) {
  KRoots r = kroots_none();
  float scale = k_fmax(k_fmax(k_fabs(a2), k_fabs(a1)), k_fabs(a0));
  if (k_fabs(a3) <= KF(1.0e-6) * scale || a3 == KF(0.0)) return solve_quadratic(a2, a1, a0);
  {
    float b = a2 / a3, c = a1 / a3, d = a0 / a3;
    float b3 = b / KF(3.0);
    float p = c - b * b3;                              /* depressed: y^3 + p y + q */
    float q = KF(2.0) * b3 * b3 * b3 - b3 * c + d;
    float hq = KF(0.5) * q;
    float tp = p / KF(3.0);
    float disc = hq * hq + tp * tp * tp;
    if (disc > KF(0.0)) {
      float A = -k_signf(q) * k_cbrt(k_fabs(hq) + k_sqrt(disc));
      float B = (A != KF(0.0)) ? -tp / A : KF(0.0);
      r.n = 1;
      r.r0 = A + B - b3;
    } else if (tp == KF(0.0)) {
      r.n = 1; /* triple root */
      r.r0 = -b3;
    } else {
      float m = KF(2.0) * k_sqrt(-tp);
      float phi = k_safe_acos(KF(3.0) * q / (p * m)) / KF(3.0);
      /* cos(phi - 2pi/3) and cos(phi - 4pi/3) from cos phi and sin phi */
      kvec3 cs = knit_sincos(phi);
      float cp = KY(cs), sp = KX(cs);
      float hc = KF(-0.5) * cp, hs = KF(0.86602540378443864676) * sp;
      r.n = 3;
      r.r0 = m * cp - b3;
      r.r1 = m * (hc + hs) - b3;
      r.r2 = m * (hc - hs) - b3;
    }
    r.r0 = cubic_newton(a3, a2, a1, a0, r.r0);
    if (r.n == 3) {
      r.r1 = cubic_newton(a3, a2, a1, a0, r.r1);
      r.r2 = cubic_newton(a3, a2, a1, a0, r.r2);
    }
    return kroots_sort(r);
  }
}

#endif /* KNIT_KERNEL_CUBIC_H */
