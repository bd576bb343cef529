/* Knitshade kernel: the near-field yarn BSDF (yarn_bsdf.h, paper Eq. 1) as
 * Cycles renders it, with closures that every Cycles from 3.4 on provides
 * to OSL. The OSL shader (osl/knit_fabric.osl) emits
 *
 *   spec      microfacet("ggx", n, t, ax, ay, eta, 0)  GGX reflection, no Fresnel
 *   body_r    diffuse(n)                               Lambertian reflection
 *   body_t    translucent(n)                           Lambertian transmission
 *   through   transparent()                            straight on, unscattered
 *
 * with n facing the viewer and the weights of yarn_cycles_lobes, which
 * depend on the view direction wo but not on the light direction wi (Cycles
 * evaluates lights outside the shader). The native library renders the same
 * mixture (knit material option "bsdf_model": "cycles"), so the error of the
 * approximation is measured against the exact lobes and against explicit
 * yarns (docs/cycles.md).
 *
 * Each weight is the directional albedo at wo of the exact lobes it stands
 * for, divided by its closure's: under light that is the same from every
 * direction the mixture returns what the exact BSDF does; what it cannot
 * keep is the exact lobes' shape.
 *   spec     F(wo.h) D G2 / (4 cos cos) -> the GGX lobe without Fresnel
 *            weighted by the visible normals' mean Fresnel reflectance,
 *            E[F(wo.h) g] / E[g] over h ~ D_wo (g = G2 / G1, the sample
 *            weight of the GGX lobe). F(|wo.z|) at the macro normal gives 5
 *            times the exact albedo at 85 degrees across the yarn.
 *   body_r   r B G (1 - F_o) k_R int LS (1 - F_i) |wi.z| dwi
 *            = r B G (1 - F_o) k_R int_0^1 mu (1 - F(mu)) / (mu + mu_o) dmu.
 *   body_t   (1 - r) B G (1 - F_o) k_T int tau (1 - F_i) |wi.z| / pi dwi.
 *            tau = exp(-k (l(wo) + l(wi))) with k = n D / 2 factorises, so
 *            this is exp(-k l(wo)) C(k, eta), C the cosine-weighted mean of
 *            exp(-k l(w)) (1 - F(|w.z|)) over a hemisphere. The
 *            straight-through tau (exp(-2 k l(wo))) gives 97% too little to
 *            148% too much at 60-89 degrees.
 *   through  the thin-slab lobe f_T, centred on wi = -wo with roughness
 *            spec_t: its albedo (1 - B) exp(-k l(wo)) E[(1 - F(wo.h))^2 g
 *            exp(-k l(wi))] (h ~ D_wo of spec_t, wi the mirrored
 *            reflection) is shared between transparent() and
 *            translucent(), no closure being a blurred straight-through
 *            lobe. transparent() takes the share
 *            exp(-ax ay / YC_DELTA_ALPHA^2): all of a smooth slab's lobe,
 *            nothing of a rough one's (1.5e-8 at the default 0.3 x 0.6),
 *            whose light would otherwise be lost to every sun or point
 *            light behind the fabric (a delta meets no delta light): the
 *            half cylinder lit from behind was 26% too dark with the whole
 *            lobe on transparent(), 15% with it on translucent()
 *            (docs/cycles.md). The rest is added to body_t, uncoloured.
 * The expectations over visible normals use a fixed rank-1 lattice of
 * YC_VNDF_POINTS points (a Fibonacci lattice, 21 points); the integrals in
 * mu and over the hemisphere 8-point Gauss-Legendre rules. Accuracy against
 * double-precision integrals of the exact lobes: tests/native/
 * test_bsdf_cycles.cpp, figures in docs/cycles.md.
 *
 * The mixture as a BSDF (the native renderer's "cycles" option, and the
 * tests), with the contract of bsdf_common.h: yarn_cycles_make(p, wo) fixes
 * the weights at wo (they must be used with the same wo), then
 *   yarn_cycles_eval(c, wo, wi)    the three smooth lobes, f |wi.z|
 *   yarn_cycles_pdf(c, wo, wi)     solid-angle density of yarn_cycles_sample's
 *                                  smooth lobes (the delta not included)
 *   yarn_cycles_sample(c, wo, u1, u2)  one lobe by u1 (rescaled and reused);
 *                                  the delta: wi = -wo, weight through / P,
 *                                  pdf P (its probability), KB_TRANSMIT | KB_DELTA
 * and, for hosts that take the delta as a pass-through event before shading
 * (the native renderer: the ray goes on with probability p3, weight
 * through / p3), the smooth lobes alone, conditioned on not passing:
 *   yarn_cycles_pdf_smooth, yarn_cycles_sample_smooth.
 * Lobe selection probabilities are proportional to the lobes' albedos at wo
 * (spec times the GGX albedo, the mean of body_r and body_t, through), each
 * with a floor of 1e-3 when the lobe is not zero, as yarn_bsdf.h does.
 * Reciprocity does not apply: the weights depend on wo alone.
 *
 * Parameters: those of KYarnBsdf (yarn_bsdf.h; spec_t's roughness shapes only
 * the thin-slab lobe's weights, through and its share of body_t). The closure weights (KCyclesLobes):
 *   name     type    meaning
 *   spec     float   weight of the GGX reflection closure (spec_r's roughness, no Fresnel)
 *   body_r   kvec3   weight of diffuse()
 *   body_t   kvec3   weight of translucent()
 *   through  float   weight of transparent()
 */
