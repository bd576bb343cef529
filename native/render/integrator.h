// Unidirectional path tracer with next-event estimation and multiple
// importance sampling (power heuristic) between light sampling and BSDF
// sampling, Russian roulette, pass-through surfaces and ray differentials.
// See docs/renderer.md#integrator.
#pragma once

#include <array>
#include <cstdint>

#include "render/report.h"
#include "render/rng.h"
#include "render/scene.h"

namespace knit::render {

// Counters of one thread's work; summed after rendering (sums are exact, so
// the totals do not depend on the thread count either).
struct PathStats {
  uint64_t camera_rays = 0;
  uint64_t bounce_rays = 0;     // continuation rays, pass-through continuations included
  uint64_t shadow_rays = 0;     // NEE visibility rays (each surface crossing counts one)
  uint64_t invalid_samples = 0; // NaN, Inf or negative radiance; dropped and reported
  uint64_t pass_limit = 0;      // paths stopped by the pass-through safety limit
  uint64_t resolves = 0;        // hits resolved by a material (knit model: shade(); explicit yarns)
  uint64_t resolve_passes = 0;  // ... of which passed straight on
  uint64_t shadow_resolves = 0; // shadow-ray crossings of such materials (knit model: transmittance())
  uint64_t shell_bounces = 0;   // bounces that met yarn again inside the same shell (no scene ray)
  uint64_t table_resolves = 0;  // resolves the knit model read from its multi-scale class table
  uint64_t sub_cell_resolves = 0;  // ... of which from its sub-cells
  uint64_t sub_boxes_reused = 0;   // ... of which took their box from the pixel's knit::FootprintMemo
  uint64_t quarter_cell_resolves = 0;  // multi-scale near-field resolves of a quarter cell or more (KnitShade::quarter_cell)
  uint64_t aggregate_resolves = 0;  // resolves the knit model aggregated over marched footprint points
  uint64_t camera_resolves = 0;  // resolves of camera paths' first hits (depth 0)
  uint64_t camera_table_footprints = 0;  // ... in near-field mode, of footprints multi-scale would read from its table
  uint64_t marches_spared = 0;  // light samples from inside a yarn shell that an opaque object blocked
                                // (Accel::occluded_by_blockers): no self-shadowing march
  std::array<uint64_t, kTubeBins> tube_spans{};  // camera hits on yarn tubes by segments per pixel (kTubeSpanEdges)

  void add(const PathStats& o) {
    camera_rays += o.camera_rays;
    bounce_rays += o.bounce_rays;
    shadow_rays += o.shadow_rays;
    invalid_samples += o.invalid_samples;
    pass_limit += o.pass_limit;
    resolves += o.resolves;
    resolve_passes += o.resolve_passes;
    shadow_resolves += o.shadow_resolves;
    shell_bounces += o.shell_bounces;
    table_resolves += o.table_resolves;
    sub_cell_resolves += o.sub_cell_resolves;
    sub_boxes_reused += o.sub_boxes_reused;
    quarter_cell_resolves += o.quarter_cell_resolves;
    aggregate_resolves += o.aggregate_resolves;
    camera_resolves += o.camera_resolves;
    camera_table_footprints += o.camera_table_footprints;
    marches_spared += o.marches_spared;
    for (size_t i = 0; i < tube_spans.size(); ++i) tube_spans[i] += o.tube_spans[i];
  }
  uint64_t total_rays() const { return camera_rays + bounce_rays + shadow_rays; }
};

class PathIntegrator {
 public:
  // Straight-through crossings of one path (or one shadow ray) beyond which it
  // is stopped and counted in PathStats::pass_limit.
  static constexpr int kMaxPassThrough = 256;

  PathIntegrator(const Scene& scene, const IntegratorDesc& settings)
      : scene_(scene), settings_(settings) {}

  // Radiance arriving along the camera ray (counted as a camera ray).
  Rgb li(RayDifferential ray, Sampler& sampler, PathStats& stats) const;

  // Transmittance from `origin` along unit `dir` up to `tmax` (inf for
  // infinite lights): 0 when blocked, the product of pass-through
  // transmittances otherwise.
  // Stochastic transmittances (the knit model) draw from `sampler`.
  // cone_width, cone_spread: the path's ray cone at the origin
  // (RayDifferential), for materials that shade by footprint.
  Rgb shadow_transmittance(Vec3 origin, Vec3 dir, float tmax, PathStats& stats, Sampler& sampler,
                           float cone_width = 0, float cone_spread = 0) const;

 private:
  const Scene& scene_;
  IntegratorDesc settings_;
};

// Origin for a ray leaving the surface point `p` (geometric normal `ng`) in
// direction `d`: offset along the normal to the side `d` goes, scaled with
// the magnitude of p to stay clear of the surface's rounding error.
Vec3 offset_ray_origin(Vec3 p, Vec3 ng, Vec3 d);

}  // namespace knit::render
