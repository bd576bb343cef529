/* Knitshade kernel: body transmission (B / pi) k_y^B of the near-field yarn
 * BSDF, paper Eq. 1 (after Khattar et al. 2025): light that scattered many
 * times inside the yarn leaves the other side uniformly in radiance.
 *
 * This header is the bare lobe; yarn_bsdf.h weights it by (1 - r) B G_{p,f},
 * the double-layer attenuation tau and the Fresnel transmittances.
 *
 *   f_LT(wo, wi) = k / pi      for wo.z * wi.z < 0 (opposite sides), else 0
 *
 * Directional albedo: int f |wi.z| dw_i = k <= 1 for every wo. Reciprocal.
 * Sampling: cosine-weighted hemisphere on the side opposite to wo,
 * pdf = |wi.z| / pi (exact); weight = eval / pdf = k.
 * eval returns f * |wi.z| (cosine included); see bsdf_common.h.
 *
 * Parameters (KLambertTransmission):
 *   name    type   default          meaning
 *   albedo  kvec3  (0.8, 0.8, 0.8)  k: RGB transmission colour, each in [0, 1]
 */
#ifndef KNIT_KERNEL_BSDF_LAMBERT_TRANSMISSION_H
#define KNIT_KERNEL_BSDF_LAMBERT_TRANSMISSION_H

KNIT_STRUCT(KLambertTransmission)
  kvec3 albedo; /* k */
KNIT_STRUCT_END(KLambertTransmission)

KNIT_FN KLambertTransmission bsdf_lt_make(kvec3 albedo) {
  KLambertTransmission p;
  p.albedo = albedo;
  return p;
}

KNIT_FN kvec3 bsdf_lt_eval(KLambertTransmission p, kvec3 wo, kvec3 wi) {
  if (KZ(wo) * KZ(wi) >= KF(0.0)) return KB_BLACK;
  return kv3_scale(p.albedo, k_fabs(KZ(wi)) * K_INV_PI);
}

KNIT_FN float bsdf_lt_pdf(KLambertTransmission p, kvec3 wo, kvec3 wi) {
  KNIT_UNUSED(p);
  if (KZ(wo) * KZ(wi) >= KF(0.0)) return KF(0.0);
  return k_fabs(KZ(wi)) * K_INV_PI;
}

KNIT_FN KBsdfSample bsdf_lt_sample(KLambertTransmission p, kvec3 wo, float u1, float u2) {
  float s = kb_side(wo);
  kvec3 d = kb_cosine_hemisphere(u1, u2);
  if (KZ(wo) == KF(0.0) || KZ(d) <= KF(0.0)) return kb_sample_fail(wo);
  return kb_sample_make(kb_flip_z(d, -s), p.albedo, KZ(d) * K_INV_PI, KB_TRANSMIT);
}

#endif /* KNIT_KERNEL_BSDF_LAMBERT_TRANSMISSION_H */
