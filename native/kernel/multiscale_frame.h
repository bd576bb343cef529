/* Knitshade kernel: shading a multi-scale footprint with one yarn lobe
 * (paper Sec. 5.1, Eq. 9-11), for hosts that shade the aggregate in place.
 *
 *   knit_ms_lobe       the shading frame of an aggregate (mean normal, mean
 *                      tangent made orthogonal to it) and the specular lobe's
 *                      roughness widened by the footprint's LEAN slope
 *                      covariance, rotated into that frame: t is the widened
 *                      lobe's major axis, (alpha_u, alpha_v) its roughness
 *                      along t and b. The transmission lobe shares the frame;
 *                      its own widened roughness has its own principal axes,
 *                      and its two roughnesses go to the frame's axes nearer
 *                      to them (within 45 degrees), so that an anisotropic
 *                      lobe is never turned by 90 degrees: (trans_alpha_u,
 *                      trans_alpha_v). Vectors are in the base frame.
 *   ply_mean_shadow    the ply/fibre shadowing G averaged around the yarn
 *                      (n_phi azimuths) and along it (n_s steps of 0.37
 *                      yarn-radius units of arc): a footprint of many yarn
 *                      points sees its mean. */
#ifndef KNIT_KERNEL_MULTISCALE_FRAME_H
#define KNIT_KERNEL_MULTISCALE_FRAME_H

KNIT_STRUCT(KMsLobe)
  kvec3 t, b, n;
  float alpha_u, alpha_v;
  float trans_alpha_u, trans_alpha_v;
KNIT_STRUCT_END(KMsLobe)

KNIT_FN KMsLobe knit_ms_lobe(kvec3 mean_n, kvec3 mean_t, float sxx_in, float sxy_in, float syy_in, float alpha_x,
                             float alpha_y, float trans_alpha_x, float trans_alpha_y) {
  KMsLobe o;
  kvec3 n = kv3_normalize(mean_n);
  kvec3 tg = kv3_sub(mean_t, kv3_scale(n, kv3_dot(mean_t, n)));
  float txy, c, s, sxx, syy, sxy, cos2d;
  KLeanRoughness lr, lt;
  if (k_sqrt(kv3_len2(tg)) < KF(1.0e-4)) tg = kv3_cross(kv3(KF(0.0), KF(1.0), KF(0.0)), n);
  tg = kv3_normalize(tg);
  /* cos and sin of the tangent's azimuth, without the trigonometry */
  txy = k_sqrt(KX(tg) * KX(tg) + KY(tg) * KY(tg));
  c = txy > KF(0.0) ? KX(tg) / txy : KF(1.0);
  s = txy > KF(0.0) ? KY(tg) / txy : KF(0.0);
  sxx = c * c * sxx_in + KF(2.0) * c * s * sxy_in + s * s * syy_in;
  syy = s * s * sxx_in - KF(2.0) * c * s * sxy_in + c * c * syy_in;
  sxy = (c * c - s * s) * sxy_in + c * s * (syy_in - sxx_in);
  lr = bsdf_lean_to_ggx(alpha_x, alpha_y, sxx, sxy, syy);
  o.n = n;
  o.t = kv3_add(kv3_scale(tg, lr.cos_u), kv3_scale(kv3_cross(n, tg), lr.sin_u));
  o.b = kv3_cross(n, o.t);
  o.alpha_u = k_fmin(lr.alpha_u, KF(1.0));
  o.alpha_v = k_fmin(lr.alpha_v, KF(1.0));
  /* The axes are more than 45 degrees apart (modulo 180) when the cosine of
   * twice the angle between them is negative. */
  lt = bsdf_lean_to_ggx(trans_alpha_x, trans_alpha_y, sxx, sxy, syy);
  cos2d = (lt.cos_u * lt.cos_u - lt.sin_u * lt.sin_u) * (lr.cos_u * lr.cos_u - lr.sin_u * lr.sin_u) +
          KF(4.0) * lt.cos_u * lt.sin_u * lr.cos_u * lr.sin_u;
  o.trans_alpha_u = k_fmin(cos2d < KF(0.0) ? lt.alpha_v : lt.alpha_u, KF(1.0));
  o.trans_alpha_v = k_fmin(cos2d < KF(0.0) ? lt.alpha_u : lt.alpha_v, KF(1.0));
  return o;
}

KNIT_FN float ply_mean_shadow(KNIT_IN(KPlyParams) p, int n_phi, int n_s) {
  float g = KF(0.0);
  int i, j;
  for (i = 0; i < n_phi; i++)
    for (j = 0; j < n_s; j++) {
      KPlyShade ps = ply_shade_procedural(p, K_2PI * (KFLT(i) + KF(0.5)) / KFLT(n_phi), KF(0.37) * KFLT(j));
      g = g + ps.shadow;
    }
  return g / KFLT(n_phi * n_s);
}

#endif /* KNIT_KERNEL_MULTISCALE_FRAME_H */
