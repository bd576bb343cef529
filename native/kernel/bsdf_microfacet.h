/* Knitshade kernel: the specular lobes f_x^S and f_y^S of the near-field yarn
 * BSDF, paper Eq. 1 (after Khattar et al. 2025): a rough dielectric with
 * anisotropic GGX microfacets (Walter et al. 2007; Heitz 2014), Smith
 * height-correlated shadowing-masking, exact dielectric Fresnel, and
 * visible-normal sampling (Heitz 2018).
 *
 * Two lobes share one parameter struct:
 *   bsdf_mf_reflect_*   specular reflection at the entry point x:
 *       f_R = F(wo.h) D(h) G2(wo, wi) / (4 |wo.z| |wi.z|),  h = normalize(wo + wi)
 *   bsdf_mf_transmit_*  specular transmission through the thin yarn, leaving at
 *       the exit point y on the other side. The yarn is a thin slab with air on
 *       both sides: ballistic light refracts in and refracts back out through a
 *       (statistically) parallel face, so the two bends cancel and the lobe is
 *       centred on the straight-through direction wi = -wo, blurred by the
 *       roughness. With wi' = (wi.x, wi.y, -wi.z), the mirror of wi into wo's
 *       hemisphere (wi = -wo maps to the mirror direction of wo):
 *       f_T = (1 - F(wo.h'))^2 D(h') G2(wo, wi') / (4 |wo.z| |wi.z|),  h' = normalize(wo + wi')
 *       (1 - F)^2: Fresnel transmittance in at x and out at y (same angle on
 *       both faces); the internally reflected part is left to the body lobes.
 *       Radiance is scaled by eta^2 going in and by 1/eta^2 going out, so f_T
 *       has no eta^2 factor and is plainly reciprocal: f_T(wo,wi) = f_T(wi,wo).
 *       It is sampled exactly (VNDF sample of wi', then mirror) and its pdf is
 *       the reflection pdf of (wo, wi').
 *   Roughness of the transmission lobe: a clean slab of index eta whose faces
 *   have roughness alpha deviates light by about sqrt(2) (1 - 1/eta) alpha
 *   radians, which the mirrored lobe reproduces with
 *   alpha_T = alpha (1 - 1/eta) / sqrt(2) (bsdf_mf_slab_alpha); a yarn is a
 *   bundle of fibres, not a clean slab, so the yarn BSDF takes alpha_T as its
 *   own parameter and uses this relation only as documentation of the lower
 *   bound.
 *
 * eval returns f * |wi.z| (cosine included); sample's weight = eval / pdf.
 * See bsdf_common.h for the frame and the contract.
 *
 * Why GGX and not Beckmann. The paper's multi-scale model (Sec. 5.1, Eq. 9-11)
 * aggregates slopes with LEAN mapping, i.e. a Beckmann-style Gaussian slope
 * covariance. GGX is used here because visible-normal sampling is exact and
 * closed form for GGX (Beckmann's needs an inverse erf and a Newton solve),
 * its tails suit the broad highlights of fibrous yarn, and Cycles' OSL
 * `microfacet("ggx", ...)` closure (the OSL host's approximation) is GGX.
 * Conversion (bsdf_lean_to_ggx): a Beckmann surface of roughness alpha has
 * Gaussian slopes with variance alpha^2 / 2 per axis, so the LEAN covariance
 * of a footprint adds to the base roughness as
 *   C = Sigma + diag(alpha_x^2 / 2, alpha_y^2 / 2)          (paper Eq. 11)
 * and the GGX roughness along each principal axis of C is sqrt(2 lambda),
 * lambda an eigenvalue of C. GGX slopes have no finite variance; this maps
 * the Beckmann alpha to the GGX alpha with the same peak D(n) = 1/(pi ax ay)
 * (alpha_GGX = alpha_Beckmann), the usual practice (Walter et al. 2007).
 *
 * Parameters (KMicrofacet):
 *   name     type   default  meaning
 *   alpha_x  float  0.15     GGX roughness along the yarn tangent x, (0, 1];
 *                            values below KB_ALPHA_MIN (1e-3) are clamped
 *   alpha_y  float  0.45     GGX roughness across the yarn (y), (0, 1]
 *   eta      float  1.55     index of refraction of the yarn relative to the
 *                            outside, [1, 3] (wool keratin ~1.55)
 */
