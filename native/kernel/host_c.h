/* Knitshade kernel: host adaptation for C99 and C++17.
 *
 * The kernel headers in this folder are written once in a subset of C that
 * `oslc` also accepts (see docs/kernel-subset.md). They never include system
 * headers and never name a host type directly; they go through the macros
 * below. `osl/knit_osl_host.h` defines the same macros for OSL.
 *
 *   KNIT_FN               qualifier of every kernel function
 *   KNIT_STRUCT(Name)     opens a struct declaration, KNIT_STRUCT_END(Name) closes it
 *   KNIT_ARRAY(T, name)   a read-only array parameter of unknown length
 *   KNIT_NOARGS           the parameter list of a function without parameters
 *   KNIT_IN(T)            a struct parameter (C++: const T&, C and OSL: T)
 *   kvec3, kv3(x,y,z)     3-vector type and constructor; KX/KY/KZ component access
 *   KF(x)                 a float literal (C: single precision, no double promotion)
 *   KINT(x), KFLT(i)      conversions
 *   KNIT_UNUSED(x);       marks a parameter a function does not read (C: a void
 *                         cast; OSL: nothing, leaving an empty statement)
 *   k_sqrt ... k_cbrt     scalar maths on float
 */
#ifndef KNIT_KERNEL_HOST_C_H
#define KNIT_KERNEL_HOST_C_H

#include <math.h>
#include <string.h>

#ifdef __cplusplus
#define KNIT_FN static inline
#else
#define KNIT_FN static inline
#endif

/* Struct parameters: C++ takes them by const reference (the kernel never
 * assigns to a parameter, see docs/kernel-subset.md), C by value. */
#ifdef __cplusplus
#define KNIT_IN(T) const T&
#else
#define KNIT_IN(T) T
#endif

#define KNIT_STRUCT(Name) typedef struct Name {
#define KNIT_STRUCT_END(Name) } Name;
#define KNIT_ARRAY(T, name) const T *name
#define KNIT_NOARGS void

typedef struct kvec3 {
  float x, y, z;
} kvec3;

KNIT_FN kvec3 kv3(float x, float y, float z) {
  kvec3 v;
  v.x = x;
  v.y = y;
  v.z = z;
  return v;
}

#define KX(v) ((v).x)
#define KY(v) ((v).y)
#define KZ(v) ((v).z)

#define KF(x) ((float)(x))
#define KINT(x) ((int)(x))
#define KFLT(i) ((float)(i))
#define KNIT_UNUSED(x) ((void)(x))

#define k_sqrt(x) sqrtf(x)
#define k_sin(x) sinf(x)
#define k_cos(x) cosf(x)
#define k_tan(x) tanf(x)
#define k_acos(x) acosf(x)
#define k_asin(x) asinf(x)
#define k_atan(x) atanf(x)
#define k_atan2(y, x) atan2f(y, x)
#define k_exp(x) expf(x)
#define k_log(x) logf(x)
#define k_pow(x, y) powf(x, y)
#define k_floor(x) floorf(x)
#define k_ceil(x) ceilf(x)
#define k_fabs(x) fabsf(x)
#define k_cbrt(x) knit_host_cbrt(x)
/* Plain comparisons (not fminf/fmaxf, which are libm calls without
 * -ffast-math); inputs are never NaN in the kernel. */
KNIT_FN float knit_host_fmin(float a, float b) { return a < b ? a : b; }
KNIT_FN float knit_host_fmax(float a, float b) { return a > b ? a : b; }
/* Cube root without libm's cbrtf (the costliest call of the cubic solver):
 * a first guess from the bits (exponent divided by three) and three Newton
 * steps, a few ulp from the exact root over [1e-30, 1e30]; cbrtf elsewhere
 * (zero, tiny, huge, inf, NaN). tests/native/test_cubic.cpp checks it. */
KNIT_FN float knit_host_cbrt(float x) {
  float ax = fabsf(x), y;
  unsigned int i;
  int it;
  if (!(ax >= 1.0e-30f && ax <= 1.0e30f)) return cbrtf(x);
  memcpy(&i, &ax, sizeof i);
  i = i / 3u + 709921077u;
  memcpy(&y, &i, sizeof y);
  for (it = 0; it < 3; it++) y = y - (y * y * y - ax) / (3.0f * y * y);
  return x < 0.0f ? -y : y;
}
#define k_fmin(a, b) knit_host_fmin(a, b)
#define k_fmax(a, b) knit_host_fmax(a, b)
#define k_isfinite(x) isfinite(x)

#endif /* KNIT_KERNEL_HOST_C_H */
