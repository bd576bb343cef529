// Renders a Scene into a float image: tiles in parallel with TBB, one
// independent random stream per (seed, pixel, sample), so the image is a pure
// function of (scene, spp, seed) whatever the number of threads.
#pragma once

#include <cstdint>
#include <vector>

#include "render/image.h"
#include "render/integrator.h"
#include "render/progress.h"
#include "render/scene.h"

namespace knit::render {

struct RenderSettings {
  int spp = 16;
  uint64_t seed = 0;
  int threads = 0;  // 0: every hardware thread
  ProgressMode progress = ProgressMode::Quiet;
  int tile_size = 16;
  // >= 0: render a coverage mask instead of radiance, the fraction of each
  // pixel's camera rays whose first hit is drawn with this material index.
  int mask_material = -1;
};

struct RenderResult {
  RgbImage image;       // linear radiance, exposure not applied
  PathStats stats;
  double seconds = 0;   // wall time of the pixel loop
  int threads = 0;      // threads actually allowed
  uint64_t samples = 0; // width * height * spp
  // First invalid (NaN/Inf/negative) sample, for the message: pixel and sample index.
  int invalid_x = -1, invalid_y = -1;
  int64_t invalid_sample = -1;
};

RenderResult render_image(const Scene& scene, const RenderSettings& settings);

// The order render_image visits its `tiles` tiles in: a fixed pseudo-random
// permutation of 0 .. tiles - 1. The image does not depend on it; the
// progress display does: rendered in raster order, a scene whose costly
// part lies low in the frame (the demo's knits under an empty sky) showed an
// ETA of a quarter of the real time until half of it had passed. Any prefix
// of a shuffled order samples the frame evenly, so the rate of the tiles
// done so far predicts the rest.
std::vector<int> tile_order(int tiles);

}  // namespace knit::render