#ifndef KNIT_KERNEL_BSDF_MICROFACET_H
#define KNIT_KERNEL_BSDF_MICROFACET_H

KNIT_STRUCT(KMicrofacet)
  float alpha_x; /* roughness along the yarn tangent x */
  float alpha_y; /* roughness across the yarn (y) */
  float eta;     /* relative index of refraction, >= 1 */
KNIT_STRUCT_END(KMicrofacet)

KNIT_FN KMicrofacet bsdf_mf_make(float alpha_x, float alpha_y, float eta) {
  KMicrofacet m;
  m.alpha_x = k_fmax(alpha_x, KB_ALPHA_MIN);
  m.alpha_y = k_fmax(alpha_y, KB_ALPHA_MIN);
  m.eta = k_fmax(eta, KF(1.0));
  return m;
}

/* The transmission roughness of a clean slab (see above): alpha (1 - 1/eta) / sqrt 2. */
KNIT_FN float bsdf_mf_slab_alpha(float alpha, float eta) {
  return k_fmax(alpha * (KF(1.0) - KF(1.0) / k_fmax(eta, KF(1.0))) * KF(0.70710678118654752),
                KB_ALPHA_MIN);
}

/* Anisotropic GGX normal distribution D(h) for a unit h (0 below the surface):
 * D = 1 / (pi ax ay (hx^2/ax^2 + hy^2/ay^2 + hz^2)^2); integral of D(h) h.z = 1. */
KNIT_FN float mf_ggx_d(float ax, float ay, kvec3 h) {
  float x = KX(h) / ax;
  float y = KY(h) / ay;
  float z = KZ(h);
  float s = x * x + y * y + z * z;
  if (z <= KF(0.0)) return KF(0.0);
  return K_INV_PI / (ax * ay * s * s);
}

/* |v.z| Lambda(v) of the Smith GGX masking function, in a form without
 * cancellation and finite at grazing: with s2 = ax^2 vx^2 + ay^2 vy^2 and
 * z = |v.z|, Lambda = (sqrt(1 + s2/z^2) - 1)/2, so
 * z Lambda = s2 / (2 (sqrt(z^2 + s2) + z)). */
KNIT_FN float mf_ggx_zlambda(float ax, float ay, kvec3 v) {
  float z = k_fabs(KZ(v));
  float s2 = ax * ax * KX(v) * KX(v) + ay * ay * KY(v) * KY(v);
  float d = k_sqrt(z * z + s2) + z;
  return d > KF(0.0) ? s2 / (KF(2.0) * d) : KF(0.0);
}

/* Smith masking G1(v) = 1 / (1 + Lambda(v)) = z / (z + z Lambda). */
KNIT_FN float mf_ggx_g1(float ax, float ay, kvec3 v) {
  float z = k_fabs(KZ(v));
  float d = z + mf_ggx_zlambda(ax, ay, v);
  return d > KF(0.0) ? z / d : KF(0.0);
}

/* Height-correlated G2(o, i) = 1 / (1 + Lambda(o) + Lambda(i)). */
KNIT_FN float mf_ggx_g2(float ax, float ay, kvec3 o, kvec3 i) {
  float zo = k_fabs(KZ(o));
  float zi = k_fabs(KZ(i));
  float d = zo * zi + zi * mf_ggx_zlambda(ax, ay, o) + zo * mf_ggx_zlambda(ax, ay, i);
  return d > KF(0.0) ? zo * zi / d : KF(0.0);
}

