// Lights. Area lights are also shapes in the Accel (the integrator meets
// them by ray hits, for MIS); point and directional lights are delta lights
// reached by next-event estimation only; the environment is reached by rays
// that escape. Every sample() density is per unit solid angle at the shaded
// point (delta lights report 1 and set `delta`).
#pragma once

#include <memory>
#include <vector>

#include "render/distribution.h"
#include "render/interaction.h"
#include "render/mesh.h"
#include "render/scene_desc.h"

namespace knit::render {

struct LightSample {
  Vec3 wi;          // unit direction from the shaded point toward the light
  Vec3 p;           // point on the light (unused for infinite lights)
  bool infinite = false;
  Rgb li;           // incident radiance (delta lights: intensity / dist^2 or irradiance)
  float pdf = 0;    // solid-angle density; 1 for delta lights
  bool delta = false;
};

class Light {
 public:
  virtual ~Light() = default;
  // Samples incident light at `p`; false when nothing can be sampled.
  virtual bool sample(Vec3 p, Vec2 u, LightSample& s) const = 0;
  // Solid-angle density of sample() producing direction `wi` at `p`, given
  // what that direction hits: `hit` for area lights, nullptr for the environment.
  virtual float pdf(Vec3 p, Vec3 wi, const SurfaceInteraction* hit) const = 0;
  // Radiance an area light emits from `hit` toward `wo`.
  virtual Rgb emitted(const SurfaceInteraction& /*hit*/, Vec3 /*wo*/) const { return {}; }
  // Radiance arriving from the environment along -dir (dir points away from the scene).
  virtual Rgb environment(Vec3 /*dir*/) const { return {}; }
  virtual bool is_delta() const { return false; }
  virtual bool is_infinite() const { return false; }
  // Emitted power (luminance), for picking lights in proportion to it.
  // Infinite lights need the scene's bounding sphere radius.
  virtual float power(float scene_radius) const = 0;
};

// A parallelogram (corner, corner + edge_u, corner + edge_u + edge_v,
// corner + edge_v) emitting `emission` toward +normalize(edge_u x edge_v),
// or both ways when two-sided.
class QuadLight final : public Light {
 public:
  explicit QuadLight(const LightDesc& d);
  bool sample(Vec3 p, Vec2 u, LightSample& s) const override;
  float pdf(Vec3 p, Vec3 wi, const SurfaceInteraction* hit) const override;
  Rgb emitted(const SurfaceInteraction& hit, Vec3 wo) const override;
  float power(float scene_radius) const override;
  // The two-triangle mesh to put in the Accel.
  std::shared_ptr<TriangleMesh> make_mesh() const;

 private:
  Vec3 corner_, eu_, ev_, n_;
  float area_ = 0;
  Rgb emission_;
  bool two_sided_ = false;
};

class PointLight final : public Light {
 public:
  explicit PointLight(const LightDesc& d) : pos_(d.position), intensity_(d.intensity) {}
  bool sample(Vec3 p, Vec2 u, LightSample& s) const override;
  float pdf(Vec3, Vec3, const SurfaceInteraction*) const override { return 0; }
  bool is_delta() const override { return true; }
  float power(float scene_radius) const override;

 private:
  Vec3 pos_;
  Rgb intensity_;
};

class DirectionalLight final : public Light {
 public:
  explicit DirectionalLight(const LightDesc& d) : to_light_(d.to_light), irradiance_(d.irradiance) {}
  bool sample(Vec3 p, Vec2 u, LightSample& s) const override;
  float pdf(Vec3, Vec3, const SurfaceInteraction*) const override { return 0; }
  bool is_delta() const override { return true; }
  bool is_infinite() const override { return true; }
  float power(float scene_radius) const override;

 private:
  Vec3 to_light_;
  Rgb irradiance_;
};

// Uniform environment: the same radiance from every direction.
class UniformEnvironmentLight final : public Light {
 public:
  explicit UniformEnvironmentLight(const LightDesc& d) : radiance_(d.color * d.strength) {}
  bool sample(Vec3 p, Vec2 u, LightSample& s) const override;
  float pdf(Vec3 p, Vec3 wi, const SurfaceInteraction* hit) const override;
  Rgb environment(Vec3 dir) const override { (void)dir; return radiance_; }
  bool is_infinite() const override { return true; }
  float power(float scene_radius) const override;

 private:
  Rgb radiance_;
};

// Lat-long environment map (docs/scene-format.md#environment): +y is up, the
// image centre looks toward -z, u grows toward +x; importance-sampled by a
// piecewise-constant 2D distribution over texels weighted by sin(theta).
class EnvironmentMapLight final : public Light {
 public:
  // Loads the image with OpenImageIO; throws SceneError naming `scene_file` and d.path.
  EnvironmentMapLight(const LightDesc& d, const std::string& scene_file);
  // From pixels (row-major, row 0 at the top), for tests.
  EnvironmentMapLight(std::vector<Rgb> pixels, int width, int height, float strength, float rotation_deg);

  bool sample(Vec3 p, Vec2 u, LightSample& s) const override;
  float pdf(Vec3 p, Vec3 wi, const SurfaceInteraction* hit) const override;
  Rgb environment(Vec3 dir) const override;
  bool is_infinite() const override { return true; }
  float power(float scene_radius) const override;

  // Direction <-> image coordinates in [0, 1)^2 (before rotation).
  static Vec3 direction_of(Vec2 uv);
  static Vec2 uv_of(Vec3 dir);

 private:
  void build();
  Rgb lookup(Vec2 uv) const;  // bilinear, wraps in u, clamps in v
  std::vector<Rgb> pixels_;
  int width_ = 0, height_ = 0;
  float strength_ = 1;
  float cos_rot_ = 1, sin_rot_ = 0;
  Distribution2D dist_;
  double integral_lum_ = 0;  // integral of luminance over the sphere
};

// Picks one light per shading point: half in proportion to its power, half
// uniformly (lights without power are never picked).
class LightSampler {
 public:
  LightSampler() = default;
  LightSampler(const std::vector<const Light*>& lights, float scene_radius);
  bool empty() const { return lights_.empty(); }
  // Index and probability of the picked light.
  const Light* pick(float u, float& prob, size_t& index) const;
  float probability(size_t index) const;

 private:
  std::vector<const Light*> lights_;
  Distribution1D dist_;
};

}  // namespace knit::render
