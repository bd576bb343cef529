#include <cmath>

#include "render/fresnel.h"
#include "render/materials.h"

namespace knit::render {

bool SmoothDielectricMaterial::sample(const SurfaceInteraction&, Vec3 wo, float uc, Vec2, BsdfSample& s) const {
  const float cos_o = wo.z;
  if (cos_o == 0) return false;
  const float f = fresnel_dielectric(cos_o, eta_);
  if (uc < f) {
    s.wi = {-wo.x, -wo.y, wo.z};
    s.weight = Rgb(1.0f);  // F / P(reflect) with P(reflect) = F
    s.pdf = f;
    s.flags = kReflection | kSpecular;
    s.eta = 1;
    return true;
  }
  // eta_rel = IOR of the far side / IOR of wo's side.
  const bool entering = cos_o > 0;
  const float eta_rel = entering ? eta_ : 1.0f / eta_;
  Vec3 wi;
  if (!refract(wo, Vec3(0, 0, entering ? 1.0f : -1.0f), eta_rel, wi)) return false;  // TIR has f = 1
  s.wi = wi;
  // (1 - F) / P(refract) = 1; radiance is scaled by 1 / eta_rel^2 across the interface.
  s.weight = tint_ / (eta_rel * eta_rel);
  s.pdf = 1.0f - f;
  s.flags = kTransmission | kSpecular;
  s.eta = eta_rel;
  return true;
}

}  // namespace knit::render