/* Density of visible normals, D_wo(h) = G1(wo) max(0, wo.h) D(h) / wo.z, for wo.z > 0. */
KNIT_FN float mf_ggx_vndf(float ax, float ay, kvec3 wo, kvec3 h) {
  float oh = kv3_dot(wo, h);
  float d = KZ(wo) + mf_ggx_zlambda(ax, ay, wo);
  if (oh <= KF(0.0) || d <= KF(0.0)) return KF(0.0);
  return oh * mf_ggx_d(ax, ay, h) / d;
}

/* A microfacet normal drawn from D_wo(h) (Heitz 2018, JCGT 7(4)): stretch wo
 * to the unit-roughness configuration, sample the projected hemisphere as a
 * disk whose far half is squashed by (1 + Vh.z)/2, unstretch. wo.z > 0.
 * In two parts, for callers that draw many normals for one wo: the
 * stretched view's frame (mf_ggx_vndf_frame), and the normal for a point
 * (p1, p2) of the unit disk (mf_ggx_vndf_from_disk). */
KNIT_STRUCT(KVndfFrame)
  kvec3 vh; /* the stretched view direction */
  kvec3 t1; /* two axes across it */
  kvec3 t2;
  float sq; /* (1 + vh.z) / 2, the squash of the disk's far half */
KNIT_STRUCT_END(KVndfFrame)

KNIT_FN KVndfFrame mf_ggx_vndf_frame(float ax, float ay, kvec3 wo) {
  KVndfFrame f;
  float lensq;
  f.vh = kv3_normalize(kv3(ax * KX(wo), ay * KY(wo), KZ(wo)));
  lensq = KX(f.vh) * KX(f.vh) + KY(f.vh) * KY(f.vh);
  f.t1 = lensq > KF(0.0) ? kv3_scale(kv3(-KY(f.vh), KX(f.vh), KF(0.0)), KF(1.0) / k_sqrt(lensq))
                         : kv3(KF(1.0), KF(0.0), KF(0.0));
  f.t2 = kv3_cross(f.vh, f.t1);
  f.sq = KF(0.5) * (KF(1.0) + KZ(f.vh));
  return f;
}

KNIT_FN kvec3 mf_ggx_vndf_from_disk(KNIT_IN(KVndfFrame) f, float ax, float ay, float p1, float p2) {
  float p2s = (KF(1.0) - f.sq) * k_safe_sqrt(KF(1.0) - p1 * p1) + f.sq * p2;
  kvec3 nh = kv3_add(kv3_add(kv3_scale(f.t1, p1), kv3_scale(f.t2, p2s)),
                     kv3_scale(f.vh, k_safe_sqrt(KF(1.0) - p1 * p1 - p2s * p2s)));
  return kv3_normalize(kv3(ax * KX(nh), ay * KY(nh), k_fmax(KZ(nh), KF(0.0))));
}

KNIT_FN kvec3 mf_ggx_sample_vndf(float ax, float ay, kvec3 wo, float u1, float u2) {
  float r = k_sqrt(k_clampf(u1, KF(0.0), KF(1.0)));
  float phi = K_2PI * u2;
  return mf_ggx_vndf_from_disk(mf_ggx_vndf_frame(ax, ay, wo), ax, ay, r * k_cos(phi), r * k_sin(phi));
}

/* f (cosine NOT included, Fresnel NOT included) of the reflection
 * configuration o, i with o.z > 0, i.z > 0:
 * D(h) G2 / (4 o.z i.z) = D(h) / (4 (o.z i.z + i.z Lambda_o o.z + o.z Lambda_i i.z)). */
KNIT_FN float mf_refl_core(float ax, float ay, kvec3 o, kvec3 i, kvec3 h) {
  float den = KZ(o) * KZ(i) + KZ(i) * mf_ggx_zlambda(ax, ay, o) + KZ(o) * mf_ggx_zlambda(ax, ay, i);
  if (den <= KF(0.0)) return KF(0.0);
  return mf_ggx_d(ax, ay, h) / (KF(4.0) * den);
}

/* Density of the reflected direction i under VNDF sampling from o (o.z > 0):
 * D_o(h) / (4 o.h) = D(h) / (4 (o.z + o.z Lambda_o)). */
