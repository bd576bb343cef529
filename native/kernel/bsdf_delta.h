/* Knitshade kernel: delta transmission through the gaps between yarns
 * (paper Sec. 5.1 and 6.2, after Zhu et al. 2023).
 *
 * Near field, the geometry decides: a ray that misses every yarn tube passes
 * straight through the fabric, unchanged. Far field, the multi-scale model
 * aggregates the footprint and reports p_delta in [0, 1], the fraction of the
 * footprint where rays pass through. The surface then scatters with
 *   f_total(wo, wi) = p_delta delta(wi + wo) / |wi.z| + (1 - p_delta) f_yarn(wo, wi).
 * The paper (Sec. 6.2) blends the sampled direction with the incoming one by a
 * p_delta-weighted average; averaging directions is not an estimator of
 * f_total, so Knitshade chooses stochastically instead (same limits:
 * p_delta -> 1 passes straight through unattenuated, p_delta -> 0 uses the
 * BSDF):
 *   with probability p_delta: wi = -wo, weight 1 (= p_delta / p_delta), pdf =
 *     p_delta as a discrete probability, flags KB_TRANSMIT | KB_DELTA;
 *   otherwise: sample f_yarn; the weight f_yarn / pdf_yarn is unchanged
 *     ((1 - p_delta) cancels), and the solid-angle pdf to report for MIS is
 *     (1 - p_delta) pdf_yarn.
 * Light sampling (next-event estimation) can never hit the delta part; it
 * evaluates (1 - p_delta) f_yarn (bsdf_delta_scale). yarn_bsdf.h has the
 * complete sample/eval/pdf with gaps.
 *
 * Parameters: p_delta (float, default 0, in [0, 1]): probability of passing
 * through, from the geometry (0 or 1) or the multi-scale model.
 */
#ifndef KNIT_KERNEL_BSDF_DELTA_H
#define KNIT_KERNEL_BSDF_DELTA_H

KNIT_STRUCT(KDeltaChoice)
  int pass;   /* 1: pass straight through (wi = -wo); 0: use the yarn BSDF */
  float prob; /* probability of the branch taken */
  float u;    /* the random number, rescaled to [0, 1) within the branch, for reuse */
KNIT_STRUCT_END(KDeltaChoice)

KNIT_FN KDeltaChoice bsdf_delta_choose(float p_delta, float u) {
  KDeltaChoice c;
  float p = k_clampf(p_delta, KF(0.0), KF(1.0));
  if (u < p) {
    c.pass = 1;
    c.prob = p;
    c.u = k_fmin(u / p, KF(0.99999994));
  } else {
    c.pass = 0;
    c.prob = KF(1.0) - p;
    c.u = c.prob > KF(0.0) ? k_fmin((u - p) / c.prob, KF(0.99999994)) : KF(0.0);
  }
  return c;
}

/* The pass-through event itself: wi = -wo with unit weight. `prob` is the
 * probability with which it was chosen (reported as its discrete pdf). */
KNIT_FN KBsdfSample bsdf_delta_sample(kvec3 wo, float prob) {
  return kb_sample_make(kv3_neg(wo), kv3(KF(1.0), KF(1.0), KF(1.0)), prob, KB_TRANSMIT + KB_DELTA);
}

/* Factor on f_yarn (eval) and on pdf_yarn for the non-delta part. */
KNIT_FN float bsdf_delta_scale(float p_delta) { return KF(1.0) - k_clampf(p_delta, KF(0.0), KF(1.0)); }

#endif /* KNIT_KERNEL_BSDF_DELTA_H */