#ifndef KNIT_KERNEL_BSDF_CYCLES_H
#define KNIT_KERNEL_BSDF_CYCLES_H

/* Points of the fixed lattice over the visible normals (u1 = (i + 1/2) / N,
 * u2 = frac(i YC_VNDF_STEP / N + 1/(2N)); 21 and 13 are Fibonacci numbers).
 * bsdf_cycles_vndf_means holds them as a table of disk points: change the
 * two together. */
#define YC_VNDF_POINTS 21
#define YC_VNDF_STEP 13
/* Selection weight floor of a lobe that is not zero (as YB_LOBE_FLOOR). */
#define YC_LOBE_FLOOR KF(1.0e-3)
/* The thin-slab lobe's share the transparent() closure takes,
 * exp(-ax ay / YC_DELTA_ALPHA^2) with (ax, ay) its roughness; the rest goes
 * to translucent(). */
#define YC_DELTA_ALPHA KF(0.1)

KNIT_STRUCT(KCyclesLobes)
  float spec;
  kvec3 body_r;
  kvec3 body_t;
  float through;
KNIT_STRUCT_END(KCyclesLobes)

/* The mixture at one view direction: weights, GGX roughness, and the lobe
 * selection probabilities p0 (GGX), p1 (diffuse), p2 (translucent), p3
 * (transparent), summing to 1 (all 0 when every weight is). */
KNIT_STRUCT(KYarnCycles)
  KCyclesLobes w;
  float alpha_x, alpha_y;
  float p0, p1, p2, p3;
  kvec3 ns; /* the mesh's smooth normal in this frame (yarn_cycles_with_base); 0: no side test */
  int cycles4; /* 1: Cycles 4's rule for the GGX closure (yarn_cycles_as_cycles4) */
KNIT_STRUCT_END(KYarnCycles)

/* Cycles (4.2 and later) lets a closure whose normal n is not the mesh's
 * smooth normal ns light only from directions wi with
 *   (ns . wi) (ns . n) (n . wi) >= 0
 * (bump_shadowing_term in its kernel/closure/bsdf.h: it keeps bump-mapped
 * normals from taking light from behind opaque geometry): a yarn normal
 * facing the front of the mesh reflects light from the front only, and
 * transmits light from behind only. 1 when wi passes, 0 when Cycles drops
 * it; ns in the local frame (n = +z), either sign. Bump map correction, which
 * softens diffuse light further, is off for Knit Fabric materials (the
 * add-on turns it off). */
