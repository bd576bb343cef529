#include "render/report.h"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>
#include <numeric>
#include <string>
#include <nlohmann/json.hpp>

#include "render/scene_desc.h"

namespace knit::render {

int64_t peak_rss_bytes() {
  struct rusage ru {};
  if (getrusage(RUSAGE_SELF, &ru) != 0) return -1;
  return static_cast<int64_t>(ru.ru_maxrss) * 1024;  // Linux reports KiB
}

std::string format_bytes(double b) {
  const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (b >= 1024.0 && u < 4) {
    b /= 1024.0;
    ++u;
  }
  char buf[32];
  std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", b, units[u]);
  return buf;
}

static std::string si_rate(double v) {
  char buf[32];
  if (v >= 1e9) std::snprintf(buf, sizeof buf, "%.2f G", v / 1e9);
  else if (v >= 1e6) std::snprintf(buf, sizeof buf, "%.2f M", v / 1e6);
  else if (v >= 1e3) std::snprintf(buf, sizeof buf, "%.2f k", v / 1e3);
  else std::snprintf(buf, sizeof buf, "%.0f ", v);
  return buf;
}

std::string RenderReport::to_text() const {
  char buf[1024];
  std::string s;
  std::snprintf(buf, sizeof buf, "rendered %s: %dx%d, %d spp, %d threads\n", scene.c_str(), width, height, spp, threads);
  s += buf;
  // The knit class tables are built while the scene is parsed; parse_seconds
  // leaves them out, so the parts still add up to the wall time.
  // Explicit yarns: sweeping the tubes and building their BVH.
  char tables[192] = "", yarns[64] = "";
  const int ntables = knit_tables_built + knit_tables_cached + knit_tables_finished + knit_tables_shaded;
  if (ntables > 0 && knit_tables_cached == ntables) {
    std::snprintf(tables, sizeof tables, "knit class tables %.2f from the cache, ", knit_table_seconds);
  } else if (knit_tables_cached > 0 || knit_tables_finished > 0 || knit_tables_shaded > 0) {
    // e.g. "(1 of 3 from the cache, 1 finished from its marches, 1 marched from its shadows)"
    std::string parts = std::to_string(knit_tables_cached) + " of " + std::to_string(ntables) + " from the cache";
    if (knit_tables_finished > 0) parts += ", " + std::to_string(knit_tables_finished) + " finished from its marches";
    if (knit_tables_shaded > 0) parts += ", " + std::to_string(knit_tables_shaded) + " marched from its shadows";
    std::snprintf(tables, sizeof tables, "knit class tables %.2f (%s), ", knit_table_seconds, parts.c_str());
  } else if (ntables > 0 || knit_table_seconds > 0) {
    std::snprintf(tables, sizeof tables, "knit class tables %.2f, ", knit_table_seconds);
  }
  if (explicit_yarns) std::snprintf(yarns, sizeof yarns, "yarns %.2f, ", yarn_build_seconds);
  std::snprintf(buf, sizeof buf, "  wall time   %.2f s (parse %.2f, %sload %.2f, %sBVH %.2f, render %.2f, write %.2f)\n",
                total_seconds, parse_seconds, tables, load_seconds, yarns, build_seconds, render_seconds,
                write_seconds);
  s += buf;
  std::snprintf(buf, sizeof buf, "  samples     %llu, %ssamples/s\n", static_cast<unsigned long long>(samples),
                si_rate(samples_per_second()).c_str());
  s += buf;
  std::snprintf(buf, sizeof buf, "  rays        %llu (camera %llu, bounce %llu, shadow %llu), %srays/s\n",
                static_cast<unsigned long long>(total_rays()), static_cast<unsigned long long>(camera_rays),
                static_cast<unsigned long long>(bounce_rays), static_cast<unsigned long long>(shadow_rays),
                si_rate(rays_per_second()).c_str());
  s += buf;
  std::snprintf(buf, sizeof buf, "  memory      peak RSS %s, Embree BVH %s (peak %s), meshes %s, %zu triangles\n",
                format_bytes(static_cast<double>(peak_rss_bytes)).c_str(),
                format_bytes(static_cast<double>(embree_bytes)).c_str(),
                format_bytes(static_cast<double>(embree_peak_bytes)).c_str(),
                format_bytes(static_cast<double>(mesh_bytes)).c_str(), triangles);
  s += buf;
  if (knit_materials > 0) {
    std::snprintf(buf, sizeof buf,
                  "  knit hits   %.2f per sample (%.0f%% passed on), %.2f shadow-ray crossings and %.2f bounces "
                  "inside the shell per sample\n",
                  samples ? double(resolves) / double(samples) : 0.0,
                  resolves ? 100.0 * double(resolve_passes) / double(resolves) : 0.0,
                  samples ? double(shadow_resolves) / double(samples) : 0.0,
                  samples ? double(shell_bounces) / double(samples) : 0.0);
    s += buf;
    if (marches_spared > 0) {
      std::snprintf(buf, sizeof buf,
                    "  shadowing   %.2f light samples per sample from inside the yarn shell found an opaque object "
                    "in the way (no march)\n",
                    samples ? double(marches_spared) / double(samples) : 0.0);
      s += buf;
    }
    if (table_resolves > 0 || aggregate_resolves > 0) {
      const double table = 100.0 * double(table_resolves) / double(resolves);
      const double sub = 100.0 * double(sub_cell_resolves) / double(resolves);
      const double aggregated = 100.0 * double(aggregate_resolves) / double(resolves);
      std::snprintf(buf, sizeof buf,
                    "  multi-scale %.1f%% of the knit hits from the class table (%.1f%% whole cells, %.1f%% "
                    "sub-cells), %.1f%% aggregated over marched points, %.1f%% as the near field (small "
                    "footprints, bounces)\n",
                    table, table - sub, sub, aggregated, std::max(0.0, 100.0 - table - aggregated));
      s += buf;
    }
    // A tenth or more of the hits shaded as the near field only for being
    // below table_min_cells: say what would serve them from the table.
    if (resolves > 0 && 10 * quarter_cell_resolves >= resolves) {
      std::snprintf(buf, sizeof buf,
                    "  hint        %.0f%% of the knit hits were multi-scale footprints of a quarter of a stitch "
                    "cell or more, below table_min_cells, shaded as the near field: \"table_min_cells\": 0.25 "
                    "reads them from the class table (faster, but it keeps the mean of the plies' glints, not "
                    "where each falls: up to 8.5%% over 4x4 pixel blocks from explicit yarns; docs/multiscale.md)\n",
                    100.0 * double(quarter_cell_resolves) / double(resolves));
      s += buf;
    }
    // Near-field mode where pixels span a quarter of a stitch cell or more:
    // multi-scale mode would read those footprints from its class table.
    if (camera_resolves > 0 && 10 * camera_table_footprints >= camera_resolves) {
      std::snprintf(buf, sizeof buf,
                    "  hint        %.0f%% of the camera's knit hits were near-field hits on footprints of a quarter "
                    "of a stitch cell or more (table_min_cells): \"mode\": \"multi_scale\" reads such footprints "
                    "from a class table built once per pattern instead of marching them (4-16x faster than the "
                    "near field at equal quality on the far swatch; it keeps the mean of the plies' glints, not "
                    "where each falls; README, \"Choosing a mode\")\n",
                    100.0 * double(camera_table_footprints) / double(camera_resolves));
      s += buf;
    }
    // Tubes too coarse for their pixels: say how many points they need.
    if (explicit_yarns && coarse_tube_share() >= 0.1 && yarn_samples_min > 0) {
      const int need = yarn_samples_min * tube_samples_factor();
      // (a tenth of the hits or more below the lowest edge: `need` is a floor)
      const bool floor = 10 * tube_spans[0] >= tube_hits();
      const std::string now = yarn_samples_min == yarn_samples_max
                                  ? std::to_string(yarn_samples_min)
                                  : std::to_string(yarn_samples_min) + " to " + std::to_string(yarn_samples_max);
      std::string advice;
      if (need <= KnitDesc::kMaxExplicitSamples)
        advice = "\"explicit_samples\": " + std::string(floor ? "at least " : "") + std::to_string(need) + " (now " +
                 now + ") would give nine tenths of them " + std::to_string(int(kTubeSpanEnough)) + " or more";
      else
        advice = "nine tenths of them would need \"explicit_samples\" of " + std::to_string(need) +
                 " or more (now " + now + "), above its limit of " + std::to_string(KnitDesc::kMaxExplicitSamples) +
                 ": at this many pixels a stitch the tubes' glints are not converged pixel by pixel (compare "
                 "blocks of pixels)";
      std::snprintf(buf, sizeof buf,
                    "  hint        %.0f%% of the camera's hits on yarn tubes were in pixels spanning fewer than %d "
                    "tube segments, where the polylines' corners move the glints (docs/renderer.md, \"Tube "
                    "density\"): %s\n",
                    100.0 * coarse_tube_share(), int(kTubeSpanEnough), advice.c_str());
      s += buf;
    }
    if (explicit_yarns) {
      std::snprintf(buf, sizeof buf,
                    "  yarns       explicit: %zu points, %zu segments, %zu curves (built in %.2f s); geometry %s, "
                    "shading data %s, Embree BVH for them %s\n",
                    yarn_points, yarn_segments, yarn_curves, yarn_build_seconds,
                    format_bytes(static_cast<double>(yarn_geometry_bytes)).c_str(),
                    format_bytes(static_cast<double>(yarn_shading_bytes)).c_str(),
                    format_bytes(static_cast<double>(embree_yarn_bytes)).c_str());
    } else {
      std::snprintf(buf, sizeof buf, "  knit model  %zu material(s): model state %s, per-mesh tables %s\n",
                    knit_materials, format_bytes(static_cast<double>(knit_state_bytes)).c_str(),
                    format_bytes(static_cast<double>(knit_binding_bytes)).c_str());
    }
    s += buf;
  }
  if (invalid_samples > 0 || pass_limit > 0) {
    std::snprintf(buf, sizeof buf, "  problems    %llu invalid (NaN/Inf/negative) samples dropped, %llu paths hit the pass-through limit\n",
                  static_cast<unsigned long long>(invalid_samples), static_cast<unsigned long long>(pass_limit));
    s += buf;
  }
  s += "  output      " + output + "\n";
  return s;
}

uint64_t RenderReport::tube_hits() const { return std::accumulate(tube_spans.begin(), tube_spans.end(), uint64_t(0)); }

double RenderReport::coarse_tube_share() const {
  const uint64_t all = tube_hits();
  uint64_t coarse = 0;
  for (size_t i = 0; i < kTubeSpanEdges.size(); ++i)
    if (kTubeSpanEdges[i] <= kTubeSpanEnough) coarse += tube_spans[i];
  return all ? double(coarse) / double(all) : 0.0;
}

int RenderReport::tube_samples_factor() const {
  const uint64_t all = tube_hits();
  if (all == 0) return 0;
  // The first bin whose hits and those below it make a tenth of the hits or
  // more: nine tenths of the hits span at least its lower edge.
  uint64_t below = 0;
  size_t bin = 0;
  for (; bin < tube_spans.size(); ++bin) {
    below += tube_spans[bin];
    if (10 * below >= all) break;
  }
  const float lower = bin == 0 ? kTubeSpanEdges[0] / 2 : kTubeSpanEdges[bin - 1];
  int factor = 1;
  while (float(factor) * lower < kTubeSpanEnough) factor *= 2;
  return factor;
}

std::string RenderReport::to_json() const {
  nlohmann::ordered_json j;
  j["knitshade_version"] = version;
  j["scene"] = scene;
  j["output"] = output;
  j["width"] = width;
  j["height"] = height;
  j["spp"] = spp;
  j["seed"] = seed;
  j["threads"] = threads;
  j["seconds"] = {{"parse", parse_seconds}, {"knit_tables", knit_table_seconds}, {"load", load_seconds},
                  {"yarns", yarn_build_seconds}, {"build", build_seconds},
                  {"render", render_seconds}, {"write", write_seconds}, {"total", total_seconds}};
  j["knit_tables"] = {{"built", knit_tables_built},
                      {"from_cache", knit_tables_cached},
                      {"finished_from_cached_marches", knit_tables_finished},
                      {"marched_from_cached_shadows", knit_tables_shaded},
                      {"cache_dir", table_cache_dir.empty() ? nlohmann::ordered_json() : nlohmann::ordered_json(table_cache_dir)}};
  j["samples"] = samples;
  j["samples_per_second"] = samples_per_second();
  j["rays"] = {{"camera", camera_rays}, {"bounce", bounce_rays}, {"shadow", shadow_rays}, {"total", total_rays()}};
  j["rays_per_second"] = rays_per_second();
  j["invalid_samples"] = invalid_samples;
  j["pass_through_limit_hits"] = pass_limit;
  j["triangles"] = triangles;
  j["memory_bytes"] = {{"peak_rss", peak_rss_bytes}, {"embree", embree_bytes}, {"embree_peak", embree_peak_bytes},
                       {"meshes", mesh_bytes},
                       {"knit_state", knit_state_bytes},
                       {"knit_binding", knit_binding_bytes},
                       {"yarn_geometry", yarn_geometry_bytes},
                       {"yarn_shading", yarn_shading_bytes},
                       {"embree_yarns", embree_yarn_bytes}};
  j["knit"] = {{"materials", knit_materials}, {"explicit_yarns", explicit_yarns},
               {"hits", resolves}, {"hits_passed", resolve_passes}, {"shadow_crossings", shadow_resolves},
               {"shell_bounces", shell_bounces}, {"table_hits", table_resolves},
               {"sub_cell_hits", sub_cell_resolves}, {"sub_cell_boxes_reused", sub_boxes_reused},
               {"quarter_cell_near_field_hits", quarter_cell_resolves},
               {"camera_hits", camera_resolves}, {"camera_table_footprint_hits", camera_table_footprints},
               {"aggregated_hits", aggregate_resolves}, {"marches_spared", marches_spared},
               {"yarn_points", yarn_points}, {"yarn_segments", yarn_segments}, {"yarn_curves", yarn_curves},
               {"yarn_build_seconds", yarn_build_seconds},
               {"explicit_samples", {{"min", yarn_samples_min}, {"max", yarn_samples_max}}},
               {"tube_pixel_spans", {{"edges", kTubeSpanEdges}, {"camera_hits", tube_spans}}},
               {"coarse_tube_share", coarse_tube_share()},
               {"tube_samples_factor", tube_samples_factor()}};
  return j.dump(2) + "\n";
}

}  // namespace knit::render
