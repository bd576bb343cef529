#include "render/renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <numeric>

#include "knit/shading.h"
#include "render/camera.h"
#include "render/rng.h"

namespace knit::render {

RenderResult render_image(const Scene& scene, const RenderSettings& settings) {
  const FilmDesc& film = scene.desc().film;
  const int w = film.width, h = film.height, spp = settings.spp;
  const int ts = std::max(1, settings.tile_size);
  const int tiles_x = (w + ts - 1) / ts, tiles_y = (h + ts - 1) / ts;
  RenderResult result;
  result.image = RgbImage(w, h);
  result.samples = static_cast<uint64_t>(w) * h * spp;
  result.threads = settings.threads > 0 ? settings.threads : tbb::info::default_concurrency();

  const PathIntegrator integrator(scene, scene.desc().integrator);
  const PinholeCamera& camera = scene.camera();
  const float diff_scale = std::max(0.125f, 1.0f / std::sqrt(static_cast<float>(spp)));
  Progress progress(settings.progress, result.samples, "render");
  std::mutex merge;

  auto render_tile = [&](int tile) {
    const int x0 = (tile % tiles_x) * ts, y0 = (tile / tiles_x) * ts;
    const int x1 = std::min(x0 + ts, w), y1 = std::min(y0 + ts, h);
    PathStats stats;
    int bad_x = -1, bad_y = -1;
    int64_t bad_s = -1;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const uint64_t pixel = static_cast<uint64_t>(y) * static_cast<uint64_t>(w) + static_cast<uint64_t>(x);
        double sr = 0, sg = 0, sb = 0;
        knit::FootprintMemo memo;  // the pixel's multi-scale boxes, shared by its samples
        for (int s = 0; s < spp; ++s) {
          Sampler sampler(settings.seed, pixel, static_cast<uint64_t>(s), static_cast<uint32_t>(spp));
          const Vec2 j = sampler.get2d();
          RayDifferential ray = camera.generate(static_cast<float>(x) + j.x, static_cast<float>(y) + j.y, diff_scale);
          ray.pixel_dx = j.x - 0.5f;
          ray.pixel_dy = j.y - 0.5f;
          ray.footprint_memo = &memo;
          Rgb l;
          if (settings.mask_material >= 0) {
            ++stats.camera_rays;
            SurfaceInteraction si;
            l = Rgb(scene.accel().intersect(ray, si) && si.material == settings.mask_material ? 1.0f : 0.0f);
          } else {
            l = integrator.li(ray, sampler, stats);
          }
          if (!l.is_finite() || l.has_negative()) {
            if (stats.invalid_samples == 0) {
              bad_x = x;
              bad_y = y;
              bad_s = s;
            }
            ++stats.invalid_samples;
            continue;  // counted and reported, contributes nothing
          }
          sr += l.r;
          sg += l.g;
          sb += l.b;
        }
        stats.sub_boxes_reused += uint64_t(memo.reused());
        const double inv = 1.0 / spp;
        result.image.at(x, y) = Rgb(static_cast<float>(sr * inv), static_cast<float>(sg * inv), static_cast<float>(sb * inv));
      }
      progress.add(static_cast<uint64_t>(x1 - x0) * spp);
    }
    std::lock_guard<std::mutex> lock(merge);
    result.stats.add(stats);
    // Keep the first invalid sample in raster order, independent of scheduling.
    if (bad_s >= 0 && (result.invalid_y < 0 || bad_y < result.invalid_y ||
                       (bad_y == result.invalid_y && bad_x < result.invalid_x))) {
      result.invalid_x = bad_x;
      result.invalid_y = bad_y;
      result.invalid_sample = bad_s;
    }
  };

  const std::vector<int> order = tile_order(tiles_x * tiles_y);
  const auto t0 = std::chrono::steady_clock::now();
  tbb::task_arena arena(result.threads);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, tiles_x * tiles_y, 1),
                      [&](const tbb::blocked_range<int>& r) {
                        for (int i = r.begin(); i != r.end(); ++i) render_tile(order[size_t(i)]);
                      },
                      tbb::simple_partitioner());
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  return result;
}

std::vector<int> tile_order(int tiles) {
  std::vector<int> order(size_t(std::max(0, tiles)));
  std::iota(order.begin(), order.end(), 0);
  // Fisher-Yates with a fixed splitmix64 stream (std::shuffle's draws differ
  // between standard libraries; this order is the same everywhere).
  uint64_t state = 0x6b6e697473686164ull;
  for (size_t i = order.size(); i > 1; --i) {
    std::swap(order[i - 1], order[size_t(mix64(state) % i)]);
    state += 0x9e3779b97f4a7c15ull;  // the stream: mix64 of key, key + step, key + 2 step, ...
  }
  return order;
}

}  // namespace knit::render
