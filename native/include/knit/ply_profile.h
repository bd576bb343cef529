// Ply and fiber detail of the yarn (paper Sec. 3.2 and 5): host side of
// native/kernel/ply_profile.h. A PlyProfile is built once per material from
// PlyParams; it holds the kernel parameters and the 1D profile table the
// kernel interpolates (KPLY_TABLE_SIZE floats, table_bytes() bytes).
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include "knit/kernel.h"

namespace knit {

struct PlyParams {
  int ply_count = 3;         // plies per yarn, [1, 16]; 1 = no ply grooves
  float ply_radius = 0.4641016f;  // ply radius / yarn radius, (0, 1); packed_radius(3)
  float ply_twist = 0.5f;    // ply helix angle at the yarn surface, radians, |.| <= 1.4 (sign: Z > 0)
  int fiber_count = 40;      // fibres per ply, [0, 10000]; < 4 gives no fibre profile
  float fiber_twist = -0.35f;  // fibre helix angle on the ply surface, radians, |.| <= 1.4
  float yarn_radius = 0.75f;   // yarn radius in pattern units, (0, 1e3]

  // Radius (in yarn radii) of n equal touching plies inside the yarn:
  // sin(pi/n) / (1 + sin(pi/n)); 1 for n = 1.
  static float packed_radius(int ply_count);
  // Throws std::invalid_argument "PlyParams.<field> = <value>: <rule>".
  void validate() const;
};

class PlyProfile {
 public:
  using Table = std::array<float, KPLY_TABLE_SIZE>;

  PlyProfile();                            // default parameters
  explicit PlyProfile(const PlyParams& p);  // validates, builds the table

  const PlyParams& params() const { return params_; }
  const k::KPlyParams& kernel_params() const { return kparams_; }
  const Table& table() const { return table_; }
  static constexpr std::size_t table_bytes() { return sizeof(float) * KPLY_TABLE_SIZE; }

  // Shadow G_{p,f} and perturbed frame at azimuth phi (radians) and arc
  // length s (pattern units) along the yarn: table lookup / closed form.
  k::KPlyShade lookup(float phi, float s) const;
  k::KPlyShade procedural(float phi, float s) const;

 private:
  PlyParams params_;
  k::KPlyParams kparams_;
  Table table_;
};

}  // namespace knit