KNIT_FN float yarn_cycles_side_ok(kvec3 ns, kvec3 wi) {
  return kv3_dot(ns, wi) * KZ(ns) * KZ(wi) < KF(0.0) ? KF(0.0) : KF(1.0);
}

/* Cycles' samplers (bsdf_diffuse_sample, bsdf_translucent_sample,
 * bsdf_microfacet_sample) drop a drawn direction wi on the wrong side of
 * the surface's normal (turned towards the viewer): below it for the
 * reflecting closures, above it for translucent(). The evaluation (and the
 * pdf Cycles weighs light samples with) does not: where a closure normal
 * tilts below the surface, light sampling finds light that closure sampling
 * never draws, and under a light Cycles samples both ways (MIS: a sky, an
 * area light) it renders darker than the closures' integral (by 6% under a
 * uniform sky on the comparison swatch). 1 when wi passes; ns as in
 * yarn_cycles_side_ok (0: no test); transmit != 0 for translucent(). */
KNIT_FN float yarn_cycles_sample_side_ok(kvec3 ns, kvec3 wo, kvec3 wi, int transmit) {
  float g = kv3_dot(ns, wi) * (kv3_dot(ns, wo) < KF(0.0) ? KF(-1.0) : KF(1.0));
  if (kv3_len2(ns) == KF(0.0)) return KF(1.0);
  return (transmit != 0 ? g < KF(0.0) : g > KF(0.0)) ? KF(1.0) : KF(0.0);
}

/* Node i (0..7) of the 8-point Gauss-Legendre rule on [0, 1]: the abscissa in
 * KX, its weight in KY (the weights sum to 1). */
KNIT_FN kvec3 bsdf_cycles_gl8(int i) {
  int j = i < 4 ? 3 - i : i - 4;
  float x = j == 0 ? KF(0.1834346424956498) : (j == 1 ? KF(0.5255324099163290)
                                            : (j == 2 ? KF(0.7966664774136267) : KF(0.9602898564975363)));
  float w = j == 0 ? KF(0.3626837833783620) : (j == 1 ? KF(0.3137066458778873)
                                            : (j == 2 ? KF(0.2223810344533745) : KF(0.1012285362903763)));
  float s = i < 4 ? KF(-1.0) : KF(1.0);
  return kv3(KF(0.5) * (KF(1.0) + s * x), KF(0.5) * w, KF(0.0));
}

/* Fresnel reflectance of the yarn surface, 0 for an index-matched yarn
 * (kb_fresnel_dielectric gives 1 at exact grazing even for eta = 1). */
KNIT_FN float bsdf_cycles_fresnel(float c, float eta) {
  return eta > KF(1.0) ? kb_fresnel_dielectric(c, eta) : KF(0.0);
}

/* int_0^1 mu (1 - F(mu)) / (mu + mu_o) dmu: the directional albedo of the
 * Lommel-Seeliger lobe (bsdf_ls_albedo) with the Fresnel transmittance of
 * the light it scatters. The Fresnel part, a few percent of the whole, by
 * Gauss-Legendre in mu (within 0.3% of the whole for eta in [1.1, 3]). */
KNIT_FN float bsdf_cycles_ls_albedo(float mu_o, float eta) {
  float mo = k_clampf(k_fabs(mu_o), KF(0.0), KF(1.0));
  float sum = KF(0.0);
  int i;
  if (eta <= KF(1.0)) return bsdf_ls_albedo(mo);
  for (i = 0; i < 8; i++) {
    kvec3 g = bsdf_cycles_gl8(i);
    float mu = KX(g);
    sum = sum + KY(g) * mu * kb_fresnel_dielectric(mu, eta) / (mu + mo);
  }
  return k_fmax(bsdf_ls_albedo(mo) - sum, KF(0.0));
}

