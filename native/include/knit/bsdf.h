// The near-field yarn BSDF (paper Eq. 1) for C++ hosts: a validated parameter
// struct and a small class around the shared kernel (native/kernel/yarn_bsdf.h
// and the lobe headers bsdf_*.h). docs/bsdf.md describes the model.
//
// Frame: local shading frame of the yarn surface, z = normal, x = yarn
// tangent, y = z cross x. wo points to the viewer, wi to the light; both unit,
// pointing away from the surface. wo.z * wi.z > 0 is reflection, < 0
// transmission. eval() returns f(wo, wi) * |wi.z| (cosine included);
// sample().weight = eval / pdf.
//
// Every method takes single directions; a batched numpy loop over them is the
// binding's job. Invalid input (parameters, non-unit or non-finite directions,
// colour indices out of range) throws std::invalid_argument naming the field
// and the value.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "knit/kernel.h"

namespace knit {

using Vec3 = k::kvec3;  // the kernel's vector type (host_c.h)

struct Rgb {
  float r = 0.8f, g = 0.8f, b = 0.8f;
};

// Bits of BsdfSample::flags (the kernel's KB_* values).
enum BsdfFlag : int { kBsdfReflect = 1, kBsdfTransmit = 2, kBsdfDelta = 4 };

// The four lobes of Eq. 1 (the kernel's YB_LOBE_* indices).
enum class Lobe : int {
  SpecularReflection = 0,    // f_x^S, rough dielectric reflection
  SpecularTransmission = 1,  // tau (1 - B) f_y^S, thin-slab rough dielectric transmission
  BodyReflection = 2,        // r B G (1 - F_o)(1 - F_i) LS k_x^B
  BodyTransmission = 3,      // tau (1 - r) B G (1 - F_o)(1 - F_i) k_y^B / pi
};

// Material-level parameters of the yarn BSDF. Defaults: a light wool-ish yarn.
struct YarnBsdfParams {
  static constexpr int kMaxColors = 256;  // as Pattern::kMaxColors

  float roughness_x = 0.15f;        // GGX alpha of f_R along the yarn tangent, (0, 1]
  float roughness_y = 0.45f;        // GGX alpha of f_R across the yarn, (0, 1]
  float trans_roughness_x = 0.30f;  // GGX alpha of f_T along the yarn, (0, 1]
  float trans_roughness_y = 0.60f;  // GGX alpha of f_T across the yarn, (0, 1]
  float eta = 1.55f;                // index of refraction of the yarn, [1, 3]
  float body_energy = 0.7f;         // B: portion of entering light scattered many times, [0, 1]
  float body_reflect = 0.6f;        // r: reflected portion of the body energy, [0, 1]
  float optical_depth = 1.0f;       // D: optical depth of one yarn through its centre, [0, 50]
  // Colours per colour index (the pattern's colour matrix): k_x^B and k_y^B,
  // each channel in [0, 1]; same count, 1..kMaxColors.
  std::vector<Rgb> reflect_colors{Rgb{}};
  std::vector<Rgb> transmit_colors{Rgb{}};

  int num_colors() const { return static_cast<int>(reflect_colors.size()); }
  // Throws std::invalid_argument "YarnBsdfParams.<field> = <value>: <rule>".
  void validate() const;
  std::string to_string() const;
};

// What the geometry and the ply profile report at a hit point.
struct BsdfPoint {
  int color = 0;         // colour index, [0, num_colors)
  int layers = 1;        // yarns crossed by the transmitted path, >= 1 (more than 4 count as 4)
  float shadow = 1.0f;   // G_{p,f} from the ply profile, [0, 1]
  float p_delta = 0.0f;  // probability of passing through a gap, [0, 1]
};

struct BsdfSample {
  Vec3 wi{0.f, 0.f, 0.f};
  Rgb weight{0.f, 0.f, 0.f};  // eval / pdf (1 for a pass-through event)
  float pdf = 0.f;            // solid-angle pdf; for kBsdfDelta the discrete probability
  int flags = 0;              // kBsdfReflect / kBsdfTransmit (+ kBsdfDelta); 0 = failed
  bool valid() const { return flags != 0 && pdf > 0.f; }
};

class YarnBsdf {
 public:
  YarnBsdf();                                 // default parameters
  explicit YarnBsdf(YarnBsdfParams params);   // validates
  const YarnBsdfParams& params() const { return params_; }

  // The kernel struct for a hit point (validates `pt`); p_delta is not part of it.
  k::KYarnBsdf kernel(const BsdfPoint& pt = {}) const;

  // (1 - p_delta) f(wo, wi) |wi.z|: what light sampling sees.
  Rgb eval(Vec3 wo, Vec3 wi, const BsdfPoint& pt = {}) const;
  // (1 - p_delta) times the mixture pdf of sample() for wi (solid angle).
  float pdf(Vec3 wo, Vec3 wi, const BsdfPoint& pt = {}) const;
  // u[0] chooses pass-through (probability p_delta), u[1] the lobe (then reused),
  // u[2] the direction. Each in [0, 1).
  BsdfSample sample(Vec3 wo, std::array<float, 3> u, const BsdfPoint& pt = {}) const;

  // One lobe's weighted contribution to eval (p_delta not applied).
  Rgb eval_lobe(Lobe lobe, Vec3 wo, Vec3 wi, const BsdfPoint& pt = {}) const;
  // Lobe selection probabilities of sample() at wo, indexed by Lobe.
  std::array<float, 4> lobe_probabilities(Vec3 wo, const BsdfPoint& pt = {}) const;

 private:
  YarnBsdfParams params_;
};

// Throws std::invalid_argument unless v is finite and of unit length (1e-3).
void check_direction(const char* name, Vec3 v);

}  // namespace knit
