// The render-ready scene: materials, lights, the camera and the Accel, built
// from a validated SceneDesc (meshes loaded, transformed, checked).
#pragma once

#include <memory>
#include <vector>

#include "render/accel.h"
#include "render/camera.h"
#include "render/light.h"
#include "render/material.h"
#include "render/scene_desc.h"

namespace knit::render {

struct BuildOptions {
  // Render knit materials as diffuse surfaces of their base colour instead
  // of refusing the scene (the knit model itself is phase 2).
  bool knit_preview_diffuse = false;
};

struct SceneStats {
  size_t meshes_loaded = 0;  // distinct mesh files
  size_t triangles = 0;      // in the Accel, lights included
  size_t mesh_bytes = 0;     // our vertex/index data
  double load_seconds = 0;   // mesh and image loading
  double build_seconds = 0;  // Embree BVH build
};

class Scene {
 public:
  // Throws SceneError naming desc.file and the field at fault.
  Scene(const SceneDesc& desc, const BuildOptions& options, Warnings& warnings);

  const SceneDesc& desc() const { return desc_; }
  const Accel& accel() const { return *accel_; }
  const Material& material(int i) const { return *materials_[static_cast<size_t>(i)]; }
  const Light& light(int i) const { return *lights_[static_cast<size_t>(i)]; }
  size_t num_lights() const { return lights_.size(); }
  const LightSampler& light_sampler() const { return light_sampler_; }
  // The environment light reached by escaping rays (nullptr if none).
  const Light* environment() const { return environment_; }
  int environment_index() const { return environment_index_; }
  bool has_pass_through() const { return has_pass_through_; }
  const PinholeCamera& camera() const { return camera_; }
  const SceneStats& stats() const { return stats_; }
  float radius() const { return radius_; }

 private:
  SceneDesc desc_;
  std::unique_ptr<Accel> accel_;
  std::vector<std::unique_ptr<Material>> materials_;
  std::vector<std::unique_ptr<Light>> lights_;
  LightSampler light_sampler_;
  const Light* environment_ = nullptr;
  int environment_index_ = -1;
  bool has_pass_through_ = false;
  PinholeCamera camera_;
  SceneStats stats_;
  float radius_ = 1;
};

}  // namespace knit::render
