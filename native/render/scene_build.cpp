// Scene construction: SceneDesc -> materials, meshes in the Accel, lights.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "render/curve_shape.h"
#include "render/json_strict.h"
#include "render/material_explicit_yarn.h"
#include "render/material_knit.h"
#include "render/materials.h"
#include "render/scene.h"
#include "render/triangle_shape.h"
#include "render/yarn_tubes.h"

namespace knit::render {

namespace {
double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The material of a desc. A knit material gets its diffuse preview here
// (used only with --knit-preview-diffuse); objects carrying the knit model or
// explicit yarns get materials of their own (Scene::Scene).
std::unique_ptr<Material> make_material(const MaterialDesc& m, const std::string& file) {
  switch (m.type) {
    case MaterialType::Diffuse: return std::make_unique<DiffuseMaterial>(m.diffuse.albedo);
    case MaterialType::Dielectric:
      // (an index of 1 is no interface: light goes straight through, a delta
      // whatever the roughness)
      if (m.dielectric.roughness > 0 && m.dielectric.eta != 1.0f)
        return std::make_unique<RoughDielectricMaterial>(m.dielectric);
      return std::make_unique<SmoothDielectricMaterial>(m.dielectric);
    case MaterialType::Thin: return std::make_unique<ThinMaterial>(m.thin);
    case MaterialType::Knit: return std::make_unique<DiffuseMaterial>(m.knit.base_color());
  }
  throw SceneError(file, m.path, "unknown material type");
}
}  // namespace

// (an error about a field of the scene file names its line: JsonPositions)
Scene::Scene(const SceneDesc& desc, const BuildOptions& options, Warnings& warnings) try
    : desc_(desc), accel_(std::make_unique<Accel>()), camera_(desc.camera, desc.film.width, desc.film.height) {
  const auto t_load = std::chrono::steady_clock::now();
  for (const MaterialDesc& m : desc.materials) {
    materials_.push_back(make_material(m, desc.file));
    if (materials_.back()->can_pass_through()) has_pass_through_ = true;
  }
  const bool explicit_yarns = (options.explicit_yarns || desc.integrator.explicit_yarns) && !options.knit_preview_diffuse;
  stats_.explicit_yarns = explicit_yarns;
  std::vector<char> knit_used(desc.materials.size(), 0);
  struct YarnJob {
    std::shared_ptr<const TriangleMesh> mesh;
    const MaterialDesc* material;
    const ObjectDesc* object;
  };
  std::vector<YarnJob> yarn_jobs;

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
    int material = o.material;
    if (md.type == MaterialType::Knit && !options.knit_preview_diffuse) {
      if (!knit_used[size_t(o.material)]) {
        knit_used[size_t(o.material)] = 1;
        ++stats_.knit_materials;
        stats_.knit_state_bytes += md.knit.model->state_bytes();
      }
      if (explicit_yarns) {
        yarn_jobs.push_back({mesh, &md, &o});
        object_materials_.push_back(-1);
        continue;  // the base mesh is only the top of the yarn shell: the tubes replace it
      }
      const std::string where = desc.file + ": " + o.path + " (" + o.name + ")";
      auto km = std::make_unique<KnitModelMaterial>(md.knit, mesh, desc.file, md.path, o.path, where, warnings);
      stats_.knit_binding_bytes += km->binding_bytes();
      materials_.push_back(std::move(km));
      has_pass_through_ = true;
      material = static_cast<int>(materials_.size()) - 1;
    }
    stats_.mesh_bytes += mesh->memory_bytes();
    object_materials_.push_back(material);
    const unsigned id = accel_->add(std::make_unique<TriangleShape>(mesh), material, -1);
    if (material >= 0 && materials_[size_t(material)]->can_pass_through()) accel_->set_pass_through(id);
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

  auto commit = [&] {
    const auto t_build = std::chrono::steady_clock::now();
    try {
      accel_->commit();
    } catch (const std::exception& e) {
      throw SceneError(desc.file, "", std::string("cannot build the acceleration structure: ") + e.what());
    }
    stats_.build_seconds += seconds_since(t_build);
  };
  commit();
  if (!yarn_jobs.empty()) {
    // Explicit yarns: built and added after the rest, so that Embree's
    // memory for the tubes can be told apart from the rest of the scene's.
    stats_.embree_bytes_without_yarns = accel_->embree_bytes();
    const auto t_yarns = std::chrono::steady_clock::now();
    std::map<const MaterialDesc*, int> yarn_material;
    for (const YarnJob& job : yarn_jobs) {
      auto it = yarn_material.find(job.material);
      if (it == yarn_material.end()) {
        materials_.push_back(std::make_unique<ExplicitYarnMaterial>(job.material->knit.model));
        it = yarn_material.emplace(job.material, static_cast<int>(materials_.size()) - 1).first;
      }
      std::shared_ptr<const YarnTubes> tubes;
      try {
        tubes = std::make_shared<const YarnTubes>(
            build_yarn_tubes(*job.mesh, *job.material->knit.model, job.material->knit.explicit_samples));
      } catch (const std::exception& e) {
        throw SceneError(desc.file, job.object->path + ".mesh",
                         std::string("explicit yarns of ") + job.material->path + ": " + e.what());
      }
      if (tubes->segments.empty()) {
        warnings.add(desc.file + ": " + job.object->path + ": no explicit yarn of " + job.material->path +
                     " lies on the mesh (is uv_scale too small for its UV range?)");
        continue;
      }
      stats_.yarn_points += tubes->num_points();
      const int samples = job.material->knit.explicit_samples;
      stats_.yarn_samples_min = stats_.yarn_samples_min ? std::min(stats_.yarn_samples_min, samples) : samples;
      stats_.yarn_samples_max = std::max(stats_.yarn_samples_max, samples);
      stats_.yarn_segments += tubes->segments.size();
      stats_.yarn_curves += tubes->curves;
      // (twice the vertices: the scaled copy Embree sees, CurveShape::attach)
      stats_.yarn_geometry_bytes += tubes->geometry_bytes() + tubes->vertices.size() * sizeof(float);
      stats_.yarn_shading_bytes += tubes->shading_bytes();
      const unsigned id = accel_->add(std::make_unique<CurveShape>(tubes), it->second, -1);
      if (materials_[size_t(it->second)]->can_pass_through()) accel_->set_pass_through(id);
      has_pass_through_ = true;
    }
    stats_.yarn_build_seconds = seconds_since(t_yarns);
    commit();
  }
  stats_.triangles = accel_->num_primitives() - stats_.yarn_segments;
  has_shadow_blockers_ = accel_->has_blockers();

  Vec3 lo, hi;
  accel_->bounds(lo, hi);
  if (accel_->num_geometries() > 0 && is_finite(lo) && is_finite(hi)) {
    radius_ = std::max(0.5f * length(hi - lo), 1e-3f);
  }
  std::vector<const Light*> ptrs;
  for (const auto& l : lights_) ptrs.push_back(l.get());
  light_sampler_ = LightSampler(ptrs, radius_);
} catch (const SceneError& e) {
  if (!desc.text) throw;
  throw JsonPositions(*desc.text).locate(e, desc.file);
}

}  // namespace knit::render
