// Affine object-to-world transforms (4x4, row-major, column vectors: p' = M p).
#pragma once

#include <array>

#include "render/vec.h"

namespace knit::render {

class Transform {
 public:
  Transform() = default;  // identity
  explicit Transform(const std::array<double, 16>& row_major) : m_(row_major) {}

  static Transform translate(Vec3 t);
  static Transform scale(Vec3 s);
  // Rotation by `deg` degrees about the x, y or z axis (right-handed).
  static Transform rotate_x(double deg);
  static Transform rotate_y(double deg);
  static Transform rotate_z(double deg);

  Transform operator*(const Transform& o) const;  // (A * B) p = A (B p)

  Vec3 point(Vec3 p) const;
  Vec3 vector(Vec3 v) const;
  // Transforms a normal by the inverse transpose of the linear part (not normalised).
  Vec3 normal(Vec3 n) const;

  double determinant3() const;  // of the linear 3x3 part
  bool is_affine() const;       // last row is (0, 0, 0, 1)
  bool is_identity() const;
  const std::array<double, 16>& m() const { return m_; }

 private:
  std::array<double, 16> m_{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
};

}  // namespace knit::render
