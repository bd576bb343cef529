#include "render/render_job.h"

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>

#include "knit/table_cache.h"
#include "knit/table_progress.h"
#include "knit/version.h"
#include "render/output.h"
#include "render/renderer.h"
#include "render/scene.h"

namespace knit::render {

namespace {
double since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

// The class tables' builds while the scene loads, shown as the render's
// progress is: a bar per material that builds them ("knit class tables").
class TableBuildBar : public TableBuildProgress {
 public:
  explicit TableBuildBar(ProgressMode mode) : mode_(mode) { set_table_build_progress(this); }
  ~TableBuildBar() override { set_table_build_progress(nullptr); }
  void begin(uint64_t total) override { bar_ = std::make_unique<Progress>(mode_, total, "knit class tables"); }
  void add(uint64_t units) override {
    if (bar_) bar_->add(units);
  }
  void end() override { bar_.reset(); }  // (its last line drawn)

 private:
  ProgressMode mode_;
  std::unique_ptr<Progress> bar_;
};
}  // namespace

RenderJobResult run_render_job(const RenderJob& job, const std::function<void(const std::string&)>& warn) {
  const auto t_start = std::chrono::steady_clock::now();
  // --threads bounds the whole job, not only the render: the class tables
  // built while loading and the scene build run in parallel too.
  std::unique_ptr<tbb::global_control> limit;
  if (job.threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(job.threads));
  // Fail on a bad output name, folder or display before spending time on rendering.
  auto check_folder = [](const std::string& file, const char* what) {
    const std::filesystem::path parent = std::filesystem::path(file).parent_path();
    std::error_code ec;
    if (!parent.empty() && !std::filesystem::is_directory(parent, ec))
      throw std::runtime_error(file + ": the " + std::string(what) + " folder " + parent.string() + " does not exist");
  };
  if (!job.output_file.empty()) {
    if (output_format_for(job.output_file) == OutputFormat::Png) DisplayTransform check(job.display);
    check_folder(job.output_file, "output");
  }
  if (!job.report_file.empty()) check_folder(job.report_file, "report");

  if (job.table_cache_dir) {
    TableCacheSettings cache = table_cache();
    cache.dir = *job.table_cache_dir;
    set_table_cache(cache);
  }
  std::unique_ptr<TableBuildBar> table_bar;
  if (job.progress != ProgressMode::Quiet) table_bar = std::make_unique<TableBuildBar>(job.progress);
  SceneDesc desc = load_scene_file(job.scene_file, job.explicit_yarns && !job.knit_preview_diffuse);
  table_bar.reset();
  const double parse_seconds = since(t_start);
  Warnings warnings = desc.warnings;
  for (const MaterialDesc& m : desc.materials)
    if (m.type == MaterialType::Knit && m.knit.model && !m.knit.model->table_cache_note().empty())
      warnings.messages.push_back(m.knit.model->table_cache_note());
  if (job.width) desc.film.width = *job.width;
  if (job.height) desc.film.height = *job.height;
  if (job.spp) desc.film.spp = *job.spp;
  if (job.seed) desc.film.seed = *job.seed;

  BuildOptions options;
  options.knit_preview_diffuse = job.knit_preview_diffuse;
  options.explicit_yarns = job.explicit_yarns;
  const Scene scene(desc, options, warnings);
  if (warn)
    for (const std::string& w : warnings.messages) warn(w);

  RenderSettings settings;
  if (!job.mask_object.empty()) {
    std::string names;
    for (size_t i = 0; i < desc.objects.size(); ++i) {
      if (desc.objects[i].name == job.mask_object) {
        settings.mask_material = scene.object_material(i);
        if (settings.mask_material < 0)
          throw std::runtime_error("--mask-object " + job.mask_object +
                                   ": its knit material is drawn as explicit yarn tubes; a mask needs the base mesh "
                                   "(render the mask without --explicit-yarns)");
        break;
      }
      names += (names.empty() ? "" : ", ") + desc.objects[i].name;
    }
    if (settings.mask_material < 0)
      throw std::runtime_error(job.scene_file + ": --mask-object " + job.mask_object + ": no object of that name (" +
                               (names.empty() ? std::string("the scene has no named object") : "objects: " + names) +
                               ")");
  }
  settings.spp = desc.film.spp;
  settings.seed = desc.film.seed;
  settings.threads = job.threads;
  settings.progress = job.progress;
  RenderResult r = render_image(scene, settings);
  if (r.stats.invalid_samples > 0 && warn)
    warn(std::to_string(r.stats.invalid_samples) + " invalid (NaN, Inf or negative) radiance samples were dropped; first at pixel (" +
         std::to_string(r.invalid_x) + ", " + std::to_string(r.invalid_y) + "), sample " + std::to_string(r.invalid_sample));
  if (r.stats.pass_limit > 0 && warn)
    warn(std::to_string(r.stats.pass_limit) + " paths were stopped after " +
         std::to_string(PathIntegrator::kMaxPassThrough) + " pass-through crossings");

  const auto t_write = std::chrono::steady_clock::now();
  if (!job.output_file.empty()) write_output(job.output_file, r.image, desc.film.exposure, job.display);
  const double write_seconds = since(t_write);

  RenderJobResult out;
  RenderReport& rep = out.report;
  rep.scene = job.scene_file;
  rep.output = job.output_file;
  rep.version = knit::version();
  rep.width = desc.film.width;
  rep.height = desc.film.height;
  rep.spp = desc.film.spp;
  rep.seed = desc.film.seed;
  rep.threads = r.threads;
  // The knit materials' class tables are built while parsing: reported apart.
  for (const MaterialDesc& m : desc.materials)
    if (m.type == MaterialType::Knit && m.knit.model && m.knit.model->footprint_table()) {
      rep.knit_table_seconds += m.knit.model->table_seconds();
      ++(m.knit.model->table_from_cache()           ? rep.knit_tables_cached
         : m.knit.model->table_marches_from_cache() ? rep.knit_tables_finished
         : m.knit.model->table_shadows_from_cache() ? rep.knit_tables_shaded
                                                    : rep.knit_tables_built);
    }
  rep.parse_seconds = std::max(0.0, parse_seconds - rep.knit_table_seconds);
  rep.table_cache_dir = table_cache().dir;
  rep.load_seconds = scene.stats().load_seconds;
  rep.build_seconds = scene.stats().build_seconds;
  rep.render_seconds = r.seconds;
  rep.write_seconds = write_seconds;
  rep.samples = r.samples;
  rep.camera_rays = r.stats.camera_rays;
  rep.bounce_rays = r.stats.bounce_rays;
  rep.shadow_rays = r.stats.shadow_rays;
  rep.invalid_samples = r.stats.invalid_samples;
  rep.pass_limit = r.stats.pass_limit;
  rep.resolves = r.stats.resolves;
  rep.resolve_passes = r.stats.resolve_passes;
  rep.shadow_resolves = r.stats.shadow_resolves;
  rep.shell_bounces = r.stats.shell_bounces;
  rep.marches_spared = r.stats.marches_spared;
  rep.table_resolves = r.stats.table_resolves;
  rep.sub_cell_resolves = r.stats.sub_cell_resolves;
  rep.sub_boxes_reused = r.stats.sub_boxes_reused;
  rep.quarter_cell_resolves = r.stats.quarter_cell_resolves;
  rep.aggregate_resolves = r.stats.aggregate_resolves;
  rep.camera_resolves = r.stats.camera_resolves;
  rep.camera_table_footprints = r.stats.camera_table_footprints;
  rep.tube_spans = r.stats.tube_spans;
  rep.triangles = scene.stats().triangles;
  rep.mesh_bytes = scene.stats().mesh_bytes;
  rep.embree_bytes = scene.accel().embree_bytes();
  rep.embree_peak_bytes = scene.accel().embree_peak_bytes();
  rep.peak_rss_bytes = peak_rss_bytes();
  const SceneStats& st = scene.stats();
  rep.knit_materials = st.knit_materials;
  rep.knit_state_bytes = st.knit_state_bytes;
  rep.knit_binding_bytes = st.knit_binding_bytes;
  rep.explicit_yarns = st.explicit_yarns;
  rep.yarn_points = st.yarn_points;
  rep.yarn_samples_min = st.yarn_samples_min;
  rep.yarn_samples_max = st.yarn_samples_max;
  rep.yarn_segments = st.yarn_segments;
  rep.yarn_curves = st.yarn_curves;
  rep.yarn_geometry_bytes = st.yarn_geometry_bytes;
  rep.yarn_shading_bytes = st.yarn_shading_bytes;
  rep.yarn_build_seconds = st.yarn_build_seconds;
  rep.embree_yarn_bytes = st.yarn_segments > 0 ? rep.embree_bytes - st.embree_bytes_without_yarns : 0;
  rep.total_seconds = since(t_start);
  if (!job.report_file.empty()) {
    std::ofstream f(job.report_file);
    if (!f) throw std::runtime_error(job.report_file + ": cannot write the report");
    f << rep.to_json();
    if (!f) throw std::runtime_error(job.report_file + ": cannot write the report");
  }
  out.image = std::move(r.image);
  return out;
}

}  // namespace knit::render
