/* Knitshade kernel: the near-field yarn BSDF of the paper, Eq. 1 (after
 * Khattar et al. 2025), as a mixture of the lobes in bsdf_*.h:
 *
 *  reflection (wo.z wi.z > 0):
 *    f = f_R(wo, wi) + r B G (1 - F_o)(1 - F_i) LS(wo, wi) k_R
 *  transmission (wo.z wi.z < 0):
 *    f = tau(wo, wi) [ (1 - B) f_T(wo, wi) + (1 - r) B G (1 - F_o)(1 - F_i) k_T / pi ]
 *
 *  f_R   rough dielectric reflection (bsdf_microfacet.h, roughness spec_r)
 *  f_T   thin-slab rough dielectric transmission (bsdf_microfacet.h, spec_t)
 *  LS    Lommel-Seeliger body reflection, unit albedo at grazing view
 *        (bsdf_lommel_seeliger.h); k_R = k_x^B its colour
 *  k_T   body transmission colour k_y^B (bsdf_lambert_transmission.h)
 *  tau   double-layer attenuation (bsdf_attenuation.h)
 *  G     inter-ply and inter-fiber shadowing G_{p,f} at the point (ply_profile.h)
 *  B, r  body energy and its reflected portion
 *  F_o, F_i  Fresnel reflectance F(|wo.z|), F(|wi.z|) of the yarn surface (eta)
 *
 * Two factors differ from Eq. 1 as printed, both for energy conservation
 * (docs/bsdf.md): (i) the body lobes are weighted by the Fresnel
 * transmittances (1 - F_o)(1 - F_i): only light that was not reflected by the
 * surface enters the body, and it has to cross the surface again to leave
 * (symmetric in wo, wi, so the BSDF stays reciprocal); (ii) f_T is weighted
 * by (1 - B): of the light entering the yarn, the portion B is scattered
 * many times (the body lobes) and the rest crosses ballistically (f_T). With
 * these, the directional albedo stays <= 1 for B, r, colours, G, tau all 1
 * (measured in tests/native/test_bsdf_yarn.cpp; value in docs/bsdf.md).
 *
 * eval returns f * |wi.z| (cosine included); sample's weight = eval / pdf;
 * pdf is the mixture pdf sum_k P_k(wo) pdf_k(wo, wi), where the lobe
 * selection probabilities P_k(wo) are proportional to estimates of the
 * lobes' albedos (yarn_bsdf_lobe_probs). See bsdf_common.h.
 *
 * Colours per colour index: the kernel takes the colour of the point
 * (kd_r, kd_t) from the caller, who maps the colour index reported by the
 * geometry through its palette (C++: knit::YarnBsdf; OSL: a colour array
 * parameter of the shader). The kernel struct thus stays small and holds no
 * array, and the number of colours is not limited by the kernel.
 *
 * Parameters (KYarnBsdf):
 *   name          type          default               meaning
 *   spec_r        KMicrofacet   (0.15, 0.45, 1.55)    f_R roughness along/across the yarn, eta
 *   spec_t        KMicrofacet   (0.30, 0.60, 1.55)    f_T roughness along/across, eta (same eta)
 *   kd_r          kvec3         (0.8, 0.8, 0.8)       k_x^B body reflection colour, [0, 1]
 *   kd_t          kvec3         (0.8, 0.8, 0.8)       k_y^B body transmission colour, [0, 1]
 *   body_energy   float         0.7                   B, [0, 1]
 *   body_reflect  float         0.6                   r, [0, 1]
 *   shadow        float         1.0                   G_{p,f} at this point, [0, 1]
 *   atten         KAttenuation  (1.0, 1)              tau: optical depth D, layer count
 */
#ifndef KNIT_KERNEL_YARN_BSDF_H
#define KNIT_KERNEL_YARN_BSDF_H

#define YB_LOBE_SPEC_R 0
#define YB_LOBE_SPEC_T 1
#define YB_LOBE_BODY_R 2
#define YB_LOBE_BODY_T 3
#define YB_NUM_LOBES 4
/* Selection weight floor of a lobe that can be non-zero (keeps every lobe's
 * support covered by the mixture even when its estimate underflows). */
#define YB_LOBE_FLOOR KF(1.0e-3)

KNIT_STRUCT(KYarnBsdf)
  KMicrofacet spec_r;
  KMicrofacet spec_t;
  kvec3 kd_r;
  kvec3 kd_t;
  float body_energy;
  float body_reflect;
  float shadow;
  KAttenuation atten;
KNIT_STRUCT_END(KYarnBsdf)

