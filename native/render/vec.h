// Small vector types of the renderer: Vec2, Vec3 (points and directions),
// Rgb (linear radiance / reflectance triples) and Frame (orthonormal basis).
// Host code only: the shared kernel has its own kvec3 (native/kernel/kmath.h).
#pragma once

#include <algorithm>
#include <cmath>

namespace knit::render {

constexpr float kPi = 3.14159265358979323846f;
constexpr float kInvPi = 0.31830988618379067154f;
constexpr float kInv2Pi = 0.15915494309189533577f;
constexpr float kInv4Pi = 0.07957747154594766788f;

inline float radians(float deg) { return deg * (kPi / 180.0f); }

struct Vec2 {
  float x = 0, y = 0;
  constexpr Vec2() = default;
  constexpr Vec2(float x_, float y_) : x(x_), y(y_) {}
};

struct Vec3 {
  float x = 0, y = 0, z = 0;
  constexpr Vec3() = default;
  constexpr Vec3(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}
  float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
};

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator*(float s, Vec3 a) { return a * s; }
inline Vec3 operator/(Vec3 a, float s) { return a * (1.0f / s); }
inline Vec3& operator+=(Vec3& a, Vec3 b) { return a = a + b; }
inline Vec3& operator-=(Vec3& a, Vec3 b) { return a = a - b; }
inline Vec3& operator*=(Vec3& a, float s) { return a = a * s; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float absdot(Vec3 a, Vec3 b) { return std::fabs(dot(a, b)); }
inline Vec3 cross(Vec3 a, Vec3 b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline float length2(Vec3 a) { return dot(a, a); }
inline float length(Vec3 a) { return std::sqrt(dot(a, a)); }
inline Vec3 normalize(Vec3 a) { return a / length(a); }
inline Vec3 vmin(Vec3 a, Vec3 b) { return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)}; }
inline Vec3 vmax(Vec3 a, Vec3 b) { return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)}; }
inline float max_abs_component(Vec3 a) {
  return std::max(std::fabs(a.x), std::max(std::fabs(a.y), std::fabs(a.z)));
}
inline bool is_finite(Vec3 a) { return std::isfinite(a.x) && std::isfinite(a.y) && std::isfinite(a.z); }
// Flips `v` into the hemisphere of `ref`.
inline Vec3 face_forward(Vec3 v, Vec3 ref) { return dot(v, ref) < 0 ? -v : v; }

// Linear RGB triple (radiance, reflectance, throughput).
struct Rgb {
  float r = 0, g = 0, b = 0;
  constexpr Rgb() = default;
  constexpr explicit Rgb(float v) : r(v), g(v), b(v) {}
  constexpr Rgb(float r_, float g_, float b_) : r(r_), g(g_), b(b_) {}
  bool is_black() const { return r == 0 && g == 0 && b == 0; }
  float max() const { return std::max(r, std::max(g, b)); }
  float mean() const { return (r + g + b) * (1.0f / 3.0f); }
  // Rec. 709 / sRGB luminance weights.
  float luminance() const { return 0.2126f * r + 0.7152f * g + 0.0722f * b; }
  bool is_finite() const { return std::isfinite(r) && std::isfinite(g) && std::isfinite(b); }
  bool has_negative() const { return r < 0 || g < 0 || b < 0; }
};

inline Rgb operator+(Rgb a, Rgb b) { return {a.r + b.r, a.g + b.g, a.b + b.b}; }
inline Rgb operator-(Rgb a, Rgb b) { return {a.r - b.r, a.g - b.g, a.b - b.b}; }
inline Rgb operator*(Rgb a, Rgb b) { return {a.r * b.r, a.g * b.g, a.b * b.b}; }
inline Rgb operator*(Rgb a, float s) { return {a.r * s, a.g * s, a.b * s}; }
inline Rgb operator*(float s, Rgb a) { return a * s; }
inline Rgb operator/(Rgb a, float s) { return a * (1.0f / s); }
inline Rgb& operator+=(Rgb& a, Rgb b) { return a = a + b; }
inline Rgb& operator*=(Rgb& a, Rgb b) { return a = a * b; }
inline Rgb& operator*=(Rgb& a, float s) { return a = a * s; }

// Orthonormal basis; local coordinates have z along n ("shading space").
struct Frame {
  Vec3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};

  Vec3 to_local(Vec3 v) const { return {dot(v, t), dot(v, b), dot(v, n)}; }
  Vec3 to_world(Vec3 v) const { return t * v.x + b * v.y + n * v.z; }

  // Any frame around the unit vector n (Duff et al. 2017, "Building an
  // orthonormal basis, revisited"; written from the paper's formulas).
  static Frame from_normal(Vec3 n) {
    const float sign = std::copysign(1.0f, n.z);
    const float a = -1.0f / (sign + n.z);
    const float bb = n.x * n.y * a;
    Frame f;
    f.n = n;
    f.t = {1.0f + sign * n.x * n.x * a, sign * bb, -sign * n.x};
    f.b = {bb, sign + n.y * n.y * a, -n.y};
    return f;
  }

  // Frame with normal n and t as close as possible to `tangent` (Gram-Schmidt);
  // falls back to from_normal when the tangent is (nearly) parallel to n.
  static Frame from_normal_tangent(Vec3 n, Vec3 tangent) {
    Vec3 t = tangent - n * dot(n, tangent);
    const float l2 = length2(t);
    if (!(l2 > 1e-12f) || !std::isfinite(l2)) return from_normal(n);
    Frame f;
    f.n = n;
    f.t = t / std::sqrt(l2);
    f.b = cross(n, f.t);
    return f;
  }
};

}  // namespace knit::render
