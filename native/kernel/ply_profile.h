/* Knitshade kernel: ply and fiber detail as 1D profiles wrapped around the
 * yarn (paper Sec. 3.2 and 5, the G_{p,f} of Eq. 1; after Montazeri et al.
 * 2020, the ply-based model: plies are twisted round tubes, fibres twisted
 * round tubes inside each ply).
 *
 * Geometry (cross-section of the yarn, lengths in yarn radii R):
 *   N plies of radius a sit on a ring of radius c = 1 - a (touching the yarn
 *   envelope), ply k at azimuth 2 pi k / N + w_p s, where s is the arc length
 *   along the yarn and w_p = tan(ply_twist) / R the ply phase rate (ply_twist
 *   is the helix angle of the plies at the yarn surface). Each ply holds
 *   fiber_count fibres packed at KPLY_FIBER_PACKING; the outer ring of a ply
 *   holds n_f fibres of radius a_f (in ply radii) on a ring of radius
 *   c_f = 1 - a_f, turning around the ply axis at rate w_f (from fiber_twist).
 * Profiles: the ply profile is a function of the ply phase psi = phi - w_p s
 *   (phi the azimuth around the yarn) over one period 2 pi / N; the fibre
 *   profile is a function of the fibre phase chi = theta - w_f s over one
 *   period 2 pi / n_f, theta being the hit point's angle around its ply's
 *   axis (from the ply profile). Per period, for the hit point seen straight
 *   down the yarn's radius:
 *   - shadow: 2D ambient visibility of the hit point in the cross-section,
 *     i.e. the cosine-weighted fraction of the half-plane above its normal
 *     not blocked by the two neighbouring plies (fibres): 1 on a crest,
 *     falling to 0 at the bottom of the groove between touching plies.
 *     Closed form: a disc of radius a at distance d blocks the directions
 *     within asin(a/d) of its centre, the blocked cosine weight of [lo, hi]
 *     is (sin hi - sin lo)/2, and the two neighbours' intervals are united.
 *     Plies further away are ignored: hidden behind the neighbours when the
 *     plies touch or overlap; seen through the gaps when they do not (then G
 *     is up to ~0.06 too high for plies 10% thinner than packed).
 *   - delta: the tilt of the ply's surface normal away from the yarn's radial
 *     direction (towards +y for delta > 0).
 *   G_{p,f} = G_ply(psi) G_fibre(chi).
 * Shading frame (ply_shade_*): the normal is tilted by delta about the yarn
 * axis, so highlights follow the ply crests; the tangent is turned in the
 * tangent plane by the angle of the fibres at the hit point,
 * atan(rho tan(ply_twist)) + fiber_twist (rho the hit point's radius; ply
 * helix plus fibre helix on the ply; opposite signs, as in balanced yarns,
 * bring the surface fibres back towards the yarn axis). Returned in the
 * yarn's local frame (x tangent, y = z cross x, z normal); use ply_to_local
 * to express directions in it before calling the BSDF.
 * Azimuth phi: measured from a reference that varies smoothly along the yarn
 * (any one: the offset only shifts the plies), increasing towards +y of the
 * local frame at the point. s: arc length along the yarn, in the same length
 * unit as yarn_radius (pattern units).
 *
 * Two equal ways to evaluate (tests assert they agree to the table's
 * interpolation error):
 *   ply_shade_procedural(p, phi, s)          everything in closed form (OSL)
 *   ply_shade_lookup(table, p, phi, s)       linear interpolation in a table of
 *       KPLY_TABLE_SIZE floats that the host fills once per material with
 *       table[i] = ply_table_value(p, i): KPLY_TABLE_N samples each of the ply
 *       shadow, the ply normal tilt and the fibre shadow over one period
 *       (3 x 256 floats = 3072 bytes).
 *
 * Parameters (KPlyParams, built by ply_params_make from):
 *   name         type   default  meaning
 *   ply_count    int    3        plies per yarn, 1..16 (1: no ply grooves)
 *   ply_radius   float  0.4641   ply radius / yarn radius, (0, 1); the default
 *                                packs 3 touching plies: sin(pi/3)/(1+sin(pi/3))
 *   ply_twist    float  0.5      helix angle of the plies at the yarn surface,
 *                                radians, |.| < 1.4; sign = handedness (Z > 0)
 *   fiber_count  int    40       fibres per ply, 0..10000 (< 4: no fibre shadowing)
 *   fiber_twist  float  -0.35    helix angle of the fibres on the ply surface
 *                                relative to the ply axis, radians, |.| < 1.4
 *   yarn_radius  float  0.75     R, pattern units (the stitch tube radius r)
 */
