/* Knitshade kernel: host adaptation for OSL (see native/kernel/host_c.h for
 * the C/C++ side and docs/kernel-subset.md for the rules). */
#ifndef KNIT_OSL_HOST_H
#define KNIT_OSL_HOST_H

#define KNIT_FN
#define KNIT_STRUCT(Name) struct Name {
#define KNIT_STRUCT_END(Name) };
#define KNIT_ARRAY(T, name) T name[]
#define KNIT_NOARGS
#define KNIT_IN(T) T

#define kvec3 vector
#define kv3(x, y, z) vector(x, y, z)
/* OSL indexes only named variables, not expressions: components go through
 * functions (read-only; the kernel never assigns to a component). */
float knit_osl_x(vector w) { return w[0]; }
float knit_osl_y(vector w) { return w[1]; }
float knit_osl_z(vector w) { return w[2]; }
#define KX(w) knit_osl_x(w)
#define KY(w) knit_osl_y(w)
#define KZ(w) knit_osl_z(w)

#define KF(x) (x)
#define KINT(x) ((int)(x))
#define KFLT(i) ((float)(i))
#define KNIT_UNUSED(x)

#define k_sqrt(x) sqrt(x)
#define k_sin(x) sin(x)
#define k_cos(x) cos(x)
#define k_tan(x) tan(x)
#define k_acos(x) acos(x)
#define k_asin(x) asin(x)
#define k_atan(x) atan(x)
#define k_atan2(y, x) atan2(y, x)
#define k_exp(x) exp(x)
#define k_log(x) log(x)
#define k_pow(x, y) pow(x, y)
#define k_floor(x) floor(x)
#define k_ceil(x) ceil(x)
#define k_fabs(x) fabs(x)
#define k_cbrt(x) cbrt(x)
#define k_fmin(a, b) min(a, b)
#define k_fmax(a, b) max(a, b)
#define k_isfinite(x) (isfinite(x) != 0)

#endif /* KNIT_OSL_HOST_H */