/* C(k, eta) = int_hemisphere exp(-k l(w)) (1 - F(|w.z|)) |w.z| / pi dw, l the
 * tube chord of bsdf_att_chord. Around the tube axis x, w = (x, rho sin psi,
 * rho cos psi) with rho = sqrt(1 - x^2) and dw = dx dpsi (Archimedes), so
 * l = cos psi / rho; with x = sin(pi s / 2), psi = pi t / 2 (smooth at the
 * poles) and the symmetries in x and psi,
 *   C = pi int_0^1 ds int_0^1 dt rho exp(-k l) (1 - F(rho cos psi)) rho cos psi,
 * here by an 8 x 8 Gauss-Legendre product rule: within 3e-5 of C for
 * k <= 2, 2e-4 at k = 4, 0.3% at k = 10 (where C is 0.004). */
KNIT_FN float bsdf_cycles_transmit_mean(float k, float eta) {
  /* cos(pi x / 2) at bsdf_cycles_gl8's nodes x, and its weights */
  float cn[8] = { KF(0.999513685), KF(0.987275388), KF(0.931367258), KF(0.801301418), KF(0.598260844), KF(0.364081077), KF(0.159019835), KF(0.031183218) };
  float wn[8] = { KF(0.050614268), KF(0.111190517), KF(0.156853323), KF(0.181341892), KF(0.181341892), KF(0.156853323), KF(0.111190517), KF(0.050614268) };
  float sum = KF(0.0);
  int i, j;
  for (i = 0; i < 8; i++) {
    float rho = cn[i];
    for (j = 0; j < 8; j++) {
      float cp = cn[j];
      float mu = rho * cp;
      float l = cp >= rho * KB_CHORD_MAX ? KB_CHORD_MAX : cp / rho;
      sum = sum + wn[i] * wn[j] * rho * k_exp(-k * l) * (KF(1.0) - bsdf_cycles_fresnel(mu, eta)) * mu;
    }
  }
  return sum * K_PI;
}

/* The lattice's expectations over the visible normals h ~ D_wo of the GGX
 * roughness (ax, ay), o = wo on the upper side, g = G2 / G1 of the
 * reflected direction (0 below the surface):
 *   KX: E[F(o.h) g]   KY: E[g] (the GGX lobe's albedo without Fresnel)
 *   KZ: E[(1 - F(o.h))^2 g exp(-k l(i))]  (the thin-slab lobe's albedo
 *       with the exit side's attenuation, i its mirrored direction) */
KNIT_FN kvec3 bsdf_cycles_vndf_means(float ax_in, float ay_in, kvec3 o, float eta, float k) {
  float ax = k_fmax(ax_in, KB_ALPHA_MIN);
  float ay = k_fmax(ay_in, KB_ALPHA_MIN);
  float lo = mf_ggx_zlambda(ax, ay, o);
  float sf = KF(0.0), sg = KF(0.0), st = KF(0.0);
  float inv = KF(1.0) / KFLT(YC_VNDF_POINTS);
  /* the lattice's points on the unit disk, sqrt(u1) (cos, sin)(2 pi u2) */
  float dx[YC_VNDF_POINTS] = { KF(0.152579909), KF(-0.166634659), KF(-0.025784332), KF(0.299267173), KF(-0.462910050), KF(0.375151256), KF(-0.041575986), KF(-0.372606424), KF(0.629103081), KF(-0.555722176), KF(0.157346061), KF(0.370006435), KF(-0.737240425), KF(0.722382176), KF(-0.303579748), KF(-0.313873495), KF(0.798623544), KF(-0.872314635), KF(0.469295318), KF(0.214426537), KF(-0.816343342) };
  float dy[YC_VNDF_POINTS] = { KF(0.022997721), KF(-0.208953253), KF(0.344067998), KF(-0.277679357), KF(0.000000000), KF(0.348089496), KF(-0.554792977), KF(0.467233678), KF(-0.094822033), KF(-0.378884964), KF(0.689378138), KF(-0.640869944), KF(0.227408554), KF(0.347880921), KF(-0.773508582), KF(0.799736624), KF(-0.384596829), KF(-0.269073430), KF(0.812843334), KF(-0.939464043), KF(0.556573467) };
  KVndfFrame vf = mf_ggx_vndf_frame(ax, ay, o);
  int i;
  for (i = 0; i < YC_VNDF_POINTS; i++) {
    kvec3 h, r;
    float oh, den, g, f;
    h = mf_ggx_vndf_from_disk(vf, ax, ay, dx[i], dy[i]);
    oh = kv3_dot(o, h);
    if (oh > KF(0.0) && KZ(h) > KF(0.0)) {
      r = kv3_normalize(kv3_sub(kv3_scale(h, KF(2.0) * oh), o));
      den = KZ(o) * KZ(r) + KZ(r) * lo + KZ(o) * mf_ggx_zlambda(ax, ay, r);
      if (KZ(r) > KF(0.0) && den > KF(0.0)) {
        g = KZ(r) * (KZ(o) + lo) / den;
        f = bsdf_cycles_fresnel(oh, eta);
        sf = sf + f * g;
        sg = sg + g;
        st = st + (KF(1.0) - f) * (KF(1.0) - f) * g * k_exp(-k * bsdf_att_chord(r));
      }
    }
  }
  return kv3(sf * inv, sg * inv, st * inv);
}

