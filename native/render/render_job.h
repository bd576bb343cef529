// One `knitshade render` run as a library call: parse, build, render, write,
// report. The CLI (native/cli/cmd_render.cpp) only parses arguments.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "render/display.h"
#include "render/image.h"
#include "render/progress.h"
#include "render/report.h"

namespace knit::render {

struct RenderJob {
  std::string scene_file;
  std::string output_file;  // .exr or .png; empty: do not write
  std::string report_file;  // JSON report; empty: none
  std::optional<int> width, height;  // override film.width, film.height
  std::optional<int> spp;   // override film.spp
  std::optional<uint64_t> seed;
  int threads = 0;
  ProgressMode progress = ProgressMode::Quiet;
  bool knit_preview_diffuse = false;  // debug: knit materials as diffuse surfaces
  bool explicit_yarns = false;        // knit materials as explicit yarn tubes
  // Non-empty: write a coverage mask of the object of this name instead of
  // radiance (1 where the camera sees its base mesh first, 0 elsewhere,
  // fractions at its edges), for `knitshade compare --mask`.
  std::string mask_object;
  DisplaySettings display;
  // The class-table cache's folder for this job's multi-scale materials
  // (knit/table_cache.h; empty: no cache); unset: the process's setting as
  // it stands (off unless the host turned it on).
  std::optional<std::string> table_cache_dir;
};

struct RenderJobResult {
  RgbImage image;  // linear, before exposure
  RenderReport report;
};

// Throws SceneError / std::runtime_error with one clear message. `warn`
// receives each warning as it is found (loading, invalid samples).
RenderJobResult run_render_job(const RenderJob& job, const std::function<void(const std::string&)>& warn = {});

}  // namespace knit::render
