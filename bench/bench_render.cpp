// Renderer throughput: camera samples per second on the demo scene at low
// resolution, raw closest-hit rays per second on its geometry, and the cost
// of one camera hit on knit fabric with the model and as explicit yarns.
//   ./bench/bench_render [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <map>
#include <memory>

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

// The knit model's cost per camera hit: Accel::intersect + Material::resolve
// (KnitMaterial::shade) on the base mesh, against intersecting the explicit
// yarn tubes of the same scene. Arg 0: half cylinder far view (curved, exact
// frames), 1: the same with frames "curvature", 2: flat swatch close-up,
// 3: flat swatch far view (multi-scale).
struct KnitCase {
  std::unique_ptr<Scene> model, tubes;
  std::vector<RayDifferential> rays;  // camera rays that hit the fabric
};

const KnitCase& knit_case(int which) {
  static std::map<int, KnitCase> cache;
  auto it = cache.find(which);
  if (it != cache.end()) return it->second;
  const char* files[] = {"half_cylinder_front.json", "half_cylinder_front.json", "swatch_closeup.json",
                         "swatch_far.json"};
  SceneDesc d = load_scene_file(std::string(KNIT_SOURCE_DIR) + "/examples/scenes/" + files[which]);
  d.film.width = d.film.height = 128;
  if (which == 1)
    for (MaterialDesc& m : d.materials)
      if (m.type == MaterialType::Knit) m.knit.frames = KnitFrames::Curvature;
  KnitCase& c = cache[which];
  static Warnings warnings;
  c.model = std::make_unique<Scene>(d, BuildOptions{}, warnings);
  BuildOptions tubes;
  tubes.explicit_yarns = true;
  c.tubes = std::make_unique<Scene>(d, tubes, warnings);
  Pcg32 rng(7, 9);
  while (c.rays.size() < 4096) {
    const RayDifferential ray = c.model->camera().generate(rng.next_float() * 128, rng.next_float() * 128, 1.0f);
    SurfaceInteraction si;
    if (c.model->accel().intersect(ray, si) && si.material >= 0 && c.model->material(si.material).resolves_hits())
      c.rays.push_back(ray);
  }
  return c;
}

void BM_KnitModelHit(benchmark::State& state) {
  const KnitCase& c = knit_case(static_cast<int>(state.range(0)));
  size_t i = 0;
  uint64_t passed = 0, n = 0;
  for (auto _ : state) {
    const RayDifferential& ray = c.rays[i++ % c.rays.size()];
    SurfaceInteraction si;
    c.model->accel().intersect(ray, si);
    Sampler sampler(1, i, 0);
    const PassThrough pt = c.model->material(si.material).resolve(si, ray, sampler);
    passed += pt.pass;
    ++n;
    benchmark::DoNotOptimize(si.yarn.bsdf);
  }
  state.counters["hits/s"] = benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsRate);
  state.counters["passed%"] = 100.0 * static_cast<double>(passed) / static_cast<double>(n);
}
BENCHMARK(BM_KnitModelHit)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

void BM_KnitExplicitHit(benchmark::State& state) {
  const KnitCase& c = knit_case(static_cast<int>(state.range(0)));
  size_t i = 0;
  uint64_t n = 0;
  for (auto _ : state) {
    const RayDifferential& ray = c.rays[i++ % c.rays.size()];
    SurfaceInteraction si;
    const bool hit = c.tubes->accel().intersect(ray, si);
    if (hit && si.material >= 0) {
      Sampler sampler(1, i, 0);
      c.tubes->material(si.material).resolve(si, ray, sampler);
    }
    ++n;
    benchmark::DoNotOptimize(si.yarn.bsdf);
  }
  state.counters["hits/s"] = benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_KnitExplicitHit)->DenseRange(0, 3)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
