/* Knitshade kernel: body reflection LS(wi, wo) k_x^B of the near-field yarn
 * BSDF, paper Eq. 1 (after Khattar et al. 2025, who take the
 * Lommel-Seeliger law of single scattering in a half-space, Jensen et al.
 * 2001 [JMLH01]).
 *
 * This header is the bare lobe; yarn_bsdf.h weights it by r B G_{p,f} and the
 * Fresnel transmittances of the yarn surface.
 *
 *   f_LS(wo, wi) = k / (2 pi) * 1 / (|wi.z| + |wo.z|)      (same side only)
 *
 * Normalisation. The classical law with single-scattering albedo k is
 * k / (4 pi (mu_i + mu_o)); its directional albedo never exceeds k / 2
 * because a half-space scatters half its single-scattered light downwards.
 * Here the lobe stands for all the body's reflected energy, so it is scaled
 * by 2: k is then the largest directional albedo. With mu = |cos| and
 * mu_o = |wo.z|, the directional albedo is
 *   A(mu_o) = int f mu_i dw_i = k int_0^1 mu / (mu + mu_o) dmu
 *           = k (1 - mu_o ln(1 + 1 / mu_o)),
 * which decreases from k (grazing view, mu_o -> 0) to k (1 - ln 2) = 0.307 k
 * (normal view): A <= k <= 1. (Test: tests/native/test_bsdf_diffuse.cpp.)
 * f is symmetric in wo and wi (reciprocal).
 *
 * Sampling: cosine-weighted hemisphere on wo's side, pdf = |wi.z| / pi
 * (exact); weight = eval / pdf = k / (2 (|wi.z| + |wo.z|)).
 * eval returns f * |wi.z| (cosine included); see bsdf_common.h.
 *
 * Cycles has no Lommel-Seeliger closure. bsdf_ls_lambert_equivalent gives the
 * Lambertian weight with the same directional albedo A(mu_o) for the OSL
 * approximation `A(mu_o) k * diffuse(N)`, so that its error can be measured.
 *
 * Parameters (KLommelSeeliger):
 *   name    type   default          meaning
 *   albedo  kvec3  (0.8, 0.8, 0.8)  k: RGB, each in [0, 1]; the directional
 *                                   albedo at grazing view (largest)
 */
#ifndef KNIT_KERNEL_BSDF_LOMMEL_SEELIGER_H
#define KNIT_KERNEL_BSDF_LOMMEL_SEELIGER_H

KNIT_STRUCT(KLommelSeeliger)
  kvec3 albedo; /* k */
KNIT_STRUCT_END(KLommelSeeliger)

KNIT_FN KLommelSeeliger bsdf_ls_make(kvec3 albedo) {
  KLommelSeeliger p;
  p.albedo = albedo;
  return p;
}

/* A(mu_o) / k = 1 - mu_o ln(1 + 1/mu_o), the directional albedo per unit k. */
KNIT_FN float bsdf_ls_albedo(float mu_o) {
  float mu = k_clampf(k_fabs(mu_o), KF(0.0), KF(1.0));
  if (mu < KF(1.0e-30)) return KF(1.0);
  return k_clampf(KF(1.0) - mu * k_log(KF(1.0) + KF(1.0) / mu), KF(0.0), KF(1.0));
}

KNIT_FN kvec3 bsdf_ls_eval(KLommelSeeliger p, kvec3 wo, kvec3 wi) {
  float mo = k_fabs(KZ(wo));
  float mi = k_fabs(KZ(wi));
  if (KZ(wo) * KZ(wi) <= KF(0.0)) return KB_BLACK;
  return kv3_scale(p.albedo, mi / (K_2PI * (mi + mo)));
}

KNIT_FN float bsdf_ls_pdf(KLommelSeeliger p, kvec3 wo, kvec3 wi) {
  KNIT_UNUSED(p);
  if (KZ(wo) * KZ(wi) <= KF(0.0)) return KF(0.0);
  return k_fabs(KZ(wi)) * K_INV_PI;
}

KNIT_FN KBsdfSample bsdf_ls_sample(KLommelSeeliger p, kvec3 wo, float u1, float u2) {
  float s = kb_side(wo);
  kvec3 d = kb_cosine_hemisphere(u1, u2);
  float mi = KZ(d);
  float mo = k_fabs(KZ(wo));
  if (KZ(wo) == KF(0.0) || mi <= KF(0.0)) return kb_sample_fail(wo);
  return kb_sample_make(kb_flip_z(d, s), kv3_scale(p.albedo, KF(0.5) / (mi + mo)), mi * K_INV_PI,
                        KB_REFLECT);
}

/* Weight w(mu_o) = A(mu_o) such that w k / pi * |wi.z| (a Lambertian lobe)
 * has the same directional albedo as this lobe at wo. */
KNIT_FN float bsdf_ls_lambert_equivalent(kvec3 wo) { return bsdf_ls_albedo(KZ(wo)); }

#endif /* KNIT_KERNEL_BSDF_LOMMEL_SEELIGER_H */
