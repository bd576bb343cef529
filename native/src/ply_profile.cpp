// Host side of the ply and fiber profiles (knit/ply_profile.h).
#include "knit/ply_profile.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace knit {
namespace {

[[noreturn]] void fail(const char* field, double value, const char* rule) {
  std::ostringstream os;
  os << "PlyParams." << field << " = " << value << ": " << rule;
  throw std::invalid_argument(os.str());
}

}  // namespace

float PlyParams::packed_radius(int ply_count) {
  if (ply_count <= 1) return 1.f;
  double s = std::sin(3.14159265358979323846 / ply_count);
  return float(s / (1.0 + s));
}

void PlyParams::validate() const {
  if (ply_count < 1 || ply_count > 16) fail("ply_count", ply_count, "must be in [1, 16]");
  if (!std::isfinite(ply_radius) || ply_radius <= 0.f || ply_radius >= 1.f)
    fail("ply_radius", ply_radius, "must be finite and in (0, 1)");
  if (!std::isfinite(ply_twist) || std::abs(ply_twist) > 1.4f)
    fail("ply_twist", ply_twist, "must be finite with |ply_twist| <= 1.4 rad");
  if (fiber_count < 0 || fiber_count > 10000) fail("fiber_count", fiber_count, "must be in [0, 10000]");
  if (!std::isfinite(fiber_twist) || std::abs(fiber_twist) > 1.4f)
    fail("fiber_twist", fiber_twist, "must be finite with |fiber_twist| <= 1.4 rad");
  if (!std::isfinite(yarn_radius) || yarn_radius <= 0.f || yarn_radius > 1e3f)
    fail("yarn_radius", yarn_radius, "must be finite and in (0, 1000]");
}

PlyProfile::PlyProfile() : PlyProfile(PlyParams{}) {}

PlyProfile::PlyProfile(const PlyParams& p) : params_(p) {
  params_.validate();
  kparams_ = k::ply_params_make(p.ply_count, p.ply_radius, p.ply_twist, p.fiber_count,
                                p.fiber_twist, p.yarn_radius);
  for (int i = 0; i < KPLY_TABLE_SIZE; ++i) table_[i] = k::ply_table_value(kparams_, i);
}

k::KPlyShade PlyProfile::lookup(float phi, float s) const {
  return k::ply_shade_lookup(table_.data(), kparams_, phi, s);
}

k::KPlyShade PlyProfile::procedural(float phi, float s) const {
  return k::ply_shade_procedural(kparams_, phi, s);
}

}  // namespace knit