KNIT_FN float mf_refl_pdf_up(float ax, float ay, kvec3 o, kvec3 h) {
  float d = KZ(o) + mf_ggx_zlambda(ax, ay, o);
  if (d <= KF(0.0)) return KF(0.0);
  return mf_ggx_d(ax, ay, h) / (KF(4.0) * d);
}

/* Eval of the reflection configuration in the upper hemisphere, with the
 * Fresnel factor chosen by `transmit` (0: F, 1: (1 - F)^2). Returns f * i.z. */
KNIT_FN float mf_eval_up(KNIT_IN(KMicrofacet) m, kvec3 o, kvec3 i, int transmit) {
  float ax = k_fmax(m.alpha_x, KB_ALPHA_MIN);
  float ay = k_fmax(m.alpha_y, KB_ALPHA_MIN);
  kvec3 hs = kv3_add(o, i);
  kvec3 h;
  float fr, fac;
  if (KZ(o) <= KF(0.0) || KZ(i) <= KF(0.0) || kv3_len2(hs) <= KF(0.0)) return KF(0.0);
  h = kv3_normalize(hs);
  fr = kb_fresnel_dielectric(kv3_dot(o, h), m.eta);
  fac = transmit != 0 ? (KF(1.0) - fr) * (KF(1.0) - fr) : fr;
  return fac * mf_refl_core(ax, ay, o, i, h) * KZ(i);
}

KNIT_FN float mf_pdf_up(KNIT_IN(KMicrofacet) m, kvec3 o, kvec3 i) {
  float ax = k_fmax(m.alpha_x, KB_ALPHA_MIN);
  float ay = k_fmax(m.alpha_y, KB_ALPHA_MIN);
  kvec3 hs = kv3_add(o, i);
  if (KZ(o) <= KF(0.0) || KZ(i) <= KF(0.0) || kv3_len2(hs) <= KF(0.0)) return KF(0.0);
  return mf_refl_pdf_up(ax, ay, o, kv3_normalize(hs));
}

/* mf_eval_up and mf_pdf_up together (transmit as there): the half vector,
 * D(h) and Lambda(o) are computed once. The same values, bit for bit. */
KNIT_STRUCT(KMfEvalPdf)
  float f;   /* mf_eval_up(m, o, i, transmit) */
  float pdf; /* mf_pdf_up(m, o, i) */
KNIT_STRUCT_END(KMfEvalPdf)

KNIT_FN KMfEvalPdf mf_eval_pdf_up(KNIT_IN(KMicrofacet) m, kvec3 o, kvec3 i, int transmit) {
  float ax = k_fmax(m.alpha_x, KB_ALPHA_MIN);
  float ay = k_fmax(m.alpha_y, KB_ALPHA_MIN);
  kvec3 hs = kv3_add(o, i);
  kvec3 h;
  float d, lo, dp, den, fr, fac;
  KMfEvalPdf r;
  r.f = KF(0.0);
  r.pdf = KF(0.0);
  if (KZ(o) <= KF(0.0) || KZ(i) <= KF(0.0) || kv3_len2(hs) <= KF(0.0)) return r;
  h = kv3_normalize(hs);
  d = mf_ggx_d(ax, ay, h);
  lo = mf_ggx_zlambda(ax, ay, o);
  dp = KZ(o) + lo;
  if (dp > KF(0.0)) r.pdf = d / (KF(4.0) * dp);
  den = KZ(o) * KZ(i) + KZ(i) * lo + KZ(o) * mf_ggx_zlambda(ax, ay, i);
  if (den > KF(0.0)) {
    fr = kb_fresnel_dielectric(kv3_dot(o, h), m.eta);
    fac = transmit != 0 ? (KF(1.0) - fr) * (KF(1.0) - fr) : fr;
    r.f = fac * (d / (KF(4.0) * den)) * KZ(i);
  }
  return r;
}

/* The direction alone of mf_sample_up (for a mixture that weighs its samples
 * itself): the same wi, and a failure (pdf 0) in the same cases but one, an
 * underflow of o.z i.z to 0 (then mf_sample_up fails and the mixture's eval
 * of the lobe is 0). pdf is 1 on success: not a density. */
