// `knitshade render SCENE -o IMAGE`: renders a scene file (docs/scene-format.md).
#ifdef KNIT_HAVE_RENDER

#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "knit/table_cache.h"
#include "render/render_job.h"

namespace knit::cli {
namespace {

const char* kUsage =
    "usage: knitshade render SCENE.json -o IMAGE.(exr|png) [options]\n"
    "\n"
    "Renders a scene file (docs/scene-format.md). EXR output is linear float;\n"
    "PNG output is display-referred through OpenColorIO ($OCIO if set, else sRGB).\n"
    "\n"
    "options:\n"
    "  -o, --output FILE        output image, .exr or .png (required)\n"
    "  --size WxH               image size in pixels (overrides film.width and film.height;\n"
    "                           the camera keeps its vertical field of view)\n"
    "  --spp N                  samples per pixel (overrides film.spp)\n"
    "  --seed N                 random seed (overrides film.seed)\n"
    "  --threads N              worker threads (default: all cores); the image does not depend on it\n"
    "  --quiet                  no progress and no report on the terminal\n"
    "  --report FILE.json       write the render report as JSON\n"
    "  --display NAME           OpenColorIO display for PNG output\n"
    "  --view NAME              OpenColorIO view, or DISPLAY/VIEW\n"
    "  --explicit-yarns         render knit materials as explicit yarn tubes (the ground\n"
    "                           truth) instead of with the knit model\n"
    "  --knit-preview-diffuse   debug: render knit materials as diffuse surfaces of their\n"
    "                           first yarn colour\n"
    "  --mask-object NAME       write a coverage mask instead of radiance: per pixel, the\n"
    "                           fraction of camera rays that first hit object NAME (for\n"
    "                           `knitshade compare --mask`)\n"
    "  --cache-dir DIR          keep multi-scale class tables in DIR between runs (default:\n"
    "                           $KNITSHADE_CACHE_DIR, else $XDG_CACHE_HOME/knitshade, else\n"
    "                           ~/.cache/knitshade, or where that cannot be written\n"
    "                           $TMPDIR/knitshade-cache-UID; KNITSHADE_CACHE_DIR=off: none)\n"
    "  --no-cache               build the class tables and keep nothing\n";

int run(const std::vector<std::string>& args) {
  using namespace knit::render;
  RenderJob job;
  bool quiet = false, no_cache = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "-o" || a == "--output") {
      job.output_file = option_value(args, i);
    } else if (a == "--size") {
      const SizeOption size = parse_size_option(a, option_value(args, i), 1, 16384);
      job.width = size.width;
      job.height = size.height;
    } else if (a == "--spp") {
      job.spp = static_cast<int>(parse_int_option(a, option_value(args, i), 1, 1 << 20));
    } else if (a == "--seed") {
      job.seed = static_cast<uint64_t>(parse_int_option(a, option_value(args, i), 0, INT64_MAX));
    } else if (a == "--threads") {
      job.threads = static_cast<int>(parse_int_option(a, option_value(args, i), 1, 1024));
    } else if (a == "--quiet" || a == "-q") {
      quiet = true;
    } else if (a == "--report") {
      job.report_file = option_value(args, i);
    } else if (a == "--display") {
      job.display.display = option_value(args, i);
    } else if (a == "--view") {
      job.display.view = option_value(args, i);
    } else if (a == "--explicit-yarns") {
      job.explicit_yarns = true;
    } else if (a == "--mask-object") {
      job.mask_object = option_value(args, i);
    } else if (a == "--cache-dir") {
      job.table_cache_dir = option_value(args, i);
      if (job.table_cache_dir->empty()) throw UsageError{"--cache-dir: empty folder name (use --no-cache for none)"};
    } else if (a == "--no-cache") {
      no_cache = true;
    } else if (a == "--knit-preview-diffuse") {
      job.knit_preview_diffuse = true;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else if (job.scene_file.empty()) {
      job.scene_file = a;
    } else {
      throw UsageError{"more than one scene file given ('" + job.scene_file + "' and '" + a + "')"};
    }
  }
  if (job.scene_file.empty()) throw UsageError{"no scene file given"};
  if (job.output_file.empty()) throw UsageError{"no output image given (-o IMAGE.exr or -o IMAGE.png)"};
  job.progress = quiet ? ProgressMode::Quiet : ProgressMode::Auto;
  if (no_cache && job.table_cache_dir) throw UsageError{"--cache-dir and --no-cache together"};
  if (no_cache)
    job.table_cache_dir = std::string();
  else if (!job.table_cache_dir)
    job.table_cache_dir = knit::writable_table_cache_dir();

  const RenderJobResult r = run_render_job(job, [](const std::string& w) {
    std::fprintf(stderr, "knitshade render: warning: %s\n", w.c_str());
  });
  if (!quiet) std::printf("%s", r.report.to_text().c_str());
  return 0;
}

const bool registered = register_command({"render", "render a scene file to an EXR or PNG image", &run});

}  // namespace
}  // namespace knit::cli

#endif  // KNIT_HAVE_RENDER
