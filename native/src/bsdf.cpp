// Host wrapper of the near-field yarn BSDF (knit/bsdf.h).
#include "knit/bsdf.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace knit {
namespace {

[[noreturn]] void fail(const std::string& field, double value, const char* rule) {
  std::ostringstream os;
  os << field << " = " << value << ": " << rule;
  throw std::invalid_argument(os.str());
}

void check_range(const std::string& field, float v, float lo, float hi, bool open_lo,
                 const char* rule) {
  if (!std::isfinite(v) || (open_lo ? v <= lo : v < lo) || v > hi) fail(field, v, rule);
}

void check_colors(const char* name, const std::vector<Rgb>& colors) {
  for (size_t i = 0; i < colors.size(); ++i) {
    const Rgb& c = colors[i];
    const float ch[3] = {c.r, c.g, c.b};
    const char* cn[3] = {"r", "g", "b"};
    for (int k = 0; k < 3; ++k) {
      std::string field =
          std::string("YarnBsdfParams.") + name + "[" + std::to_string(i) + "]." + cn[k];
      check_range(field, ch[k], 0.f, 1.f, false, "must be finite and in [0, 1]");
    }
  }
}

Vec3 to_kv(const Rgb& c) { return Vec3{c.r, c.g, c.b}; }
Rgb to_rgb(Vec3 v) { return Rgb{v.x, v.y, v.z}; }

}  // namespace

void YarnBsdfParams::validate() const {
  const char* unit = "must be finite and in (0, 1]";
  check_range("YarnBsdfParams.roughness_x", roughness_x, 0.f, 1.f, true, unit);
  check_range("YarnBsdfParams.roughness_y", roughness_y, 0.f, 1.f, true, unit);
  check_range("YarnBsdfParams.trans_roughness_x", trans_roughness_x, 0.f, 1.f, true, unit);
  check_range("YarnBsdfParams.trans_roughness_y", trans_roughness_y, 0.f, 1.f, true, unit);
  check_range("YarnBsdfParams.eta", eta, 1.f, 3.f, false, "must be finite and in [1, 3]");
  check_range("YarnBsdfParams.body_energy", body_energy, 0.f, 1.f, false,
              "must be finite and in [0, 1]");
  check_range("YarnBsdfParams.body_reflect", body_reflect, 0.f, 1.f, false,
              "must be finite and in [0, 1]");
  check_range("YarnBsdfParams.optical_depth", optical_depth, 0.f, 50.f, false,
              "must be finite and in [0, 50]");
  if (reflect_colors.empty() || static_cast<int>(reflect_colors.size()) > kMaxColors)
    fail("YarnBsdfParams.reflect_colors.size()", double(reflect_colors.size()),
         "must be in [1, 256]");
  if (transmit_colors.size() != reflect_colors.size())
    fail("YarnBsdfParams.transmit_colors.size()", double(transmit_colors.size()),
         "must equal reflect_colors.size()");
  check_colors("reflect_colors", reflect_colors);
  check_colors("transmit_colors", transmit_colors);
}

std::string YarnBsdfParams::to_string() const {
  std::ostringstream os;
  os << "YarnBsdfParams(roughness=(" << roughness_x << ", " << roughness_y
     << "), trans_roughness=(" << trans_roughness_x << ", " << trans_roughness_y
     << "), eta=" << eta << ", B=" << body_energy << ", r=" << body_reflect
     << ", D=" << optical_depth << ", colors=" << reflect_colors.size() << ")";
  return os.str();
}

void check_direction(const char* name, Vec3 v) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw std::invalid_argument(std::string(name) + " is not finite");
  double len = std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
  if (std::abs(len - 1.0) > 1e-3) fail(std::string(name) + " length", len, "must be 1 (unit vector)");
}

YarnBsdf::YarnBsdf() : YarnBsdf(YarnBsdfParams{}) {}

YarnBsdf::YarnBsdf(YarnBsdfParams params) : params_(std::move(params)) { params_.validate(); }

k::KYarnBsdf YarnBsdf::kernel(const BsdfPoint& pt) const {
  if (pt.color < 0 || pt.color >= params_.num_colors())
    fail("BsdfPoint.color", pt.color, "must be a colour index in [0, num_colors)");
  if (pt.layers < 1) fail("BsdfPoint.layers", pt.layers, "must be >= 1");
  check_range("BsdfPoint.shadow", pt.shadow, 0.f, 1.f, false, "must be finite and in [0, 1]");
  check_range("BsdfPoint.p_delta", pt.p_delta, 0.f, 1.f, false, "must be finite and in [0, 1]");
  const YarnBsdfParams& p = params_;
  return k::yarn_bsdf_make(k::bsdf_mf_make(p.roughness_x, p.roughness_y, p.eta),
                           k::bsdf_mf_make(p.trans_roughness_x, p.trans_roughness_y, p.eta),
                           to_kv(p.reflect_colors[pt.color]), to_kv(p.transmit_colors[pt.color]),
                           p.body_energy, p.body_reflect, pt.shadow,
                           k::bsdf_att_make(p.optical_depth, pt.layers));
}

Rgb YarnBsdf::eval(Vec3 wo, Vec3 wi, const BsdfPoint& pt) const {
  check_direction("wo", wo);
  check_direction("wi", wi);
  return to_rgb(k::yarn_bsdf_eval_gaps(kernel(pt), pt.p_delta, wo, wi));
}

float YarnBsdf::pdf(Vec3 wo, Vec3 wi, const BsdfPoint& pt) const {
  check_direction("wo", wo);
  check_direction("wi", wi);
  return k::yarn_bsdf_pdf_gaps(kernel(pt), pt.p_delta, wo, wi);
}

BsdfSample YarnBsdf::sample(Vec3 wo, std::array<float, 3> u, const BsdfPoint& pt) const {
  check_direction("wo", wo);
  for (int i = 0; i < 3; ++i)
    if (!(u[i] >= 0.f && u[i] < 1.f)) fail("u[" + std::to_string(i) + "]", u[i], "must be in [0, 1)");
  k::KBsdfSample s = k::yarn_bsdf_sample_gaps(kernel(pt), pt.p_delta, wo, u[0], u[1], u[2]);
  BsdfSample out;
  out.wi = s.wi;
  out.weight = to_rgb(s.weight);
  out.pdf = s.pdf;
  out.flags = s.flags;
  return out;
}

Rgb YarnBsdf::eval_lobe(Lobe lobe, Vec3 wo, Vec3 wi, const BsdfPoint& pt) const {
  check_direction("wo", wo);
  check_direction("wi", wi);
  int l = static_cast<int>(lobe);
  if (l < 0 || l >= YB_NUM_LOBES) fail("lobe", l, "must be a Lobe value");
  return to_rgb(k::yarn_bsdf_lobe_eval(kernel(pt), l, wo, wi));
}

std::array<float, 4> YarnBsdf::lobe_probabilities(Vec3 wo, const BsdfPoint& pt) const {
  check_direction("wo", wo);
  k::KYarnLobeProbs q = k::yarn_bsdf_lobe_probs(kernel(pt), wo);
  return {q.p0, q.p1, q.p2, q.p3};
}

}  // namespace knit
