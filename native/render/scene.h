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
  // Debug: render knit materials as diffuse surfaces of their first yarn
  // colour instead of with the knit model.
  bool knit_preview_diffuse = false;
  // Render knit materials as explicit yarn tubes (ground truth); also set by
  // the scene's integrator.explicit_yarns.
  bool explicit_yarns = false;
};

struct SceneStats {
  size_t meshes_loaded = 0;  // distinct mesh files
  size_t triangles = 0;      // in the Accel, lights included
  size_t mesh_bytes = 0;     // our vertex/index data
  double load_seconds = 0;   // mesh and image loading
  double build_seconds = 0;  // Embree BVH build
  // The knit model (docs/renderer.md#report).
  size_t knit_materials = 0;       // knit materials used by objects
  size_t knit_state_bytes = 0;     // KnitMaterial::state_bytes() summed over them
  size_t knit_binding_bytes = 0;   // per-mesh tables of the renderer (scale, curvature, MeshFrame)
  // Explicit yarns (--explicit-yarns).
  bool explicit_yarns = false;
  size_t yarn_points = 0, yarn_segments = 0, yarn_curves = 0;
  size_t yarn_geometry_bytes = 0;  // Embree vertex/index/flag buffers of the tubes
  size_t yarn_shading_bytes = 0;   // per-point colour, ply coordinate, fabric normal
  double yarn_build_seconds = 0;   // making the tubes (curves, mapping onto the meshes)
  int yarn_samples_min = 0, yarn_samples_max = 0;  // explicit_samples of the materials made tubes
  int64_t embree_bytes_without_yarns = 0;  // Embree's memory before the tubes were added
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
  // Some geometry blocks shadow rays outright (Accel::has_blockers).
  bool has_shadow_blockers() const { return has_shadow_blockers_; }
  const PinholeCamera& camera() const { return camera_; }
  const SceneStats& stats() const { return stats_; }
  float radius() const { return radius_; }
  // Material index the base mesh of desc().objects[i] is drawn with (-1 when
  // explicit yarn tubes replace it).
  int object_material(size_t i) const { return object_materials_[i]; }

 private:
  SceneDesc desc_;
  std::unique_ptr<Accel> accel_;
  std::vector<std::unique_ptr<Material>> materials_;
  std::vector<std::unique_ptr<Light>> lights_;
  LightSampler light_sampler_;
  const Light* environment_ = nullptr;
  int environment_index_ = -1;
  bool has_pass_through_ = false;
  bool has_shadow_blockers_ = false;
  PinholeCamera camera_;
  SceneStats stats_;
  float radius_ = 1;
  std::vector<int> object_materials_;
};

}  // namespace knit::render