/* The share of the thin-slab lobe f_T (roughness ax, ay) that transparent()
 * stands for: 1 for a smooth slab, falling to 0 as the lobe widens past a
 * few degrees (exp(-ax ay / YC_DELTA_ALPHA^2): 0.37 at 0.1 x 0.1, 1.5e-8
 * at the default 0.3 x 0.6). */
KNIT_FN float bsdf_cycles_delta_share(float ax, float ay) {
  float a2 = k_fmax(ax, KB_ALPHA_MIN) * k_fmax(ay, KB_ALPHA_MIN);
  return k_exp(-a2 / (YC_DELTA_ALPHA * YC_DELTA_ALPHA));
}

/* The closure weights and selection probabilities for the view direction wo
 * (local frame, either side). */
KNIT_FN KYarnCycles yarn_cycles_make(KNIT_IN(KYarnBsdf) p, kvec3 wo) {
  KYarnCycles c;
  float mo = k_fabs(KZ(wo));
  kvec3 o = kv3(KX(wo), KY(wo), mo);
  float eta = p.spec_r.eta;
  float b = p.body_energy;
  float k = KF(0.5) * p.atten.optical_depth * KFLT(k_maxi(1, k_mini(p.atten.layers, KB_MAX_LAYERS)));
  float fo, body, e_o, w0, w1, w2, w3, sum, inv, thin, share, rest;
  kvec3 mr, mt;
  c.ns = kv3(KF(0.0), KF(0.0), KF(0.0));
  c.cycles4 = 0;
  c.alpha_x = k_fmax(p.spec_r.alpha_x, KB_ALPHA_MIN);
  c.alpha_y = k_fmax(p.spec_r.alpha_y, KB_ALPHA_MIN);
  c.w.spec = KF(0.0);
  c.w.body_r = KB_BLACK;
  c.w.body_t = KB_BLACK;
  c.w.through = KF(0.0);
  c.p0 = KF(0.0);
  c.p1 = KF(0.0);
  c.p2 = KF(0.0);
  c.p3 = KF(0.0);
  if (!(mo > KF(0.0))) return c; /* the exact BSDF is black at exact grazing */
  fo = bsdf_cycles_fresnel(mo, eta);
  e_o = k_exp(-k * bsdf_att_chord(wo));
  body = b * p.shadow * (KF(1.0) - fo);
  mr = eta > KF(1.0) ? bsdf_cycles_vndf_means(c.alpha_x, c.alpha_y, o, eta, k) : KB_BLACK;
  c.w.spec = KY(mr) > KF(0.0) ? KX(mr) / KY(mr) : KF(0.0);
  c.w.body_r = kv3_scale(p.kd_r, p.body_reflect * body * bsdf_cycles_ls_albedo(mo, eta));
  c.w.body_t = kv3_scale(p.kd_t, (KF(1.0) - p.body_reflect) * body * e_o * bsdf_cycles_transmit_mean(k, eta));
  if (b < KF(1.0)) {
    mt = bsdf_cycles_vndf_means(p.spec_t.alpha_x, p.spec_t.alpha_y, o, eta, k);
    thin = (KF(1.0) - b) * e_o * KZ(mt);
    share = bsdf_cycles_delta_share(p.spec_t.alpha_x, p.spec_t.alpha_y);
    rest = (KF(1.0) - share) * thin;
    c.w.through = share * thin;
    c.w.body_t = kv3_add(c.w.body_t, kv3(rest, rest, rest));
  }
  w0 = c.w.spec * KY(mr);
  w1 = kb_average(c.w.body_r);
  w2 = kb_average(c.w.body_t);
  w3 = c.w.through;
  w0 = w0 > KF(0.0) ? k_fmax(w0, YC_LOBE_FLOOR) : KF(0.0);
  w1 = w1 > KF(0.0) ? k_fmax(w1, YC_LOBE_FLOOR) : KF(0.0);
  w2 = w2 > KF(0.0) ? k_fmax(w2, YC_LOBE_FLOOR) : KF(0.0);
  w3 = w3 > KF(0.0) ? k_fmax(w3, YC_LOBE_FLOOR) : KF(0.0);
  sum = w0 + w1 + w2 + w3;
  inv = sum > KF(0.0) ? KF(1.0) / sum : KF(0.0);
  c.p0 = w0 * inv;
  c.p1 = w1 * inv;
  c.p2 = w2 * inv;
  c.p3 = w3 * inv;
  return c;
}

