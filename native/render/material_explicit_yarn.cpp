#include "render/material_explicit_yarn.h"

#include <algorithm>

namespace knit::render {

ExplicitYarnMaterial::ExplicitYarnMaterial(std::shared_ptr<const knit::KnitMaterial> model)
    : model_(std::move(model)) {}

PassThrough ExplicitYarnMaterial::resolve(SurfaceInteraction& si, const RayDifferential& ray, Sampler&) const {
  PassThrough pt;
  if (dot(ray.d, si.ng) > 0) {
    pt.pass = true;  // leaving a tube it was transmitted into
    return pt;
  }
  const knit::KnitMaterialParams& mp = model_->params();
  const knit::YarnBsdfParams& bp = mp.bsdf;
  knit::KnitShade sh;
  sh.pass_through = false;
  const int c = std::clamp(si.yarn.color, 0, bp.num_colors() - 1);
  sh.point.color = c;
  sh.point.layers = 1;
  sh.point.shadow = 1;
  sh.kd_r = bp.reflect_colors[size_t(c)];
  sh.kd_t = bp.transmit_colors[size_t(c)];
  sh.spec_r = knit::k::bsdf_mf_make(bp.roughness_x, bp.roughness_y, bp.eta);
  sh.spec_t = knit::k::bsdf_mf_make(bp.trans_roughness_x, bp.trans_roughness_y, bp.eta);
  if (mp.ply_detail) {
    // Ply and fibre detail at the hit's azimuth and ply coordinate (ply_arc), in the
    // tube's frame (x along the yarn, z the outward normal).
    const knit::k::KPlyShade ps = model_->ply().lookup(si.yarn.phi, si.yarn.arc);
    sh.point.shadow = ps.shadow;
    const Frame f = si.shading;
    Frame p;
    p.t = f.to_world(from_kvec(ps.t));
    p.b = f.to_world(from_kvec(ps.b));
    p.n = f.to_world(from_kvec(ps.n));
    si.shading = Frame::from_normal_tangent(normalize(p.n), p.t);
  }
  si.yarn.active = true;
  si.yarn.bsdf = model_->kernel_bsdf(sh);
  return pt;
}

Rgb ExplicitYarnMaterial::transmittance(const SurfaceInteraction& si, Vec3 w, Sampler&) const {
  return dot(w, si.ng) > 0 ? Rgb(1.0f) : Rgb(0.0f);
}

}  // namespace knit::render
