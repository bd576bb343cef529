/* Knitshade kernel: the double-layer attenuation tau(x, y) of the near-field
 * yarn BSDF, paper Eq. 1 (after Khattar et al. 2025, woven model): the loss
 * of light transmitted through one yarn, or through overlapping yarns.
 *
 * Form chosen: Beer-Lambert extinction along the chord through a round tube.
 * In the local frame at the shading point (z = outward normal of the tube,
 * x = tube axis), a straight line entering the tube at this point with unit
 * direction d runs inside the tube for
 *   L(d) = 2 R |d.z| / (d.y^2 + d.z^2)
 * (R the tube radius): 2R straight down the normal, shorter towards the
 * silhouette, longer along the axis. In units of the diameter,
 * l(d) = L / (2R) = |d.z| / (d.y^2 + d.z^2), clamped to KB_CHORD_MAX = 8
 * (a real yarn bends away long before a chord 16 R long).
 * Light leaving towards the viewer along wo and arriving from the light
 * along wi sees the yarn along both directions; the path length is taken as
 * their mean, which keeps tau symmetric in (wo, wi) and hence the BSDF
 * reciprocal (for the ballistic path wi = -wo both agree anyway):
 *   tau_1 = exp(-D (l(wo) + l(wi)) / 2)
 * D is the optical depth of one yarn straight through its centre (sigma 2R),
 * so R never appears. The geometry reports how many yarns the transmitted
 * path crosses (the layer count); each one is another tube of the same yarn,
 * crossed at about the same angle, so the transmittances multiply:
 *   tau = tau_1 ^ n,  n = clamp(layers, 1, KB_MAX_LAYERS)
 * n = 2 is the paper's double layer (overlapping yarns, tau_1^2); knit
 * interlocks can stack more loops, up to 4 are compounded. A host that
 * traces the other yarns itself (the native renderer's self-shadowing,
 * docs/renderer.md) passes n = 1: they already block the path.
 * Why this form: it is the exact ballistic transmittance of a homogeneous
 * round yarn for the entry point at hand, it needs no table, it is cheap
 * (one exp) and tau <= 1 always, so it can only remove energy.
 * What it leaves out: refraction bending the path inside (a yarn is mostly
 * air between fibres), and the second tube's own orientation (not reported by
 * the geometry).
 *
 * Parameters (KAttenuation):
 *   name           type   default  meaning
 *   optical_depth  float  1.0      D = sigma 2R, optical depth of one yarn through
 *                                  its centre, [0, 50]; 0 = no loss
 *   layers         int    1        yarns crossed by the transmitted path, from the
 *                                  geometry (1, or 2+ where yarns overlap)
 */
#ifndef KNIT_KERNEL_BSDF_ATTENUATION_H
#define KNIT_KERNEL_BSDF_ATTENUATION_H

#define KB_CHORD_MAX KF(8.0)
#define KB_MAX_LAYERS 4

KNIT_STRUCT(KAttenuation)
  float optical_depth; /* D */
  int layers;          /* n */
KNIT_STRUCT_END(KAttenuation)

KNIT_FN KAttenuation bsdf_att_make(float optical_depth, int layers) {
  KAttenuation a;
  a.optical_depth = k_fmax(optical_depth, KF(0.0));
  a.layers = layers;
  return a;
}

/* l(d) = |d.z| / (d.y^2 + d.z^2), the chord through a round tube from this
 * point along d, in units of the tube's diameter, clamped to KB_CHORD_MAX. */
KNIT_FN float bsdf_att_chord(kvec3 d) {
  float perp2 = KY(d) * KY(d) + KZ(d) * KZ(d);
  float az = k_fabs(KZ(d));
  if (az >= perp2 * KB_CHORD_MAX) return KB_CHORD_MAX;
  return az / perp2;
}

/* tau for a path seen along wo (towards the viewer) and wi (towards the light). */
KNIT_FN float bsdf_att_tau(KNIT_IN(KAttenuation) a, kvec3 wo, kvec3 wi) {
  int n = k_maxi(1, k_mini(a.layers, KB_MAX_LAYERS));
  float l = KF(0.5) * (bsdf_att_chord(wo) + bsdf_att_chord(wi));
  return k_exp(-a.optical_depth * KFLT(n) * l);
}

/* tau of the straight-through path wi = -wo (used to weigh lobes for sampling). */
KNIT_FN float bsdf_att_tau_straight(KNIT_IN(KAttenuation) a, kvec3 wo) {
  return bsdf_att_tau(a, wo, kv3_neg(wo));
}

#endif /* KNIT_KERNEL_BSDF_ATTENUATION_H */