KNIT_FN KBsdfSample mf_sample_dir_up(KNIT_IN(KMicrofacet) m, kvec3 o, float u1, float u2) {
  float ax = k_fmax(m.alpha_x, KB_ALPHA_MIN);
  float ay = k_fmax(m.alpha_y, KB_ALPHA_MIN);
  kvec3 h, i;
  float oh;
  if (KZ(o) <= KF(0.0)) return kb_sample_fail(o);
  h = mf_ggx_sample_vndf(ax, ay, o, u1, u2);
  oh = kv3_dot(o, h);
  /* h.z > 0 is mf_sample_up's pdf > 0: D(h) > 0 exactly when h.z > 0 */
  if (oh <= KF(0.0) || KZ(h) <= KF(0.0)) return kb_sample_fail(o);
  i = kv3_normalize(kv3_sub(kv3_scale(h, KF(2.0) * oh), o));
  if (KZ(i) <= KF(0.0)) return kb_sample_fail(o);
  return kb_sample_make(i, kv3(KF(1.0), KF(1.0), KF(1.0)), KF(1.0), KB_REFLECT);
}

/* Sample of the upper-hemisphere reflection configuration from o (o.z > 0);
 * the returned wi has wi.z > 0 (the caller mirrors it for transmission). */
KNIT_FN KBsdfSample mf_sample_up(KNIT_IN(KMicrofacet) m, kvec3 o, float u1, float u2, int transmit) {
  float ax = k_fmax(m.alpha_x, KB_ALPHA_MIN);
  float ay = k_fmax(m.alpha_y, KB_ALPHA_MIN);
  kvec3 h, i;
  float oh, lo, li, den, fr, fac, w;
  if (KZ(o) <= KF(0.0)) return kb_sample_fail(o);
  h = mf_ggx_sample_vndf(ax, ay, o, u1, u2);
  oh = kv3_dot(o, h);
  if (oh <= KF(0.0)) return kb_sample_fail(o);
  i = kv3_normalize(kv3_sub(kv3_scale(h, KF(2.0) * oh), o));
  if (KZ(i) <= KF(0.0)) return kb_sample_fail(o);
  lo = mf_ggx_zlambda(ax, ay, o);
  li = mf_ggx_zlambda(ax, ay, i);
  den = KZ(o) * KZ(i) + KZ(i) * lo + KZ(o) * li;
  if (den <= KF(0.0)) return kb_sample_fail(o);
  fr = kb_fresnel_dielectric(oh, m.eta);
  fac = transmit != 0 ? (KF(1.0) - fr) * (KF(1.0) - fr) : fr;
  /* eval / pdf = fac G2 / G1(o), written without D (which cancels). */
  w = fac * KZ(i) * (KZ(o) + lo) / den;
  return kb_sample_make(i, kv3(w, w, w), mf_refl_pdf_up(ax, ay, o, h),
                        transmit != 0 ? KB_TRANSMIT : KB_REFLECT);
}

/* ---- Specular reflection f_x^S ------------------------------------------ */

KNIT_FN kvec3 bsdf_mf_reflect_eval(KNIT_IN(KMicrofacet) m, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  float v;
  if (KZ(wo) * KZ(wi) <= KF(0.0)) return KB_BLACK;
  v = mf_eval_up(m, kb_flip_z(wo, s), kb_flip_z(wi, s), 0);
  return kv3(v, v, v);
}

KNIT_FN float bsdf_mf_reflect_pdf(KNIT_IN(KMicrofacet) m, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  if (KZ(wo) * KZ(wi) <= KF(0.0)) return KF(0.0);
  return mf_pdf_up(m, kb_flip_z(wo, s), kb_flip_z(wi, s));
}

KNIT_FN KBsdfSample bsdf_mf_reflect_sample(KNIT_IN(KMicrofacet) m, kvec3 wo, float u1, float u2) {
  float s = kb_side(wo);
  KBsdfSample r = mf_sample_up(m, kb_flip_z(wo, s), u1, u2, 0);
  r.wi = kb_flip_z(r.wi, s);
  return r;
}