KNIT_STRUCT(KYarnLobeProbs)
  float p0; /* specular reflection */
  float p1; /* specular transmission */
  float p2; /* body reflection */
  float p3; /* body transmission */
  float fo; /* F(|wo.z|) of the yarn surface, for yarn_bsdf_eval_pdf_with */
KNIT_STRUCT_END(KYarnLobeProbs)

KNIT_FN KYarnBsdf yarn_bsdf_make(KNIT_IN(KMicrofacet) spec_r, KNIT_IN(KMicrofacet) spec_t, kvec3 kd_r, kvec3 kd_t,
                                 float body_energy, float body_reflect, float shadow,
                                 KNIT_IN(KAttenuation) atten) {
  KYarnBsdf p;
  p.spec_r = spec_r;
  p.spec_t = spec_t;
  p.kd_r = kd_r;
  p.kd_t = kd_t;
  p.body_energy = k_clampf(body_energy, KF(0.0), KF(1.0));
  p.body_reflect = k_clampf(body_reflect, KF(0.0), KF(1.0));
  p.shadow = k_clampf(shadow, KF(0.0), KF(1.0));
  p.atten = atten;
  return p;
}

/* Lobe selection probabilities for wo: proportional to estimated albedos
 * (Fresnel at the macro normal, LS albedo, straight-through tau), with a
 * floor for every lobe that can be non-zero. All zero when the BSDF is. */
KNIT_FN KYarnLobeProbs yarn_bsdf_lobe_probs(KNIT_IN(KYarnBsdf) p, kvec3 wo) {
  KYarnLobeProbs q;
  float mo = k_fabs(KZ(wo));
  float fo = kb_fresnel_dielectric(mo, p.spec_r.eta);
  float tau = bsdf_att_tau_straight(p.atten, wo);
  float b = p.body_energy;
  float body_r = p.body_reflect * b * p.shadow * kb_average(p.kd_r);
  float body_t = (KF(1.0) - p.body_reflect) * b * p.shadow * kb_average(p.kd_t);
  float w0 = p.spec_r.eta > KF(1.0) ? k_fmax(fo, YB_LOBE_FLOOR) : KF(0.0);
  float w1 = b < KF(1.0) ? k_fmax((KF(1.0) - b) * (KF(1.0) - fo) * (KF(1.0) - fo) * tau, YB_LOBE_FLOOR)
                         : KF(0.0);
  float w2 = body_r > KF(0.0) ? k_fmax(body_r * (KF(1.0) - fo) * bsdf_ls_albedo(mo), YB_LOBE_FLOOR)
                              : KF(0.0);
  float w3 = body_t > KF(0.0) ? k_fmax(body_t * (KF(1.0) - fo) * tau, YB_LOBE_FLOOR) : KF(0.0);
  float sum = w0 + w1 + w2 + w3;
  float inv = sum > KF(0.0) ? KF(1.0) / sum : KF(0.0);
  q.p0 = w0 * inv;
  q.p1 = w1 * inv;
  q.p2 = w2 * inv;
  q.p3 = w3 * inv;
  q.fo = fo;
  return q;
}

/* One lobe's contribution (index YB_LOBE_*), weights included; eval is their sum. */
KNIT_FN kvec3 yarn_bsdf_lobe_eval(KNIT_IN(KYarnBsdf) p, int lobe, kvec3 wo, kvec3 wi) {
  float b = p.body_energy;
  float r = p.body_reflect;
  float body;
  if (KZ(wo) * KZ(wi) == KF(0.0)) return KB_BLACK;
  if (lobe == YB_LOBE_SPEC_R) return bsdf_mf_reflect_eval(p.spec_r, wo, wi);
  body = b * p.shadow * (KF(1.0) - kb_fresnel_dielectric(k_fabs(KZ(wo)), p.spec_r.eta)) *
         (KF(1.0) - kb_fresnel_dielectric(k_fabs(KZ(wi)), p.spec_r.eta));
  if (lobe == YB_LOBE_BODY_R) return kv3_scale(bsdf_ls_eval(bsdf_ls_make(p.kd_r), wo, wi), r * body);
  if (KZ(wo) * KZ(wi) > KF(0.0)) return KB_BLACK;
  if (lobe == YB_LOBE_SPEC_T)
    return kv3_scale(bsdf_mf_transmit_eval(p.spec_t, wo, wi), (KF(1.0) - b) * bsdf_att_tau(p.atten, wo, wi));
  if (lobe == YB_LOBE_BODY_T)
    return kv3_scale(bsdf_lt_eval(bsdf_lt_make(p.kd_t), wo, wi),
                     (KF(1.0) - r) * body * bsdf_att_tau(p.atten, wo, wi));
  return KB_BLACK;
}

