#include "render/material_yarn.h"

#include <cmath>

namespace knit::render {

namespace {
bool usable(Vec3 w) { return is_finite(w) && std::fabs(length2(w) - 1.0f) < 1e-3f; }

// The tabulated BSDF of a class-table footprint towards wi, from one
// lookup: f |wi.z| of the light that reaches the yarn (lit) and of all of
// it (total), sample()'s density there, and the lit share q of the total
// (one number for the three channels), which leaves the fabric; the rest
// meets other yarn of the footprint first (Material::bounce_table). A
// folded table (TableBsdf::folded) has that rest summed into its values:
// lit and total are the same, q is 1 and every sample leaves.
struct TableAt {
  knit::k::kvec3 lit, total;
  float density = 0, q = 0;
  // The density of sampling wi as a direction that leaves the fabric.
  float leaving_pdf() const { return q * density; }
};
TableAt table_at(const YarnShading& y, Vec3 wi) {
  TableAt t;
  t.lit = y.table->eval(y.mix, to_kvec(wi), y.bsdf.kd_r, y.bsdf.kd_t, &t.total, &t.density);
  const float lt = t.lit.x + t.lit.y + t.lit.z, tt = t.total.x + t.total.y + t.total.z;
  t.q = tt > 0 ? std::min(1.0f, lt / tt) : 0.0f;
  return t;
}
}  // namespace

Rgb YarnShadedMaterial::eval(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi) || wi.z == 0.0f) return {};
  const knit::k::kvec3 f =
      si.yarn.table    ? si.yarn.table->eval(si.yarn.mix, to_kvec(wi), si.yarn.bsdf.kd_r, si.yarn.bsdf.kd_t)
      : si.yarn.cycles ? knit::k::yarn_cycles_eval(si.yarn.cyc, to_kvec(wo), to_kvec(wi))
                       : knit::k::yarn_bsdf_eval(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
  const float inv = 1.0f / std::fabs(wi.z);
  return {f.x * inv, f.y * inv, f.z * inv};
}

float YarnShadedMaterial::pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi) const {
  if (!si.yarn.active || !usable(wo) || !usable(wi)) return 0;
  if (si.yarn.table) return table_at(si.yarn, wi).leaving_pdf();
  if (si.yarn.cycles) return knit::k::yarn_cycles_pdf_smooth(si.yarn.cyc, to_kvec(wo), to_kvec(wi));
  return knit::k::yarn_bsdf_pdf(si.yarn.bsdf, to_kvec(wo), to_kvec(wi));
}

Rgb YarnShadedMaterial::eval_pdf(const SurfaceInteraction& si, Vec3 wo, Vec3 wi, bool want_pdf,
                                 float& pdf_out) const {
  if (!want_pdf || !si.yarn.table || !si.yarn.active || !usable(wo) || !usable(wi) || wi.z == 0.0f)
    return eval(si, wo, wi);
  const TableAt t = table_at(si.yarn, wi);
  pdf_out = t.leaving_pdf();
  const float inv = 1.0f / std::fabs(wi.z);
  return {t.lit.x * inv, t.lit.y * inv, t.lit.z * inv};
}

bool YarnShadedMaterial::sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const {
  if (!si.yarn.active || !usable(wo)) return false;
  if (si.yarn.table) {
    // A direction from the total (lit and shadowed), then whether it leaves
    // the fabric (the lit share) or meets other yarn of the footprint
    // first: the path then scatters there (Material::bounce_table).
    knit::k::kvec3 wi;
    float u3 = 0;
    if (!si.yarn.table->sample(si.yarn.mix, uc, u.x, u.y, wi, nullptr, &u3) || wi.z == 0.0f) return false;
    const TableAt t = table_at(si.yarn, from_kvec(wi));
    s.internal = !(u3 < t.q);
    s.wi = from_kvec(wi);
    // The branch's part over its probability: lit / (pdf q) leaving, the
    // shadowed rest / (pdf (1 - q)) inside (each channel exactly, though q
    // is one number for the three).
    s.pdf = s.internal ? t.density * (1 - t.q) : t.leaving_pdf();
    const knit::k::kvec3 part = s.internal ? knit::k::kv3_sub(t.total, t.lit) : t.lit;
    s.weight = Rgb(std::max(0.0f, part.x) / s.pdf, std::max(0.0f, part.y) / s.pdf, std::max(0.0f, part.z) / s.pdf);
    s.flags = kGlossy | (wi.z * wo.z > 0 ? kReflection : kTransmission);
    s.eta = 1;
    return s.pdf > 0 && s.weight.is_finite();
  }
  // (Cycles' closures: the smooth ones, the transparent one having been the
  // resolve's pass-through)
  const knit::k::KBsdfSample k = si.yarn.cycles
                                     ? knit::k::yarn_cycles_sample_smooth(si.yarn.cyc, to_kvec(wo), u.x, u.y)
                                     : knit::k::yarn_bsdf_sample(si.yarn.bsdf, to_kvec(wo), u.x, u.y);
  if (!(k.pdf > 0) || k.flags == 0) return false;
  s.wi = from_kvec(k.wi);
  s.weight = {k.weight.x, k.weight.y, k.weight.z};
  s.pdf = k.pdf;
  s.flags = kGlossy | ((k.flags & KB_REFLECT) ? kReflection : kTransmission);
  s.eta = 1;
  return s.weight.is_finite();
}

}  // namespace knit::render