#ifndef KNIT_KERNEL_PLY_PROFILE_H
#define KNIT_KERNEL_PLY_PROFILE_H

#define KPLY_TABLE_N 256
#define KPLY_TABLE_SIZE 768 /* 3 * KPLY_TABLE_N floats */
#define KPLY_FIBER_PACKING KF(0.7)
#define KPLY_MAX_RING 256
#define KPLY_MAX_TWIST KF(1.4)

KNIT_STRUCT(KPlyParams)
  int ply_count;      /* N (1: the yarn is a single ply) */
  float ply_radius;   /* a, in yarn radii */
  float ply_center;   /* c = 1 - a, in yarn radii (0 when N = 1) */
  float ply_twist;    /* helix angle at the yarn surface, radians */
  float ply_rate;     /* w_p = tan(ply_twist) / R, radians of psi per unit s */
  int fiber_ring;     /* n_f, fibres on a ply's outer ring (0: no fibre profile) */
  float fiber_radius; /* a_f, in ply radii */
  float fiber_center; /* c_f = 1 - a_f, in ply radii */
  float fiber_twist;  /* fibre helix angle on the ply surface, radians */
  float fiber_rate;   /* w_f, radians of chi per unit s (yarn arc length) */
  float yarn_radius;  /* R */
KNIT_STRUCT_END(KPlyParams)

KNIT_STRUCT(KPlyRing)
  float shadow; /* cosine-weighted visibility in the cross-section, [0, 1] */
  float delta;  /* normal tilt from the radial direction, radians */
KNIT_STRUCT_END(KPlyRing)

KNIT_STRUCT(KPlyShade)
  kvec3 n;            /* perturbed normal, in the yarn's local frame */
  kvec3 t;            /* perturbed tangent (fibre direction), orthogonal to n */
  kvec3 b;            /* n cross t */
  float shadow;       /* G_{p,f} = ply_shadow * fiber_shadow */
  float ply_shadow;   /* G_p */
  float fiber_shadow; /* G_f */
KNIT_STRUCT_END(KPlyShade)

/* x reduced to [-period/2, period/2). */
KNIT_FN float kply_reduce(float x, float period) {
  return x - period * k_floor(x / period + KF(0.5));
}

KNIT_FN KPlyParams ply_params_make(int ply_count, float ply_radius, float ply_twist, int fiber_count,
                                   float fiber_twist, float yarn_radius) {
  KPlyParams p;
  float r = k_fmax(yarn_radius, KF(1.0e-6));
  float ap = k_clampf(ply_twist, -KPLY_MAX_TWIST, KPLY_MAX_TWIST);
  float af = k_clampf(fiber_twist, -KPLY_MAX_TWIST, KPLY_MAX_TWIST);
  float a = k_clampf(ply_radius, KF(0.01), KF(1.0));
  float ring, cos_center;
  p.ply_count = k_maxi(ply_count, 1);
  if (p.ply_count == 1 || a >= KF(0.999)) {
    p.ply_count = 1;
    a = KF(1.0);
  }
  p.ply_radius = a;
  p.ply_center = KF(1.0) - a;
  p.ply_twist = ap;
  p.ply_rate = p.ply_count > 1 ? k_tan(ap) / r : KF(0.0);
  p.yarn_radius = r;
  p.fiber_twist = af;
  p.fiber_ring = 0;
  p.fiber_radius = KF(1.0);
  p.fiber_center = KF(0.0);
  p.fiber_rate = KF(0.0);
  if (fiber_count >= 3) {
    p.fiber_radius = k_sqrt(KPLY_FIBER_PACKING / KFLT(fiber_count));
    p.fiber_center = KF(1.0) - p.fiber_radius;
    if (p.fiber_radius < p.fiber_center) {
      ring = k_floor(K_PI / k_asin(p.fiber_radius / p.fiber_center) + KF(1.0e-4));
      p.fiber_ring = ring >= KF(3.0) ? k_mini(KINT(ring), KPLY_MAX_RING) : 0;
    }
  }
  if (p.fiber_ring > 0) {
    /* Ply centre line helix angle atan(c tan(ply_twist)); yarn arc length s
     * runs along the ply as s / cos(that angle). */
    cos_center = KF(1.0) / k_sqrt(KF(1.0) + k_sqr(p.ply_center * k_tan(ap)));
    p.fiber_rate = k_tan(af) / (p.fiber_center * a * r * cos_center);
  }
  return p;
}