KNIT_FN kvec3 yarn_bsdf_eval(KNIT_IN(KYarnBsdf) p, kvec3 wo, kvec3 wi) {
  float b = p.body_energy;
  float r = p.body_reflect;
  float body, tau;
  if (KZ(wo) * KZ(wi) == KF(0.0)) return KB_BLACK;
  body = b * p.shadow * (KF(1.0) - kb_fresnel_dielectric(k_fabs(KZ(wo)), p.spec_r.eta)) *
         (KF(1.0) - kb_fresnel_dielectric(k_fabs(KZ(wi)), p.spec_r.eta));
  if (KZ(wo) * KZ(wi) > KF(0.0)) {
    return kv3_add(bsdf_mf_reflect_eval(p.spec_r, wo, wi),
                   kv3_scale(bsdf_ls_eval(bsdf_ls_make(p.kd_r), wo, wi), r * body));
  }
  tau = bsdf_att_tau(p.atten, wo, wi);
  return kv3_scale(kv3_add(kv3_scale(bsdf_mf_transmit_eval(p.spec_t, wo, wi), KF(1.0) - b),
                           kv3_scale(bsdf_lt_eval(bsdf_lt_make(p.kd_t), wo, wi), (KF(1.0) - r) * body)),
                   tau);
}

KNIT_FN float yarn_bsdf_pdf_with(KNIT_IN(KYarnBsdf) p, KNIT_IN(KYarnLobeProbs) q, kvec3 wo, kvec3 wi) {
  if (KZ(wo) * KZ(wi) > KF(0.0)) {
    return q.p0 * bsdf_mf_reflect_pdf(p.spec_r, wo, wi) +
           q.p2 * bsdf_ls_pdf(bsdf_ls_make(p.kd_r), wo, wi);
  }
  if (KZ(wo) * KZ(wi) < KF(0.0)) {
    return q.p1 * bsdf_mf_transmit_pdf(p.spec_t, wo, wi) +
           q.p3 * bsdf_lt_pdf(bsdf_lt_make(p.kd_t), wo, wi);
  }
  return KF(0.0);
}

KNIT_FN float yarn_bsdf_pdf(KNIT_IN(KYarnBsdf) p, kvec3 wo, kvec3 wi) {
  return yarn_bsdf_pdf_with(p, yarn_bsdf_lobe_probs(p, wo), wo, wi);
}

KNIT_FN float yarn_bsdf_lobe_prob(KNIT_IN(KYarnLobeProbs) q, int lobe) {
  return lobe == 0 ? q.p0 : (lobe == 1 ? q.p1 : (lobe == 2 ? q.p2 : q.p3));
}

/* yarn_bsdf_eval and yarn_bsdf_pdf_with at (wo, wi) in one pass, q from
 * yarn_bsdf_lobe_probs(p, wo) (with its F(|wo.z|)): the microfacet lobe's
 * half vector, D and Lambda are shared by its eval and pdf. The same values,
 * bit for bit (tests/native/test_bsdf_yarn.cpp). */
KNIT_STRUCT(KYarnEvalPdf)
  kvec3 f;   /* yarn_bsdf_eval(p, wo, wi) */
  float pdf; /* yarn_bsdf_pdf_with(p, q, wo, wi) */
KNIT_STRUCT_END(KYarnEvalPdf)

KNIT_FN KYarnEvalPdf yarn_bsdf_eval_pdf_with(KNIT_IN(KYarnBsdf) p, KNIT_IN(KYarnLobeProbs) q, kvec3 wo, kvec3 wi) {
  float b = p.body_energy;
  float r = p.body_reflect;
  float s = kb_side(wo);
  float body;
  KMfEvalPdf mf;
  KYarnEvalPdf e;
  e.f = KB_BLACK;
  e.pdf = KF(0.0);
  if (KZ(wo) * KZ(wi) == KF(0.0)) return e;
  body = b * p.shadow * (KF(1.0) - q.fo) * (KF(1.0) - kb_fresnel_dielectric(k_fabs(KZ(wi)), p.spec_r.eta));
  if (KZ(wo) * KZ(wi) > KF(0.0)) {
    mf = mf_eval_pdf_up(p.spec_r, kb_flip_z(wo, s), kb_flip_z(wi, s), 0);
    e.f = kv3_add(kv3(mf.f, mf.f, mf.f), kv3_scale(bsdf_ls_eval(bsdf_ls_make(p.kd_r), wo, wi), r * body));
    e.pdf = q.p0 * mf.pdf + q.p2 * bsdf_ls_pdf(bsdf_ls_make(p.kd_r), wo, wi);
    return e;
  }
  mf = mf_eval_pdf_up(p.spec_t, kb_flip_z(wo, s), kb_flip_z(wi, -s), 1);
  e.f = kv3_scale(kv3_add(kv3_scale(kv3(mf.f, mf.f, mf.f), KF(1.0) - b),
                          kv3_scale(bsdf_lt_eval(bsdf_lt_make(p.kd_t), wo, wi), (KF(1.0) - r) * body)),
                  bsdf_att_tau(p.atten, wo, wi));
  e.pdf = q.p1 * mf.pdf + q.p3 * bsdf_lt_pdf(bsdf_lt_make(p.kd_t), wo, wi);
  return e;
}