/* c with Cycles' side test (yarn_cycles_side_ok) for the mesh's smooth
 * normal ns_local, expressed in c's frame: eval, pdf and sample then drop
 * the directions Cycles drops. */
KNIT_FN KYarnCycles yarn_cycles_with_base(KNIT_IN(KYarnCycles) c_in, kvec3 ns_local) {
  KYarnCycles c = c_in;
  c.ns = ns_local;
  return c;
}

/* c as Cycles before 5.0 (Blender 4.x, the standalone Cycles 4.2) renders
 * it: its GGX closure takes light from the viewer's side of the surface's
 * normal whatever the closure normal's tilt (bsdf_microfacet_eval's test
 * against sd->N), where Cycles 5 applies the side test of
 * yarn_cycles_side_ok to it too; and where the side test drops a
 * diffuse() or translucent() direction, Cycles 4 zeroes its value but keeps
 * its density (in the mixture's pdf, for MIS and for the other closures'
 * samples), where Cycles 5 drops both. diffuse() and translucent() take the
 * side test in both (Cycles 4 through bump_shadowing_term, bump map
 * correction off). Needs yarn_cycles_with_base. */
KNIT_FN KYarnCycles yarn_cycles_as_cycles4(KNIT_IN(KYarnCycles) c_in) {
  KYarnCycles c = c_in;
  c.cycles4 = 1;
  return c;
}

/* 1 when the GGX closure takes light from wi (reflection, local frame). */
KNIT_FN float yarn_cycles_ggx_side_ok(KNIT_IN(KYarnCycles) c, kvec3 wo, kvec3 wi) {
  return c.cycles4 != 0 ? yarn_cycles_sample_side_ok(c.ns, wo, wi, 0) : yarn_cycles_side_ok(c.ns, wi);
}

/* The closure weights for the view direction wo (local frame, either side):
 * what the OSL shader multiplies its four closures by. */
KNIT_FN KCyclesLobes yarn_cycles_lobes(KNIT_IN(KYarnBsdf) p, kvec3 wo) {
  KYarnCycles c = yarn_cycles_make(p, wo);
  return c.w;
}