/* ---- Specular transmission f_y^S (thin slab, see the header comment) ------- */

KNIT_FN kvec3 bsdf_mf_transmit_eval(KNIT_IN(KMicrofacet) m, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  float v;
  if (KZ(wo) * KZ(wi) >= KF(0.0)) return KB_BLACK;
  v = mf_eval_up(m, kb_flip_z(wo, s), kb_flip_z(wi, -s), 1);
  return kv3(v, v, v);
}

KNIT_FN float bsdf_mf_transmit_pdf(KNIT_IN(KMicrofacet) m, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  if (KZ(wo) * KZ(wi) >= KF(0.0)) return KF(0.0);
  return mf_pdf_up(m, kb_flip_z(wo, s), kb_flip_z(wi, -s));
}

KNIT_FN KBsdfSample bsdf_mf_transmit_sample(KNIT_IN(KMicrofacet) m, kvec3 wo, float u1, float u2) {
  float s = kb_side(wo);
  KBsdfSample r = mf_sample_up(m, kb_flip_z(wo, s), u1, u2, 1);
  r.wi = kb_flip_z(r.wi, -s);
  return r;
}

/* ---- LEAN covariance to GGX roughness (paper Sec. 5.1, Eq. 9-11) ----------- */

KNIT_STRUCT(KLeanRoughness)
  float alpha_u; /* GGX roughness along the principal direction u */
  float alpha_v; /* GGX roughness along v, perpendicular to u in the tangent plane */
  float cos_u, sin_u; /* u = cos_u x + sin_u y, the angle in (-pi/2, pi/2] (cos_u >= 0) */
KNIT_STRUCT_END(KLeanRoughness)

/* Base roughness (alpha_x, alpha_y) widened by the slope covariance
 * (sxx, sxy, syy) of the normals aggregated over a footprint (paper Eq. 10).
 * The caller turns its tangent x to u and uses (alpha_u, alpha_v). The
 * major axis is at half the angle of (cxx - cyy, 2 sxy); its cosine and
 * sine come from the half-angle identities, in the form that does not
 * cancel (no arctangent, sine or cosine). */
KNIT_FN KLeanRoughness bsdf_lean_to_ggx(float alpha_x, float alpha_y, float sxx, float sxy,
                                        float syy) {
  KLeanRoughness r;
  float cxx = KF(0.5) * alpha_x * alpha_x + k_fmax(sxx, KF(0.0));
  float cyy = KF(0.5) * alpha_y * alpha_y + k_fmax(syy, KF(0.0));
  float mean = KF(0.5) * (cxx + cyy);
  float half_diff = KF(0.5) * (cxx - cyy);
  float rad = k_sqrt(half_diff * half_diff + sxy * sxy);
  float l1 = mean + rad;
  float l2 = k_fmax(mean - rad, KF(0.0));
  r.cos_u = KF(1.0); /* isotropic: x */
  r.sin_u = KF(0.0);
  if (rad > KF(0.0)) {
    /* cos and sin of twice the angle: (half_diff, sxy) / rad */
    float c2 = half_diff / rad, s2 = sxy / rad;
    if (c2 >= KF(0.0)) {
      r.cos_u = k_sqrt(KF(0.5) * (KF(1.0) + c2));
      r.sin_u = KF(0.5) * s2 / r.cos_u;
    } else {
      r.sin_u = k_sqrt(KF(0.5) * (KF(1.0) - c2));
      if (s2 < KF(0.0)) r.sin_u = -r.sin_u;
      r.cos_u = KF(0.5) * s2 / r.sin_u;
    }
  }
  r.alpha_u = k_fmax(k_sqrt(KF(2.0) * l1), KB_ALPHA_MIN);
  r.alpha_v = k_fmax(k_sqrt(KF(2.0) * l2), KB_ALPHA_MIN);
  return r;
}

#endif /* KNIT_KERNEL_BSDF_MICROFACET_H */
