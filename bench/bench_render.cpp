// Renderer throughput: camera samples per second on the demo scene at low
// resolution, and raw closest-hit rays per second on its geometry.
//   ./bench/bench_render [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include "render/renderer.h"
#include "render/rng.h"
#include "render/sampling.h"
#include "render/scene.h"

namespace {

using namespace knit::render;

const Scene& demo_scene() {
  static SceneDesc desc = [] {
    SceneDesc d = load_scene_file(std::string(KNIT_SOURCE_DIR) + "/examples/scenes/demo.json");
    d.film.width = 160;
    d.film.height = 90;
    return d;
  }();
  static Warnings warnings;
  static const Scene scene(desc, BuildOptions{}, warnings);
  return scene;
}

void BM_RenderDemo(benchmark::State& state) {
  const Scene& scene = demo_scene();
  RenderSettings s;
  s.spp = 4;
  s.threads = static_cast<int>(state.range(0));
  uint64_t samples = 0, rays = 0;
  for (auto _ : state) {
    const RenderResult r = render_image(scene, s);
    samples += r.samples;
    rays += r.stats.total_rays();
    benchmark::DoNotOptimize(r.image.pixels.data());
  }
  state.counters["samples/s"] = benchmark::Counter(static_cast<double>(samples), benchmark::Counter::kIsRate);
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderDemo)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ClosestHit(benchmark::State& state) {
  const Scene& scene = demo_scene();
  Pcg32 rng(1, 2);
  uint64_t n = 0;
  for (auto _ : state) {
    RayDifferential ray;
    ray.o = {rng.next_float() * 2 - 1, 0.5f + rng.next_float(), 2.0f};
    ray.d = sample_uniform_sphere({rng.next_float(), rng.next_float()});
    SurfaceInteraction si;
    benchmark::DoNotOptimize(scene.accel().intersect(ray, si));
    ++n;
  }
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ClosestHit);

}  // namespace

BENCHMARK_MAIN();