/* f |wi.z| of the three smooth lobes (the delta is not in eval). */
KNIT_FN kvec3 yarn_cycles_eval(KNIT_IN(KYarnCycles) c, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  kvec3 o = kb_flip_z(wo, s);
  kvec3 i = kb_flip_z(wi, s);
  kvec3 hs = kv3_add(o, i);
  float ggx = KF(0.0);
  float ok = yarn_cycles_side_ok(c.ns, wi);
  if (KZ(wo) * KZ(wi) == KF(0.0)) return KB_BLACK;
  if (KZ(i) < KF(0.0)) return kv3_scale(c.w.body_t, ok * -KZ(i) * K_INV_PI);
  if (c.w.spec > KF(0.0) && kv3_len2(hs) > KF(0.0) && yarn_cycles_ggx_side_ok(c, wo, wi) != KF(0.0))
    ggx = c.w.spec * mf_refl_core(c.alpha_x, c.alpha_y, o, i, kv3_normalize(hs)) * KZ(i);
  return kv3_add(kv3(ggx, ggx, ggx), kv3_scale(c.w.body_r, ok * KZ(i) * K_INV_PI));
}

/* Solid-angle density of yarn_cycles_sample's smooth lobes. */
KNIT_FN float yarn_cycles_pdf(KNIT_IN(KYarnCycles) c, kvec3 wo, kvec3 wi) {
  float s = kb_side(wo);
  kvec3 o = kb_flip_z(wo, s);
  kvec3 i = kb_flip_z(wi, s);
  kvec3 hs = kv3_add(o, i);
  float pg = KF(0.0);
  /* (Cycles 4 keeps the density of a diffuse() or translucent() direction
   * its side test drops: bsdf_eval scales the value alone) */
  float ok = c.cycles4 != 0 ? KF(1.0) : yarn_cycles_side_ok(c.ns, wi);
  if (KZ(wo) * KZ(wi) == KF(0.0)) return KF(0.0);
  if (KZ(i) < KF(0.0)) return ok * c.p2 * (-KZ(i)) * K_INV_PI;
  if (c.p0 > KF(0.0) && kv3_len2(hs) > KF(0.0) && yarn_cycles_ggx_side_ok(c, wo, wi) != KF(0.0))
    pg = c.p0 * mf_refl_pdf_up(c.alpha_x, c.alpha_y, o, kv3_normalize(hs));
  return pg + ok * c.p1 * KZ(i) * K_INV_PI;
}

/* Density of the smooth lobes given that the delta was not chosen. */
KNIT_FN float yarn_cycles_pdf_smooth(KNIT_IN(KYarnCycles) c, kvec3 wo, kvec3 wi) {
  float ps = c.p0 + c.p1 + c.p2;
  return ps > KF(0.0) ? yarn_cycles_pdf(c, wo, wi) / ps : KF(0.0);
}

/* A lobe chosen with u1 (all four, or with smooth_only != 0 the smooth ones
 * alone, their probabilities divided by their sum) and sampled with (u1',
 * u2); weight = eval / pdf, with the pdf of the lobes it chooses among. */
