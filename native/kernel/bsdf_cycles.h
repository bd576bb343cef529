/* Knitshade kernel: the near-field yarn BSDF (yarn_bsdf.h, paper Eq. 1) as
 * Cycles renders it, with closures that every Cycles from 3.4 on provides
 * to OSL. The OSL shader (osl/knit_fabric.osl) emits
 *
 *   spec      microfacet("ggx", n, t, ax, ay, eta, 0)  GGX reflection, no Fresnel
 *   body_r    diffuse(n)                               Lambertian reflection
 *   body_t    translucent(n)                           Lambertian transmission
 *   through   transparent()                            straight on, unscattered
 *
 * with the weights below, which may depend on the view direction wo but not
 * on the light direction wi (Cycles evaluates lights outside the shader).
 * The native library renders the same mixture as a material option
 * ("bsdf": "cycles"), so the error of the approximation is measured against
 * the exact lobes and against explicit yarns (docs/cycles.md).
 *
 * What each exact lobe becomes, and why:
 *   f_R   F(wo.h) D G2 / (4 cos cos)  ->  F(|wo.z|) x (D G2 / (4 cos cos)).
 *         Cycles' microfacet closure with refract = 0 has no Fresnel term;
 *         the Fresnel factor is taken at the macro normal, exact at the
 *         lobe's peak for narrow lobes.
 *   body R  r B G (1 - F_o)(1 - F_i) LS k_R  ->  a Lambertian lobe with the
 *         same directional albedo at wo: LS's albedo A(mu_o) and the
 *         cosine-weighted mean of (1 - F_i) over the hemisphere.
 *   body T  tau (1 - r) B G (1 - F_o)(1 - F_i) k_T / pi  ->  Lambertian
 *         transmission, with tau taken on the straight-through path and
 *         (1 - F_i) by its cosine-weighted mean.
 *   f_T   tau (1 - B) (1 - F)^2 D G2 / (4 cos cos), a thin-slab lobe centred
 *         on wi = -wo  ->  transparent(), weight tau (1 - B) (1 - F_o)^2: the
 *         ballistic light goes straight on. Its blur (the transmission
 *         roughness) is lost; what it lets through is kept.
 *
 * Parameters: those of KYarnBsdf (yarn_bsdf.h); the lobe weights are
 *   name     type    meaning
 *   spec     float   weight of the GGX reflection closure (spec_r's roughness and eta)
 *   body_r   kvec3   weight of diffuse()
 *   body_t   kvec3   weight of translucent()
 *   through  float   weight of transparent()
 */
#ifndef KNIT_KERNEL_BSDF_CYCLES_H
#define KNIT_KERNEL_BSDF_CYCLES_H

KNIT_STRUCT(KCyclesLobes)
  float spec;
  kvec3 body_r;
  kvec3 body_t;
  float through;
KNIT_STRUCT_END(KCyclesLobes)

/* Cosine-weighted hemispherical mean of the Fresnel reflectance,
 * 2 int_0^1 F(mu) mu dmu, by 16-point midpoint quadrature in mu^2 (where
 * the integrand 2 F mu dmu = F d(mu^2) is smooth): within 2e-4 of the exact
 * integral for eta in [1, 3]. */
KNIT_FN float bsdf_cycles_fresnel_mean(float eta) {
  float sum = KF(0.0);
  int i;
  for (i = 0; i < 16; i++) {
    float m2 = (KFLT(i) + KF(0.5)) / KF(16.0);
    sum = sum + kb_fresnel_dielectric(k_sqrt(m2), eta);
  }
  return sum / KF(16.0);
}

/* The closure weights for the view direction wo (local frame, either side). */
KNIT_FN KCyclesLobes yarn_cycles_lobes(KNIT_IN(KYarnBsdf) p, kvec3 wo) {
  KCyclesLobes c;
  float mo = k_fabs(KZ(wo));
  float fo = p.spec_r.eta > KF(1.0) ? kb_fresnel_dielectric(mo, p.spec_r.eta) : KF(0.0);
  float fi_mean = p.spec_r.eta > KF(1.0) ? bsdf_cycles_fresnel_mean(p.spec_r.eta) : KF(0.0);
  float tau = bsdf_att_tau_straight(p.atten, wo);
  float b = p.body_energy;
  float body = b * p.shadow * (KF(1.0) - fo) * (KF(1.0) - fi_mean);
  c.spec = fo;
  c.body_r = kv3_scale(p.kd_r, p.body_reflect * body * bsdf_ls_albedo(mo));
  c.body_t = kv3_scale(p.kd_t, tau * (KF(1.0) - p.body_reflect) * body);
  c.through = tau * (KF(1.0) - b) * (KF(1.0) - fo) * (KF(1.0) - fo);
  return c;
}

#endif /* KNIT_KERNEL_BSDF_CYCLES_H */
