/* Knitshade kernel: what every BSDF lobe shares (docs/bsdf.md).
 *
 * Frame. All lobes work in the local shading frame of the yarn surface:
 *   z = yarn surface normal, x = yarn tangent, y = z cross x.
 * wo points towards the viewer, wi towards the light; both are unit vectors
 * pointing away from the surface. wo.z * wi.z > 0 is reflection, < 0 is
 * transmission (the yarn is thin: transmitted light leaves on the other side).
 * Every lobe is two-sided: a viewer below the surface (wo.z < 0) sees the
 * mirror image of what a viewer above sees.
 *
 * Contract of every lobe (pbrt-v4 / Cycles style):
 *   X_eval(params, wo, wi)       -> kvec3  f(wo, wi) * |wi.z|   (RGB)
 *   X_pdf(params, wo, wi)        -> float  solid-angle density of X_sample
 *   X_sample(params, wo, u1, u2) -> KBsdfSample {wi, weight, pdf, flags}
 * eval INCLUDES the cosine |wi.z|: it is exactly what a path tracer multiplies
 * the incoming radiance by. sample's weight is eval(wo, wi) / pdf(wo, wi)
 * for the returned wi. A failed sample has pdf 0, weight 0 and flags 0.
 * u1, u2 are uniform in [0, 1).
 *
 * Kernel subset (docs/kernel-subset.md): no pointers, no output parameters,
 * no assignment to parameters (OSL treats them as read-only). */
#ifndef KNIT_KERNEL_BSDF_COMMON_H
#define KNIT_KERNEL_BSDF_COMMON_H

/* Sample flags (bit values; test them with kb_has_flag). */
#define KB_REFLECT 1
#define KB_TRANSMIT 2
#define KB_DELTA 4

/* Smallest GGX roughness the kernel uses; smaller values are clamped to it
 * (1e-3 keeps D(h) below 3.2e5, well inside float range). */
#define KB_ALPHA_MIN KF(1.0e-3)
/* Black, as an RGB value. */
#define KB_BLACK kv3(KF(0.0), KF(0.0), KF(0.0))

KNIT_STRUCT(KBsdfSample)
  kvec3 wi;     /* sampled direction towards the light, unit */
  kvec3 weight; /* eval(wo, wi) / pdf(wo, wi): RGB throughput of the sample */
  float pdf;    /* solid-angle density (for delta events: the discrete probability) */
  int flags;    /* KB_REFLECT / KB_TRANSMIT, plus KB_DELTA for a delta event */
KNIT_STRUCT_END(KBsdfSample)

KNIT_FN KBsdfSample kb_sample_make(kvec3 wi, kvec3 weight, float pdf, int flags) {
  KBsdfSample s;
  s.wi = wi;
  s.weight = weight;
  s.pdf = pdf;
  s.flags = flags;
  return s;
}

/* The failed sample: pdf 0, weight 0, flags 0 (wi is a harmless placeholder). */
KNIT_FN KBsdfSample kb_sample_fail(kvec3 wo) {
  return kb_sample_make(kv3_neg(wo), KB_BLACK, KF(0.0), 0);
}

/* 1 when bit `flag` (a power of two) is set in `flags`, else 0. Written without
 * bitwise operators so the same line reads the same in every host. */
KNIT_FN int kb_has_flag(int flags, int flag) { return (flags / flag) % 2; }

/* Mean of the three channels: the scalar used to weigh lobes for sampling. */
KNIT_FN float kb_average(kvec3 c) { return (KX(c) + KY(c) + KZ(c)) * KF(0.33333333333); }

/* v with its z component multiplied by s (s = +1 or -1): the two-sided flip. */
KNIT_FN kvec3 kb_flip_z(kvec3 v, float s) { return kv3(KX(v), KY(v), KZ(v) * s); }

/* +1 when wo is on the side the normal points to, -1 below. */
KNIT_FN float kb_side(kvec3 wo) { return KZ(wo) < KF(0.0) ? KF(-1.0) : KF(1.0); }

/* Unpolarised Fresnel reflectance of a dielectric interface seen from the
 * outside (index 1) into a medium of relative index eta >= 1, at the cosine
 * c in [0, 1] between the direction and the (micro)normal. Exact formula
 * (Walter et al. 2007, Eq. 22); no total internal reflection from outside. */
KNIT_FN float kb_fresnel_dielectric(float c_in, float eta) {
  float c = k_clampf(c_in, KF(0.0), KF(1.0));
  float g = k_safe_sqrt((eta - KF(1.0)) * (eta + KF(1.0)) + c * c); /* no cancellation near eta = 1 */
  float a, b;
  if (g + c <= KF(0.0)) return KF(1.0); /* eta == 1 at exact grazing */
  a = (g - c) / (g + c);
  b = (c * (g + c) - KF(1.0)) / (c * (g - c) + KF(1.0));
  return k_clampf(KF(0.5) * a * a * (KF(1.0) + b * b), KF(0.0), KF(1.0));
}

/* Cosine-weighted direction on the hemisphere z > 0: pdf = z / pi.
 * Polar mapping r = sqrt(u1), phi = 2 pi u2. */
KNIT_FN kvec3 kb_cosine_hemisphere(float u1, float u2) {
  float r = k_sqrt(k_clampf(u1, KF(0.0), KF(1.0)));
  float phi = K_2PI * u2;
  return kv3(r * k_cos(phi), r * k_sin(phi), k_safe_sqrt(KF(1.0) - r * r));
}

#endif /* KNIT_KERNEL_BSDF_COMMON_H */