KNIT_STRUCT(KPlyInterval)
  float lo; /* angles relative to the normal, clipped to [-pi/2, pi/2]; empty when hi <= lo */
  float hi;
KNIT_STRUCT_END(KPlyInterval)

/* Directions (angles relative to the normal direction `theta`) from the
 * point (px, py) that hit the disc of radius a centred at (cx, cy), clipped
 * to the half-plane around the normal. */
KNIT_FN KPlyInterval kply_disc_interval(float px, float py, float theta, float cx, float cy, float a) {
  KPlyInterval r;
  float vx = cx - px;
  float vy = cy - py;
  float d = k_sqrt(vx * vx + vy * vy);
  float g = d > a ? k_asin(a / d) : K_PI_2;
  float rel = kply_reduce(k_atan2(vy, vx) - theta, K_2PI);
  r.lo = k_fmax(rel - g, -K_PI_2);
  r.hi = k_fmin(rel + g, K_PI_2);
  return r;
}

/* Cosine weight (of the half-plane's total 2, so in [0, 1]) of [lo, hi]. */
KNIT_FN float kply_cos_weight(float lo, float hi) {
  return hi > lo ? KF(0.5) * (k_sin(hi) - k_sin(lo)) : KF(0.0);
}

/* Profile of a ring of n discs of radius a centred on a circle of radius c
 * (the discs' outer envelope has radius c + a = 1), at the phase psi (any
 * value; reduced to the nearest disc). */
KNIT_FN KPlyRing ply_ring_eval(int n, float c, float a, float psi_in) {
  KPlyRing r;
  KPlyInterval i1, i2;
  float period, psi, sp, lim, rho, px, py, nx, ny, theta, occ;
  if (n < 2 || c <= KF(0.0)) {
    r.shadow = KF(1.0);
    r.delta = KF(0.0);
    return r;
  }
  period = K_2PI / KFLT(n);
  /* Reduce to the nearest disc; +-period/2 itself is kept on its side. */
  psi = k_fabs(psi_in) <= KF(0.5) * period ? psi_in : kply_reduce(psi_in, period);
  sp = k_sin(psi);
  /* Where the discs leave gaps, the radial line misses the disc: use the
   * disc's tangent point (its flank) instead. */
  lim = a / c;
  if (lim < KF(1.0) && k_fabs(sp) > lim) {
    psi = k_signf(psi) * k_asin(lim);
    sp = k_sin(psi);
  }
  rho = c * k_cos(psi) + k_safe_sqrt(a * a - c * c * sp * sp);
  px = rho * k_cos(psi);
  py = rho * sp;
  nx = (px - c) / a;
  ny = py / a;
  theta = k_atan2(ny, nx);
  /* The two neighbours' shadows on the half-plane can overlap near the
   * horizon (the normal tilts strongly in a groove): weigh their union. */
  i1 = kply_disc_interval(px, py, theta, c * k_cos(period), c * k_sin(period), a);
  occ = kply_cos_weight(i1.lo, i1.hi);
  if (n > 2) {
    i2 = kply_disc_interval(px, py, theta, c * k_cos(period), -c * k_sin(period), a);
    occ = occ + kply_cos_weight(i2.lo, i2.hi) -
          kply_cos_weight(k_fmax(i1.lo, i2.lo), k_fmin(i1.hi, i2.hi));
  }
  r.shadow = k_clampf(KF(1.0) - occ, KF(0.0), KF(1.0));
  r.delta = kply_reduce(theta - psi, K_2PI);
  return r;
}

/* The ply phase psi of (phi, s), reduced to [-pi/N, pi/N). */
KNIT_FN float ply_phase(KNIT_IN(KPlyParams) p, float phi, float s) {
  return kply_reduce(phi - p.ply_rate * s, K_2PI / KFLT(k_maxi(p.ply_count, 1)));
}

/* The fibre phase chi, given the ply phase psi and the ply normal tilt delta
 * (theta = psi + delta is the angle around the ply axis). */
KNIT_FN float ply_fiber_phase(KNIT_IN(KPlyParams) p, float psi, float delta, float s) {
  return kply_reduce(psi + delta - p.fiber_rate * s, K_2PI / KFLT(k_maxi(p.fiber_ring, 1)));
}

