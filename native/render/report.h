// The render report: timings, throughput, memory. Printed at the end of
// `knitshade render` and written as JSON with --report for benchmarks.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace knit::render {

// Camera hits on explicit yarn tubes are binned by how many of the hit's
// tube segments one pixel spans there (the pixel's cone width over the
// segment's length): bin i < kTubeBins - 1 holds ratios below
// kTubeSpanEdges[i] (and at or above the edge before it), the last bin the
// rest. A tube's polyline cuts the curve's corners, and where a pixel spans
// few segments the glints move with them (docs/renderer.md, "Tube
// density").
inline constexpr std::array<float, 6> kTubeSpanEdges = {0.25f, 0.5f, 1.0f, 2.0f, 4.0f, 8.0f};
inline constexpr int kTubeBins = int(kTubeSpanEdges.size()) + 1;
// Pixels spanning fewer segments than this are counted as too coarse
// (RenderReport's tube-density hint; an edge of kTubeSpanEdges). Measured
// on the two close-up examples at 48 pixels against 256-point tubes
// (1,024 samples): pixels of 0.5-1 segments 13% off per pixel beyond the
// noise, 1-2 segments 3.9% and 5.3%, 2-4 segments within the noise and
// 0.95%, 4-8 within the noise.
inline constexpr float kTubeSpanEnough = 2.0f;


struct RenderReport {
  std::string scene, output, version;
  int width = 0, height = 0, spp = 0, threads = 0;
  uint64_t seed = 0;
  // parse_seconds leaves out knit_table_seconds, the knit materials' class
  // table builds (multi-scale), which happen while the scene is parsed.
  double parse_seconds = 0, knit_table_seconds = 0, load_seconds = 0, build_seconds = 0, render_seconds = 0,
         write_seconds = 0, total_seconds = 0;
  // Knit materials with a class table: built here, read from the class-table
  // cache, finished here from the cache's marches (a material cached with
  // other colours: KnitMaterial::table_marches_from_cache), or marched here
  // from the cache's shadows (cached with other yarn parameters:
  // KnitMaterial::table_shadows_from_cache).
  int knit_tables_built = 0, knit_tables_cached = 0, knit_tables_finished = 0, knit_tables_shaded = 0;
  std::string table_cache_dir;  // the class-table cache's folder; empty: off
  uint64_t samples = 0;
  uint64_t camera_rays = 0, bounce_rays = 0, shadow_rays = 0;
  uint64_t invalid_samples = 0, pass_limit = 0;
  uint64_t resolves = 0, resolve_passes = 0, shadow_resolves = 0, shell_bounces = 0, table_resolves = 0,
           sub_cell_resolves = 0, sub_boxes_reused = 0, aggregate_resolves = 0, marches_spared = 0, quarter_cell_resolves = 0;
  // Camera paths' first hits resolved, and of them the near-field hits
  // whose footprints multi-scale mode would read from its class table
  // (KnitMaterial::table_would_serve): the near field's "mode" hint.
  uint64_t camera_resolves = 0, camera_table_footprints = 0;
  size_t triangles = 0, mesh_bytes = 0;
  int64_t embree_bytes = 0, embree_peak_bytes = 0;
  int64_t peak_rss_bytes = 0;
  // Knit materials: the model's state and the renderer's per-mesh tables.
  size_t knit_materials = 0, knit_state_bytes = 0, knit_binding_bytes = 0;
  // Explicit yarns: tube geometry, per-point shading data, Embree's BVH for them.
  bool explicit_yarns = false;
  size_t yarn_points = 0, yarn_segments = 0, yarn_curves = 0;
  size_t yarn_geometry_bytes = 0, yarn_shading_bytes = 0;
  int64_t embree_yarn_bytes = 0;
  double yarn_build_seconds = 0;
  int yarn_samples_min = 0, yarn_samples_max = 0;  // the knit materials' explicit_samples (tubes' points a stitch)
  std::array<uint64_t, kTubeBins> tube_spans{};  // camera hits on yarn tubes by segments per pixel (kTubeSpanEdges)
  uint64_t tube_hits() const;  // those hits, all bins summed
  // The share of those hits whose pixel spans fewer than kTubeSpanEnough
  // segments, and the factor on explicit_samples that would bring nine
  // tenths of them to kTubeSpanEnough (a power of two; 0 when no hits).
  double coarse_tube_share() const;
  int tube_samples_factor() const;

  uint64_t total_rays() const { return camera_rays + bounce_rays + shadow_rays; }
  double samples_per_second() const { return render_seconds > 0 ? samples / render_seconds : 0; }
  double rays_per_second() const { return render_seconds > 0 ? total_rays() / render_seconds : 0; }

  std::string to_text() const;  // a few human-readable lines
  std::string to_json() const;  // one JSON object (docs/renderer.md#report)
};

// Peak resident set size of this process so far (getrusage), in bytes.
int64_t peak_rss_bytes();

// "12.3 MiB" style.
std::string format_bytes(double bytes);

}  // namespace knit::render