/* Chooses a lobe with u1 (rescaled and reused), samples it with (u1', u2),
 * and returns wi with weight = eval / pdf and the mixture pdf. A microfacet
 * lobe gives only the direction (mf_sample_dir_up): the mixture's eval and
 * pdf are computed once, for all lobes together. */
KNIT_FN KBsdfSample yarn_bsdf_sample(KNIT_IN(KYarnBsdf) p, kvec3 wo, float u1, float u2) {
  KYarnLobeProbs q = yarn_bsdf_lobe_probs(p, wo);
  float c1 = q.p0;
  float c2 = c1 + q.p1;
  float c3 = c2 + q.p2;
  float side = kb_side(wo);
  float start, pk, ur;
  int k = 3;
  KBsdfSample s;
  KYarnEvalPdf e;
  if (c3 + q.p3 <= KF(0.0) || KZ(wo) == KF(0.0)) return kb_sample_fail(wo);
  if (u1 < c3) k = 2;
  if (u1 < c2) k = 1;
  if (u1 < c1) k = 0;
  while (k > 0 && yarn_bsdf_lobe_prob(q, k) <= KF(0.0)) k = k - 1; /* rounding at the top end */
  start = k == 0 ? KF(0.0) : (k == 1 ? c1 : (k == 2 ? c2 : c3));
  pk = yarn_bsdf_lobe_prob(q, k);
  ur = k_clampf((u1 - start) / pk, KF(0.0), KF(0.99999994));
  if (k == YB_LOBE_SPEC_R) {
    s = mf_sample_dir_up(p.spec_r, kb_flip_z(wo, side), ur, u2);
    s.wi = kb_flip_z(s.wi, side);
    s.flags = KB_REFLECT;
  } else if (k == YB_LOBE_SPEC_T) {
    s = mf_sample_dir_up(p.spec_t, kb_flip_z(wo, side), ur, u2);
    s.wi = kb_flip_z(s.wi, -side);
    s.flags = KB_TRANSMIT;
  } else if (k == YB_LOBE_BODY_R) {
    s = bsdf_ls_sample(bsdf_ls_make(p.kd_r), wo, ur, u2);
  } else {
    s = bsdf_lt_sample(bsdf_lt_make(p.kd_t), wo, ur, u2);
  }
  if (s.pdf <= KF(0.0)) return kb_sample_fail(wo);
  e = yarn_bsdf_eval_pdf_with(p, q, wo, s.wi);
  if (e.pdf <= KF(0.0)) return kb_sample_fail(wo);
  return kb_sample_make(s.wi, kv3_scale(e.f, KF(1.0) / e.pdf), e.pdf, s.flags);
}

/* ---- With delta transmission through gaps (bsdf_delta.h) ------------------ */

/* u0 chooses pass-through (probability p_delta) or the yarn BSDF (u1, u2). */
KNIT_FN KBsdfSample yarn_bsdf_sample_gaps(KNIT_IN(KYarnBsdf) p, float p_delta, kvec3 wo, float u0, float u1,
                                          float u2) {
  KDeltaChoice c = bsdf_delta_choose(p_delta, u0);
  KBsdfSample s;
  if (c.pass != 0) return bsdf_delta_sample(wo, c.prob);
  s = yarn_bsdf_sample(p, wo, u1, u2);
  s.pdf = s.pdf * c.prob;
  return s;
}

/* The non-delta part (what light sampling sees): (1 - p_delta) f * |wi.z|. */
KNIT_FN kvec3 yarn_bsdf_eval_gaps(KNIT_IN(KYarnBsdf) p, float p_delta, kvec3 wo, kvec3 wi) {
  return kv3_scale(yarn_bsdf_eval(p, wo, wi), bsdf_delta_scale(p_delta));
}

/* Solid-angle pdf of the non-delta part: (1 - p_delta) pdf. */
KNIT_FN float yarn_bsdf_pdf_gaps(KNIT_IN(KYarnBsdf) p, float p_delta, kvec3 wo, kvec3 wi) {
  return yarn_bsdf_pdf(p, wo, wi) * bsdf_delta_scale(p_delta);
}

#endif /* KNIT_KERNEL_YARN_BSDF_H */
