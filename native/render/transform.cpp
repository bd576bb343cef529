#include "render/transform.h"

#include <cmath>

namespace knit::render {

static constexpr double kPiD = 3.14159265358979323846;

Transform Transform::translate(Vec3 t) {
  return Transform({1, 0, 0, t.x, 0, 1, 0, t.y, 0, 0, 1, t.z, 0, 0, 0, 1});
}

Transform Transform::scale(Vec3 s) {
  return Transform({s.x, 0, 0, 0, 0, s.y, 0, 0, 0, 0, s.z, 0, 0, 0, 0, 1});
}

Transform Transform::rotate_x(double deg) {
  const double c = std::cos(deg * kPiD / 180), s = std::sin(deg * kPiD / 180);
  return Transform({1, 0, 0, 0, 0, c, -s, 0, 0, s, c, 0, 0, 0, 0, 1});
}

Transform Transform::rotate_y(double deg) {
  const double c = std::cos(deg * kPiD / 180), s = std::sin(deg * kPiD / 180);
  return Transform({c, 0, s, 0, 0, 1, 0, 0, -s, 0, c, 0, 0, 0, 0, 1});
}

Transform Transform::rotate_z(double deg) {
  const double c = std::cos(deg * kPiD / 180), s = std::sin(deg * kPiD / 180);
  return Transform({c, -s, 0, 0, s, c, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
}

Transform Transform::operator*(const Transform& o) const {
  std::array<double, 16> r{};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += m_[i * 4 + k] * o.m_[k * 4 + j];
      r[i * 4 + j] = s;
    }
  return Transform(r);
}

Vec3 Transform::point(Vec3 p) const {
  const double x = p.x, y = p.y, z = p.z;
  return {static_cast<float>(m_[0] * x + m_[1] * y + m_[2] * z + m_[3]),
          static_cast<float>(m_[4] * x + m_[5] * y + m_[6] * z + m_[7]),
          static_cast<float>(m_[8] * x + m_[9] * y + m_[10] * z + m_[11])};
}

Vec3 Transform::vector(Vec3 v) const {
  const double x = v.x, y = v.y, z = v.z;
  return {static_cast<float>(m_[0] * x + m_[1] * y + m_[2] * z),
          static_cast<float>(m_[4] * x + m_[5] * y + m_[6] * z),
          static_cast<float>(m_[8] * x + m_[9] * y + m_[10] * z)};
}

Vec3 Transform::normal(Vec3 n) const {
  // Inverse transpose of the 3x3 part = cofactor matrix / det; the scale
  // does not matter for a normal, so use the cofactors and keep the sign.
  const auto& a = m_;
  const double c00 = a[5] * a[10] - a[6] * a[9], c01 = a[6] * a[8] - a[4] * a[10],
               c02 = a[4] * a[9] - a[5] * a[8];
  const double c10 = a[2] * a[9] - a[1] * a[10], c11 = a[0] * a[10] - a[2] * a[8],
               c12 = a[1] * a[8] - a[0] * a[9];
  const double c20 = a[1] * a[6] - a[2] * a[5], c21 = a[2] * a[4] - a[0] * a[6],
               c22 = a[0] * a[5] - a[1] * a[4];
  const double det = determinant3();
  const double s = det < 0 ? -1.0 : 1.0;
  const double x = n.x, y = n.y, z = n.z;
  return {static_cast<float>(s * (c00 * x + c01 * y + c02 * z)),
          static_cast<float>(s * (c10 * x + c11 * y + c12 * z)),
          static_cast<float>(s * (c20 * x + c21 * y + c22 * z))};
}

double Transform::determinant3() const {
  const auto& a = m_;
  return a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) +
         a[2] * (a[4] * a[9] - a[5] * a[8]);
}

bool Transform::is_affine() const { return m_[12] == 0 && m_[13] == 0 && m_[14] == 0 && m_[15] == 1; }

bool Transform::is_identity() const {
  for (int i = 0; i < 16; ++i)
    if (m_[i] != ((i % 5) == 0 ? 1.0 : 0.0)) return false;
  return true;
}

}  // namespace knit::render
