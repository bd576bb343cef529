// Environment lights: uniform colour, and lat-long maps importance-sampled
// by a 2D CDF over texels.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "knit/fast_math.h"
#include "render/image.h"
#include "render/light.h"
#include "render/sampling.h"

namespace knit::render {

bool UniformEnvironmentLight::sample(Vec3, Vec2 u, LightSample& s) const {
  s.wi = sample_uniform_sphere(u);
  s.infinite = true;
  s.li = radiance_;
  s.pdf = uniform_sphere_pdf();
  s.delta = false;
  return true;
}

float UniformEnvironmentLight::pdf(Vec3, Vec3, const SurfaceInteraction*) const {
  return uniform_sphere_pdf();
}

float UniformEnvironmentLight::power(float scene_radius) const {
  return 4 * kPi * kPi * scene_radius * scene_radius * radiance_.luminance();
}

Vec3 EnvironmentMapLight::direction_of(Vec2 uv) {
  const float phi = 2 * kPi * (uv.x - 0.5f), theta = kPi * uv.y;
  const float st = std::sin(theta);
  return {st * std::sin(phi), std::cos(theta), -st * std::cos(phi)};
}

Vec2 EnvironmentMapLight::uv_of(Vec3 d) {
  // (libm's atan2f and acosf were a tenth of a scene's render under a map;
  // these are within 4e-7 rad, a small fraction of a texel.)
  const float phi = knit::atan2_approx(d.x, -d.z);
  float u = 0.5f + phi * kInv2Pi;
  if (u >= 1.0f) u -= 1.0f;
  if (u < 0.0f) u += 1.0f;
  const float v = knit::acos_approx(d.y) * kInvPi;
  return {u, v};
}

EnvironmentMapLight::EnvironmentMapLight(const LightDesc& d, const std::string& scene_file)
    : strength_(d.strength) {
  try {
    RgbImage img = read_rgb_image(d.file);
    pixels_ = std::move(img.pixels);
    width_ = img.width;
    height_ = img.height;
  } catch (const std::exception& e) {
    throw SceneError(scene_file, d.path + ".file", e.what());
  }
  cos_rot_ = std::cos(radians(d.rotation));
  sin_rot_ = std::sin(radians(d.rotation));
  try {
    build();
  } catch (const std::exception& e) {
    throw SceneError(scene_file, d.path + ".file", d.file + ": " + e.what());
  }
}

EnvironmentMapLight::EnvironmentMapLight(std::vector<Rgb> pixels, int width, int height, float strength,
                                         float rotation_deg)
    : pixels_(std::move(pixels)), width_(width), height_(height), strength_(strength) {
  if (width <= 0 || height <= 0 || pixels_.size() != static_cast<size_t>(width) * height)
    throw std::invalid_argument("EnvironmentMapLight: pixel count does not match the size");
  cos_rot_ = std::cos(radians(rotation_deg));
  sin_rot_ = std::sin(radians(rotation_deg));
  build();
}

void EnvironmentMapLight::build() {
  // The radiance lookup is bilinear, so the value inside a texel's cell mixes
  // its 3x3 neighbourhood. Sampling in proportion to the neighbourhood's
  // maximum luminance keeps radiance / pdf bounded: no fireflies next to
  // small bright features such as a sun.
  std::vector<float> f(pixels_.size());
  integral_lum_ = 0;
  for (int y = 0; y < height_; ++y) {
    const float st = std::sin(kPi * (static_cast<float>(y) + 0.5f) / static_cast<float>(height_));
    for (int x = 0; x < width_; ++x) {
      const size_t i = static_cast<size_t>(y) * width_ + x;
      float lum_max = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int yy = std::clamp(y + dy, 0, height_ - 1);
          const int xx = ((x + dx) % width_ + width_) % width_;
          lum_max = std::max(lum_max, pixels_[static_cast<size_t>(yy) * width_ + xx].luminance());
        }
      f[i] = lum_max * st;
      integral_lum_ += static_cast<double>(std::max(0.0f, pixels_[i].luminance())) * st;
    }
  }
  integral_lum_ *= (2.0 * kPi / width_) * (kPi / height_) * strength_;
  dist_ = Distribution2D(f, static_cast<size_t>(width_), static_cast<size_t>(height_));
}

Rgb EnvironmentMapLight::lookup(Vec2 uv) const {
  const float x = uv.x * static_cast<float>(width_) - 0.5f;
  const float y = uv.y * static_cast<float>(height_) - 0.5f;
  const float fx0 = std::floor(x), fy0 = std::floor(y);
  const float tx = x - fx0, ty = y - fy0;
  // u in [0, 1): x0 in [-1, width_ - 1]; wrapped without integer division.
  int x0 = static_cast<int>(fx0);
  if (x0 < 0) x0 += width_;
  if (x0 >= width_) x0 -= width_;
  const int x1 = x0 + 1 < width_ ? x0 + 1 : 0;
  const int y0 = std::clamp(static_cast<int>(fy0), 0, height_ - 1);
  const int y1 = std::clamp(static_cast<int>(fy0) + 1, 0, height_ - 1);
  auto px = [&](int xi, int yi) { return pixels_[static_cast<size_t>(yi) * width_ + xi]; };
  return (px(x0, y0) * (1 - tx) + px(x1, y0) * tx) * (1 - ty) + (px(x0, y1) * (1 - tx) + px(x1, y1) * tx) * ty;
}

bool EnvironmentMapLight::sample(Vec3, Vec2 u, LightSample& s) const {
  if (!(dist_.integral() > 0)) return false;
  float pdf_uv = 0;
  const Vec2 uv = dist_.sample(u, pdf_uv);
  if (!(pdf_uv > 0)) return false;
  const float st = std::sin(kPi * uv.y);
  if (!(st > 0)) return false;
  const Vec3 l = direction_of(uv);
  // Environment space -> world: rotate by +rotation about +y.
  s.wi = {cos_rot_ * l.x + sin_rot_ * l.z, l.y, -sin_rot_ * l.x + cos_rot_ * l.z};
  s.infinite = true;
  s.li = lookup(uv) * strength_;
  s.pdf = pdf_uv / (2 * kPi * kPi * st);
  s.delta = false;
  return std::isfinite(s.pdf);
}

float EnvironmentMapLight::pdf(Vec3, Vec3 wi, const SurfaceInteraction*) const {
  if (!(dist_.integral() > 0)) return 0;
  const Vec3 l = {cos_rot_ * wi.x - sin_rot_ * wi.z, wi.y, sin_rot_ * wi.x + cos_rot_ * wi.z};
  const Vec2 uv = uv_of(l);
  const float st = std::sqrt(std::max(0.0f, 1 - l.y * l.y));  // sin theta
  if (!(st > 0)) return 0;
  return dist_.pdf(uv) / (2 * kPi * kPi * st);
}

Rgb EnvironmentMapLight::environment(Vec3 dir) const {
  const Vec3 l = {cos_rot_ * dir.x - sin_rot_ * dir.z, dir.y, sin_rot_ * dir.x + cos_rot_ * dir.z};
  return lookup(uv_of(l)) * strength_;
}

float EnvironmentMapLight::power(float scene_radius) const {
  return static_cast<float>(kPi * scene_radius * scene_radius * integral_lum_);
}

}  // namespace knit::render