/* Frame and shadow from the profile values at the point. */
KNIT_FN KPlyShade ply_shade_assemble(KNIT_IN(KPlyParams) p, float psi, float ply_shadow, float delta,
                                     float fiber_shadow) {
  KPlyShade o;
  float rho = p.ply_center * k_cos(psi) + p.ply_radius * k_cos(delta);
  float gt = k_atan(rho * k_tan(p.ply_twist) * (p.ply_count > 1 ? KF(1.0) : KF(0.0))) + p.fiber_twist;
  kvec3 n = kv3(KF(0.0), k_sin(delta), k_cos(delta));
  kvec3 t0 = kv3(k_cos(gt), k_sin(gt), KF(0.0));
  kvec3 t = kv3_normalize(kv3_sub(t0, kv3_scale(n, kv3_dot(t0, n))));
  o.n = n;
  o.t = t;
  o.b = kv3_cross(n, t);
  o.ply_shadow = ply_shadow;
  o.fiber_shadow = fiber_shadow;
  o.shadow = ply_shadow * fiber_shadow;
  return o;
}

KNIT_FN KPlyShade ply_shade_procedural(KNIT_IN(KPlyParams) p, float phi, float s) {
  float psi = ply_phase(p, phi, s);
  KPlyRing pr = ply_ring_eval(p.ply_count, p.ply_center, p.ply_radius, psi);
  KPlyRing fr = ply_ring_eval(p.fiber_ring, p.fiber_center, p.fiber_radius,
                              ply_fiber_phase(p, psi, pr.delta, s));
  return ply_shade_assemble(p, psi, pr.shadow, pr.delta, fr.shadow);
}

/* Table abscissae. Sample j of a channel sits at the phase
 *   x_j = (period / 2) sin(pi/2 t_j),  t_j = -1 + 2 j / (N - 1),
 * dense towards the ends of the period: there (the groove) the profiles
 * behave like sqrt(period/2 - |x|), which this warp turns into a function
 * linear in t, so linear interpolation in t stays accurate. */
KNIT_FN float ply_table_phase(int j, float period) {
  float t = KF(-1.0) + KF(2.0) * KFLT(j) / KFLT(KPLY_TABLE_N - 1);
  return KF(0.5) * period * k_sin(K_PI_2 * t);
}

/* Entry i (0 <= i < KPLY_TABLE_SIZE) of the table: channel i / KPLY_TABLE_N
 * (0 ply shadow, 1 ply normal tilt, 2 fibre shadow) at sample j = i mod N. */
KNIT_FN float ply_table_value(KNIT_IN(KPlyParams) p, int i) {
  int ch = i / KPLY_TABLE_N;
  int j = i - ch * KPLY_TABLE_N;
  KPlyRing r;
  if (ch < 2) {
    r = ply_ring_eval(p.ply_count, p.ply_center, p.ply_radius,
                      ply_table_phase(j, K_2PI / KFLT(k_maxi(p.ply_count, 1))));
    return ch == 0 ? r.shadow : r.delta;
  }
  r = ply_ring_eval(p.fiber_ring, p.fiber_center, p.fiber_radius,
                    ply_table_phase(j, K_2PI / KFLT(k_maxi(p.fiber_ring, 1))));
  return r.shadow;
}

/* Linear interpolation in channel `ch` at phase x (already reduced to
 * [-period/2, period/2]) of a profile of the given period. */
KNIT_FN float ply_table_interp(KNIT_ARRAY(float, table), int ch, float x, float period) {
  float t = k_safe_asin(KF(2.0) * x / period) / K_PI_2;
  float f = k_clampf(KF(0.5) * (t + KF(1.0)), KF(0.0), KF(1.0)) * KFLT(KPLY_TABLE_N - 1);
  int j = k_mini(KINT(f), KPLY_TABLE_N - 2);
  float w = f - KFLT(j);
  int base = ch * KPLY_TABLE_N + j;
  return table[base] + (table[base + 1] - table[base]) * w;
}

KNIT_FN KPlyShade ply_shade_lookup(KNIT_ARRAY(float, table), KNIT_IN(KPlyParams) p, float phi, float s) {
  float psi = ply_phase(p, phi, s);
  float period = K_2PI / KFLT(k_maxi(p.ply_count, 1));
  float gp = ply_table_interp(table, 0, psi, period);
  float delta = ply_table_interp(table, 1, psi, period);
  float gf = KF(1.0);
  if (p.fiber_ring >= 3)
    gf = ply_table_interp(table, 2, ply_fiber_phase(p, psi, delta, s), K_2PI / KFLT(p.fiber_ring));
  return ply_shade_assemble(p, psi, gp, delta, gf);
}

/* v (in the yarn's local frame) expressed in the perturbed frame (t, b, n). */
KNIT_FN kvec3 ply_to_local(KNIT_IN(KPlyShade) f, kvec3 v) { return kv3_to_local(v, f.t, f.b, f.n); }

#endif /* KNIT_KERNEL_PLY_PROFILE_H */
