// Scene construction: SceneDesc -> materials, meshes in the Accel, lights.
#include <chrono>
#include <cmath>
#include <map>

#include "render/materials.h"
#include "render/scene.h"
#include "render/triangle_shape.h"

namespace knit::render {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::unique_ptr<Material> make_material(const MaterialDesc& m, const std::string& file,
                                        const BuildOptions& options) {
  switch (m.type) {
    case MaterialType::Diffuse: return std::make_unique<DiffuseMaterial>(m.diffuse.albedo);
    case MaterialType::Dielectric: return std::make_unique<SmoothDielectricMaterial>(m.dielectric);
    case MaterialType::Thin: return std::make_unique<ThinMaterial>(m.thin);
    case MaterialType::Knit:
      if (!options.knit_preview_diffuse)
        throw SceneError(file, m.path,
                         "rendering the knit material is not implemented yet (phase 2 of the "
                         "native renderer); pass --knit-preview-diffuse to render it as a diffuse "
                         "surface of its base colour (yarn_colors[0])");
      return std::make_unique<DiffuseMaterial>(m.knit.base_color());
  }
  throw SceneError(file, m.path, "unknown material type");
}
}  // namespace

Scene::Scene(const SceneDesc& desc, const BuildOptions& options, Warnings& warnings)
    : desc_(desc), accel_(std::make_unique<Accel>()), camera_(desc.camera, desc.film.width, desc.film.height) {
  const auto t_load = std::chrono::steady_clock::now();
  for (const MaterialDesc& m : desc.materials) {
    materials_.push_back(make_material(m, desc.file, options));
    if (materials_.back()->can_pass_through()) has_pass_through_ = true;
  }

  std::map<std::string, std::shared_ptr<const TriangleMesh>> cache;
  for (const ObjectDesc& o : desc.objects) {
    std::shared_ptr<const TriangleMesh> base;
    auto it = cache.find(o.mesh_file);
    if (it != cache.end()) {
      base = it->second;
    } else {
      try {
        base = std::make_shared<const TriangleMesh>(load_mesh(o.mesh_file, &warnings));
      } catch (const std::exception& e) {
        throw SceneError(desc.file, o.path + ".mesh", e.what());
      }
      cache.emplace(o.mesh_file, base);
    }
    const MaterialDesc& md = desc.materials[static_cast<size_t>(o.material)];
    if (md.type == MaterialType::Knit && !base->has_uvs())
      throw SceneError(desc.file, o.path + ".mesh",
                       o.mesh_file + " has no UV coordinates, which the knit material '" + md.name +
                           "' needs");
    auto mesh = o.transform.is_identity() ? base
                                          : std::make_shared<const TriangleMesh>(transform_mesh(*base, o.transform));
    stats_.mesh_bytes += mesh->memory_bytes();
    accel_->add(std::make_unique<TriangleShape>(mesh), o.material, -1);
  }
  stats_.meshes_loaded = cache.size();

  for (const LightDesc& l : desc.lights) {
    const int index = static_cast<int>(lights_.size());
    switch (l.type) {
      case LightType::Quad: {
        auto q = std::make_unique<QuadLight>(l);
        auto mesh = q->make_mesh();
        stats_.mesh_bytes += mesh->memory_bytes();
        accel_->add(std::make_unique<TriangleShape>(std::move(mesh)), -1, index);
        lights_.push_back(std::move(q));
        break;
      }
      case LightType::Point: lights_.push_back(std::make_unique<PointLight>(l)); break;
      case LightType::Directional: lights_.push_back(std::make_unique<DirectionalLight>(l)); break;
      case LightType::EnvironmentUniform:
        lights_.push_back(std::make_unique<UniformEnvironmentLight>(l));
        environment_ = lights_.back().get();
        environment_index_ = index;
        break;
      case LightType::EnvironmentMap:
        lights_.push_back(std::make_unique<EnvironmentMapLight>(l, desc.file));
        environment_ = lights_.back().get();
        environment_index_ = index;
        break;
    }
  }
  stats_.load_seconds = seconds_since(t_load);

  const auto t_build = std::chrono::steady_clock::now();
  try {
    accel_->commit();
  } catch (const std::exception& e) {
    throw SceneError(desc.file, "", std::string("cannot build the acceleration structure: ") + e.what());
  }
  stats_.build_seconds = seconds_since(t_build);
  stats_.triangles = accel_->num_primitives();

  Vec3 lo, hi;
  accel_->bounds(lo, hi);
  if (accel_->num_geometries() > 0 && is_finite(lo) && is_finite(hi)) {
    radius_ = std::max(0.5f * length(hi - lo), 1e-3f);
  }
  std::vector<const Light*> ptrs;
  for (const auto& l : lights_) ptrs.push_back(l.get());
  light_sampler_ = LightSampler(ptrs, radius_);
}

}  // namespace knit::render
