#include "render/differentials.h"

#include <cmath>

namespace knit::render {

void differentials_pass_through(const RayDifferential& in, const SurfaceInteraction& si, RayDifferential& out) {
  out.has_differentials = in.has_differentials && si.footprint.valid;
  out.diff_scale = in.diff_scale;
  out.pixel_dx = in.pixel_dx;
  out.pixel_dy = in.pixel_dy;
  out.footprint_memo = in.footprint_memo;
  if (!out.has_differentials) return;
  out.rx_o = si.p + si.footprint.dpdx;
  out.ry_o = si.p + si.footprint.dpdy;
  out.rx_d = in.rx_d;
  out.ry_d = in.ry_d;
}

// With wo = -d, n the shading normal and c = wo.n:
//   reflection  wi = -wo + 2 c n          dwi = -dwo + 2 (dc n + c dn)
//   refraction  wi = -eta wo + mu n,  mu = eta c - |wi.n|, eta = IOR(wo side) / IOR(far side)
//               dwi = -eta dwo + dmu n + mu dn,  dmu = (eta - eta^2 c / |wi.n|) dc
// where dc = dwo.n + wo.dn (derived from the two formulas; cf. Igehy 1999, Sec. 3).
void differentials_specular(const RayDifferential& in, const SurfaceInteraction& si, const BsdfSample& bs,
                            RayDifferential& out) {
  out.has_differentials = in.has_differentials && si.footprint.valid;
  out.diff_scale = in.diff_scale;
  out.pixel_dx = in.pixel_dx;
  out.pixel_dy = in.pixel_dy;
  out.footprint_memo = in.footprint_memo;
  if (!out.has_differentials) return;
  const Footprint& f = si.footprint;
  const Vec3 wo = -in.d;
  const Vec3 wi = out.d;
  Vec3 n = si.shading.n;
  Vec3 dndx = f.dndx, dndy = f.dndy;
  const Vec3 dwodx = -(in.rx_d - in.d), dwody = -(in.ry_d - in.d);
  out.rx_o = si.p + f.dpdx;
  out.ry_o = si.p + f.dpdy;
  if (bs.flags & kReflection) {
    const float c = dot(wo, n);
    const float dcdx = dot(dwodx, n) + dot(wo, dndx);
    const float dcdy = dot(dwody, n) + dot(wo, dndy);
    out.rx_d = wi - dwodx + (dndx * c + n * dcdx) * 2.0f;
    out.ry_d = wi - dwody + (dndy * c + n * dcdy) * 2.0f;
  } else {
    if (dot(wo, n) < 0) {
      n = -n;
      dndx = -dndx;
      dndy = -dndy;
    }
    const float eta = 1.0f / bs.eta;
    const float c = dot(wo, n);
    const float ci = std::fabs(dot(wi, n));
    if (!(ci > 1e-6f)) {
      out.has_differentials = false;
      return;
    }
    const float mu = eta * c - ci;
    const float k = eta - eta * eta * c / ci;
    const float dcdx = dot(dwodx, n) + dot(wo, dndx);
    const float dcdy = dot(dwody, n) + dot(wo, dndy);
    out.rx_d = wi - dwodx * eta + dndx * mu + n * (k * dcdx);
    out.ry_d = wi - dwody * eta + dndy * mu + n * (k * dcdy);
  }
  if (!is_finite(out.rx_d) || !is_finite(out.ry_d) || !is_finite(out.rx_o) || !is_finite(out.ry_o))
    out.has_differentials = false;
}

}  // namespace knit::render