namespace knit::render {

namespace {

// The pieces of a rough dielectric's lobes at (wo, wi) (local frame, the
// normal outside; eta = IOR inside / IOR outside), for eval and pdf alike.
struct RoughConfig {
  bool valid = false, reflect = false;
  Vec3 h;            // the microfacet normal, h.z > 0
  float etap = 1;    // IOR of wi's side / IOR of wo's side (1 for reflection)
  float fresnel = 0; // F at wo.h
};

RoughConfig rough_config(Vec3 wo, Vec3 wi, float eta) {
  RoughConfig c;
  const float co = wo.z, ci = wi.z;
  if (co == 0 || ci == 0) return c;
  c.reflect = co * ci > 0;
  c.etap = c.reflect ? 1.0f : (co > 0 ? eta : 1.0f / eta);
  // The generalised half vector (Walter et al. 2007, Eq. 16): wo + etap wi
  // is along -h for a refraction and along h for a reflection.
  const Vec3 hs = wo + wi * c.etap;
  const float l2 = length2(hs);
  if (!(l2 > 0) || !std::isfinite(l2)) return c;
  c.h = hs / std::sqrt(l2);
  if (c.h.z < 0) c.h = -c.h;
  // Both directions on the sides of the microfacet their hemispheres put them.
  if (dot(c.h, wo) * co <= 0 || dot(c.h, wi) * ci <= 0) return c;
  c.fresnel = fresnel_dielectric(dot(wo, c.h), eta);
  c.valid = true;
  return c;
}

knit::k::kvec3 kv(Vec3 v) { return knit::k::kv3(v.x, v.y, v.z); }

// GGX D(h), the visible-normal density D_wo(h) seen from wo's side, and
// height-correlated G2(wo, wi), for isotropic alpha.
float ggx_d(float alpha, Vec3 h) { return knit::k::mf_ggx_d(alpha, alpha, kv(h)); }
float ggx_g1(float alpha, Vec3 w) { return knit::k::mf_ggx_g1(alpha, alpha, kv(w)); }
float ggx_g2(float alpha, Vec3 wo, Vec3 wi) { return knit::k::mf_ggx_g2(alpha, alpha, kv(wo), kv(wi)); }
float ggx_visible(float alpha, Vec3 wo, Vec3 h) {
  return ggx_g1(alpha, wo) * ggx_d(alpha, h) * std::fabs(dot(wo, h)) / std::fabs(wo.z);
}

// d h / d wi of a refraction, |wi.h| / (wi.h + wo.h / etap)^2.
float refraction_jacobian(Vec3 wo, Vec3 wi, Vec3 h, float etap) {
  const float den = dot(wi, h) + dot(wo, h) / etap;
  return std::fabs(dot(wi, h)) / (den * den);
}

}  // namespace

RoughDielectricMaterial::RoughDielectricMaterial(const DielectricDesc& d)
    : eta_(d.eta), alpha_(d.roughness * d.roughness), tint_(d.tint) {}

Rgb RoughDielectricMaterial::eval(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const {
  const RoughConfig c = rough_config(wo, wi, eta_);
  if (!c.valid) return {};
  const float dg = ggx_d(alpha_, c.h) * ggx_g2(alpha_, wo, wi);
  const float co = std::fabs(wo.z), ci = std::fabs(wi.z);
  if (c.reflect) return Rgb(c.fresnel * dg / (4.0f * co * ci));
  // Walter et al. Eq. 21 for radiance: T D G2 |wi.h| |wo.h| / (|wi.z| |wo.z|
  // (wi.h + wo.h / etap)^2) / etap^2.
  const float den = dot(wi, c.h) + dot(wo, c.h) / c.etap;
  const float f = (1.0f - c.fresnel) * dg * std::fabs(dot(wi, c.h) * dot(wo, c.h)) /
                  (co * ci * den * den * c.etap * c.etap);
  return std::isfinite(f) ? tint_ * f : Rgb();
}

float RoughDielectricMaterial::pdf(const SurfaceInteraction&, Vec3 wo, Vec3 wi) const {
  const RoughConfig c = rough_config(wo, wi, eta_);
  if (!c.valid) return 0;
  const float visible = ggx_visible(alpha_, wo, c.h);
  const float p = c.reflect ? visible * c.fresnel / (4.0f * std::fabs(dot(wo, c.h)))
                            : visible * (1.0f - c.fresnel) * refraction_jacobian(wo, wi, c.h, c.etap);
  return std::isfinite(p) ? p : 0.0f;
}

bool RoughDielectricMaterial::sample(const SurfaceInteraction& si, Vec3 wo, float uc, Vec2 u, BsdfSample& s) const {
  const float co = wo.z;
  if (co == 0) return false;
  // A visible normal of wo's side (the kernel samples from above: wo is
  // mirrored below the surface, and h with it back into h.z > 0).
  const float side = co > 0 ? 1.0f : -1.0f;
  const knit::k::kvec3 hk = knit::k::mf_ggx_sample_vndf(alpha_, alpha_, kv(wo * side), u.x, u.y);
  const Vec3 h(hk.x, hk.y, hk.z);
  const float oh = dot(wo, h);
  if (!(oh * side > 0)) return false;
  const float fr = fresnel_dielectric(oh, eta_);
  const float g1 = ggx_g1(alpha_, wo);
  if (!(g1 > 0)) return false;
  if (uc < fr) {
    s.wi = h * (2.0f * oh) - wo;
    if (!(s.wi.z * co > 0)) return false;  // reflected below the macro surface: shadowed
    s.flags = kReflection | kGlossy;
    s.eta = 1;
    s.weight = Rgb(ggx_g2(alpha_, wo, s.wi) / g1);  // f |wi.z| / pdf, the rest cancels
  } else {
    const float etap = co > 0 ? eta_ : 1.0f / eta_;
    Vec3 wi;
    if (!refract(wo, h * side, etap, wi)) return false;  // total internal reflection: fr was 1
    if (!(wi.z * co < 0)) return false;
    s.wi = wi;
    s.flags = kTransmission | kGlossy;
    s.eta = etap;
    s.weight = tint_ * (ggx_g2(alpha_, wo, wi) / (g1 * etap * etap));
  }
  s.pdf = pdf(si, wo, s.wi);
  return s.pdf > 0 && s.weight.is_finite();
}

}  // namespace knit::render
