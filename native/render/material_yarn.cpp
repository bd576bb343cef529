#include "render/material_yarn.h"

#include <cmath>

namespace knit::render {

namespace {
bool usable(Vec3 w) { return is_finite(w) && std::fabs(length2(w) - 1.0f) < 1e-3f; }

// The tabulated BSDF of a class-table footprint: f |wi.z|, and its
// sampling weights' colours (the channel means of the body colours).
knit::k::kvec3 table_eval(const YarnShading& y, Vec3 wi, knit::k::kvec3* total = nullptr) {
  return y.table->eval(y.mix, to_kvec(wi), y.bsdf.kd_r, y.bsdf.kd_t, total);
}
float lum(knit::k::kvec3 c) { return c.x + c.y + c.z; }
}  // namespace

Rgb YarnShadedMaterial::eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi) || wi.z == 0.0f) return {};
  const knit::k::kvec3 f =
      si.yarn.table ? table_eval(si.yarn, wi) : knit::k::yarn_bsdf_eval(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
  const float inv = 1.0f / std::fabs(wi.z);
  return {f.x * inv, f.y * inv, f.z * inv};
}

float YarnShadedMaterial::pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi)) return 0;
  if (si.yarn.table) {
    // The density of sampling wi as a direction that leaves the fabric:
    // sample()'s density times the lit share there.
    knit::k::kvec3 total;
    const knit::k::kvec3 lit = table_eval(si.yarn, wi, &total);
    const float q = lum(total) > 0 ? std::min(1.0f, lum(lit) / lum(total)) : 0.0f;
    return q * si.yarn.table->pdf(si.yarn.mix, to_kvec(wi));
  }
  return knit::k::yarn_bsdf_pdf(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
}

Rgb YarnShadedMaterial::eval_pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi, bool want_pdf,
                                 float& pdf_out) const {
  if (!want_pdf || !si.yarn.table || !si.yarn.active || !usable(wo) || !usable(wi) || wi.z == 0.0f)
    return eval(si, wo, wi);
  knit::k::kvec3 total;
  const knit::k::kvec3 lit = table_eval(si.yarn, wi, &total);
  const float q = lum(total) > 0 ? std::min(1.0f, lum(lit) / lum(total)) : 0.0f;
  pdf_out = q * si.yarn.table->pdf(si.yarn.mix, to_kvec(wi));
  const float inv = 1.0f / std::fabs(wi.z);
  return {lit.x * inv, lit.y * inv, lit.z * inv};
}

bool YarnShadedMaterial::sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const {
  if (!si.yarn.active || !usable(wo)) return false;
  if (si.yarn.table) {
    // A direction from the total (lit and shadowed), then whether it leaves
    // the fabric (the lit share) or meets other yarn of the footprint
    // first: the path then scatters there (Material::bounce_table).
    knit::k::kvec3 wi;
    float pdf = 0, u3 = 0;
    if (!si.yarn.table->sample(si.yarn.mix, uc, u.x, u.y, wi, pdf, &u3) ||
        wi.z == 0.0f)
      return false;
    knit::k::kvec3 total;
    const knit::k::kvec3 lit = table_eval(si.yarn, from_kvec(wi), &total);
    const float q = lum(total) > 0 ? std::min(1.0f, lum(lit) / lum(total)) : 0.0f;
    s.internal = !(u3 < q);
    s.wi = from_kvec(wi);
    // The branch's part over its probability: lit / (pdf q) leaving, the
    // shadowed rest / (pdf (1 - q)) inside (each channel exactly, though q
    // is one number for the three).
    s.pdf = s.internal ? pdf * (1 - q) : pdf * q;
    const knit::k::kvec3 part = s.internal ? knit::k::kv3_sub(total, lit) : lit;
    s.weight = Rgb(std::max(0.0f, part.x) / s.pdf, std::max(0.0f, part.y) / s.pdf, std::max(0.0f, part.z) / s.pdf);
    s.flags = kGlossy | (wi.z * wo.z > 0 ? kReflection : kTransmission);
    s.eta = 1;
    return s.pdf > 0 && s.weight.is_finite();
  }
  const knit::k::KBsdfSample k = knit::k::yarn_bsdf_sample(si.yarn.bsdf, to_kvec(wo), u.x, u.y);
  if (!(k.pdf > 0) || k.flags == 0) return false;
  s.wi = from_kvec(k.wi);
  s.weight = {k.weight.x, k.weight.y, k.weight.z};
  s.pdf = k.pdf;
  s.flags = kGlossy | ((k.flags & KB_REFLECT) ? kReflection : kTransmission);
  s.eta = 1;
  return s.weight.is_finite();
}

}  // namespace knit::render