KNIT_FN KBsdfSample yarn_cycles_sample_in(KNIT_IN(KYarnCycles) c, kvec3 wo, float u1, float u2, int smooth_only) {
  float c1 = c.p0;
  float c2 = c1 + c.p1;
  float c3 = c2 + c.p2;
  float total = smooth_only != 0 ? c3 : c3 + c.p3;
  float side = kb_side(wo);
  float u = u1 * total;
  float start, pk, ur, pdf, w;
  int k = smooth_only != 0 ? 2 : 3;
  KBsdfSample s;
  kvec3 d;
  if (!(total > KF(0.0)) || KZ(wo) == KF(0.0)) return kb_sample_fail(wo);
  if (u < c3) k = 2;
  if (u < c2) k = 1;
  if (u < c1) k = 0;
  pk = k == 0 ? c.p0 : (k == 1 ? c.p1 : (k == 2 ? c.p2 : c.p3));
  while (k > 0 && pk <= KF(0.0)) { /* rounding at the top end */
    k = k - 1;
    pk = k == 0 ? c.p0 : (k == 1 ? c.p1 : c.p2);
  }
  if (!(pk > KF(0.0))) return kb_sample_fail(wo);
  if (k == 3) {
    w = c.w.through / pk;
    return kb_sample_make(kv3_neg(wo), kv3(w, w, w), pk, KB_TRANSMIT + KB_DELTA);
  }
  start = k == 0 ? KF(0.0) : (k == 1 ? c1 : c2);
  ur = k_clampf((u - start) / pk, KF(0.0), KF(0.99999994));
  if (k == 0) {
    s = mf_sample_dir_up(bsdf_mf_make(c.alpha_x, c.alpha_y, KF(1.0)), kb_flip_z(wo, side), ur, u2);
    if (s.pdf <= KF(0.0)) return kb_sample_fail(wo);
    s.wi = kb_flip_z(s.wi, side);
    s.flags = KB_REFLECT;
  } else {
    d = kb_cosine_hemisphere(ur, u2);
    if (KZ(d) <= KF(0.0)) return kb_sample_fail(wo);
    s = kb_sample_make(kb_flip_z(d, k == 1 ? side : -side), KB_BLACK, KF(1.0), k == 1 ? KB_REFLECT : KB_TRANSMIT);
  }
  if (yarn_cycles_sample_side_ok(c.ns, wo, s.wi, k == 2) == KF(0.0)) return kb_sample_fail(wo);
  if (c.cycles4 == 0 && yarn_cycles_side_ok(c.ns, s.wi) == KF(0.0)) {
    /* Cycles 5 applies the side test to a drawn direction through
     * bump_shadowing_term, which zeroes the drawn closure's value only when
     * it is diffuse() or translucent() and keeps its density; the other
     * closures, evaluated there, give it neither. So the drawn closure
     * alone counts, without the test, and a GGX draw keeps its value. */
    KYarnCycles own = c;
    own.ns = kv3(KF(0.0), KF(0.0), KF(0.0));
    own.p0 = k == 0 ? c.p0 : KF(0.0);
    own.p1 = k == 1 ? c.p1 : KF(0.0);
    own.p2 = k == 2 ? c.p2 : KF(0.0);
    own.w.body_r = KB_BLACK;
    own.w.body_t = KB_BLACK;
    if (k != 0) own.w.spec = KF(0.0);
    pdf = yarn_cycles_pdf(own, wo, s.wi) / total;
    if (!(pdf > KF(0.0))) return kb_sample_fail(wo);
    return kb_sample_make(s.wi, kv3_scale(yarn_cycles_eval(own, wo, s.wi), KF(1.0) / pdf), pdf, s.flags);
  }
  pdf = yarn_cycles_pdf(c, wo, s.wi) / total;
  if (!(pdf > KF(0.0))) return kb_sample_fail(wo);
  return kb_sample_make(s.wi, kv3_scale(yarn_cycles_eval(c, wo, s.wi), KF(1.0) / pdf), pdf, s.flags);
}

/* The whole mixture, the delta included (see the file header). */
KNIT_FN KBsdfSample yarn_cycles_sample(KNIT_IN(KYarnCycles) c, kvec3 wo, float u1, float u2) {
  return yarn_cycles_sample_in(c, wo, u1, u2, 0);
}

/* The smooth lobes given that the delta was not chosen: pdf
 * yarn_cycles_pdf_smooth, weight = eval / that pdf. */
KNIT_FN KBsdfSample yarn_cycles_sample_smooth(KNIT_IN(KYarnCycles) c, kvec3 wo, float u1, float u2) {
  return yarn_cycles_sample_in(c, wo, u1, u2, 1);
}

#endif /* KNIT_KERNEL_BSDF_CYCLES_H */
