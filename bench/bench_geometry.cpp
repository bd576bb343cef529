// Geometry benchmarks: the analytic vertical query, CAPM per view angle, and
// a brute-force closest point on the densely sampled curve at equal accuracy.
//
//   build/bench/bench_geometry --benchmark_counters_tabular=true
//
// Counters: q/s (queries per second, single thread), steps (mean CAPM
// segments), zerr_r (mean |z - z_explicit| / r of the method, measured in
// setup against the double-precision explicit-tube ray caster).
#include <benchmark/benchmark.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "knit/shading.h"
#include "knit/surface.h"
#include "knit/table_cache.h"
#include "knit/yarns.h"
#include "../tests/support/groundtruth.h"
#include "../tests/support/test_patterns.h"

namespace {

using namespace knit;

struct Pts {
  std::vector<float> x, y;
};

Pts random_points(const KnitSurface& s, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(0, 1);
  Pts p;
  for (int i = 0; i < n; ++i) {
    p.x.push_back(20 + 60 * U(rng));
    p.y.push_back(20 + 60 * U(rng));
  }
  (void)s;
  return p;
}

void BM_VerticalQuery(benchmark::State& state) {
  const Pattern pat = state.range(0) == 0 ? test::stockinette() : test::pyramid16();
  KnitSurface s(pat, StitchParams{});
  Pts p = random_points(s, 4096, 1);
  size_t i = 0;
  long hits = 0;
  for (auto _ : state) {
    SurfaceHit h = s.query(p.x[i & 4095], p.y[i & 4095]);
    hits += h.hit;
    benchmark::DoNotOptimize(h);
    ++i;
  }
  state.counters["q/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["hit%"] = 100.0 * double(hits) / double(state.iterations());
  state.SetLabel(state.range(0) == 0 ? "stockinette" : "pyramid16");
}
BENCHMARK(BM_VerticalQuery)->Arg(0)->Arg(1);

// The path a batch benchmark's second argument names: 0 the widest the CPU
// has (Auto), 1 the scalar kernel, 2 AVX2. False (and the benchmark skipped
// with the reason) when this CPU cannot run it.
bool batch_path_arg(benchmark::State& state, KnitSurface::BatchPath& path) {
  path = state.range(1) == 1   ? KnitSurface::BatchPath::Scalar
         : state.range(1) == 2 ? KnitSurface::BatchPath::Avx2
                               : KnitSurface::BatchPath::Auto;
  if (path == KnitSurface::BatchPath::Avx2 && !KnitSurface::batch_simd_available()) {
    state.SkipWithError("this CPU has no AVX2 with FMA");
    return false;
  }
  return true;
}

// The same queries through KnitSurface::query_batch, 4096 points per call
// (AVX-512, 16 points at a time, or AVX2, 8 at a time, whichever the CPU
// has: the label says which path ran). A second argument of 1 forces the
// scalar path and 2 the AVX2 one, for the ratios in one run.
void BM_VerticalQueryBatch(benchmark::State& state) {
  const Pattern pat = state.range(0) == 0 ? test::stockinette() : test::pyramid16();
  KnitSurface s(pat, StitchParams{});
  Pts p = random_points(s, 4096, 1);
  std::vector<SurfaceHit> out(4096);
  KnitSurface::BatchPath path;
  if (!batch_path_arg(state, path)) return;
  long hits = 0;
  for (auto _ : state) {
    s.query_batch(p.x.data(), p.y.data(), 4096, out.data(), path);
    hits += out[0].hit;
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  state.counters["q/s"] = benchmark::Counter(4096.0 * double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["ns/pt"] = benchmark::Counter(4096.0 * double(state.iterations()),
                                               benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(std::string(state.range(0) == 0 ? "stockinette" : "pyramid16") +
                 " " + KnitSurface::batch_isa_name(s.batch_isa(path)));
}
// With --benchmark_repetitions=N, a "_min" row besides the mean and median:
// the fastest repetition's time and ns/pt (its q/s column is the slowest's,
// the statistic being taken column by column). On a shared machine whose
// speed drifts by 10-30% between runs, the fastest of many short
// repetitions is the figure that repeats (within about 2% here, against
// 10% for the median); compare builds by alternating them.
double fastest(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
BENCHMARK(BM_VerticalQueryBatch)->ArgsProduct({{0, 1}, {0, 1, 2}})->ComputeStatistics("min", fastest);

// Small calls (the first argument is the points per call, as Python's
// query of a few points makes them): the vector paths' fixed cost per call
// against the scalar kernel's. Second argument as above; ns per point.
void BM_VerticalQueryBatchSmall(benchmark::State& state) {
  KnitSurface s(test::stockinette(), StitchParams{});
  Pts p = random_points(s, 4096, 1);
  const int n = int(state.range(0));
  KnitSurface::BatchPath path;
  if (!batch_path_arg(state, path)) return;
  std::vector<SurfaceHit> out(static_cast<size_t>(n));
  size_t i = 0;
  for (auto _ : state) {
    s.query_batch(p.x.data() + i, p.y.data() + i, size_t(n), out.data(), path);
    benchmark::DoNotOptimize(out.data());
    i = (i + size_t(n)) % (4096 - 64);
  }
  state.counters["ns/pt"] = benchmark::Counter(double(n) * double(state.iterations()),
                                               benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(KnitSurface::batch_isa_name(s.batch_isa(path)));
}
BENCHMARK(BM_VerticalQueryBatchSmall)->ArgsProduct({{1, 2, 4, 16, 32, 48, 64, 128, 256}, {0, 1, 2}});

// The kernel call alone (no SurfaceHit conversion, no layer count).
void BM_KernelLineQuery(benchmark::State& state) {
  KnitSurface s(test::stockinette(), StitchParams{});
  Pts p = random_points(s, 4096, 2);
  size_t i = 0;
  for (auto _ : state) {
    k::KnitLineHit h = k::knit_vertical_query(s.geom(), s.codes(), s.colors(), p.x[i & 4095], p.y[i & 4095]);
    benchmark::DoNotOptimize(h);
    ++i;
  }
  state.counters["q/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_KernelLineQuery);

void BM_Capm(benchmark::State& state) {
  const double theta = double(state.range(0)) * 3.14159265358979 / 180;
  KnitSurface s(test::seed(), StitchParams{});
  Pts p = random_points(s, 4096, 3);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> U(0, 6.2831853f);
  std::vector<Vec3> wi;
  for (int i = 0; i < 4096; ++i) {
    const float ph = U(rng);
    wi.push_back(k::kv3(float(std::sin(theta) * std::cos(ph)), float(std::sin(theta) * std::sin(ph)),
                        float(std::cos(theta))));
  }
  std::unique_ptr<FrameProvider> frame;
  if (state.range(1) > 0) frame = std::make_unique<CylinderFrame>(float(state.range(1)));
  size_t i = 0;
  long steps = 0;
  for (auto _ : state) {
    SurfaceHit h = s.capm(p.x[i & 4095], p.y[i & 4095], wi[i & 4095], frame.get());
    steps += h.steps;
    benchmark::DoNotOptimize(h);
    ++i;
  }
  state.counters["rays/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["steps"] = double(steps) / double(state.iterations());
  state.SetLabel(state.range(1) > 0 ? "cylinder" : "flat");
}
BENCHMARK(BM_Capm)->ArgsProduct({{0, 45, 75, 85}, {0, 80}});

// Brute force: the curve sampled with N points per stitch (tabulated once,
// one pattern period, pattern codes baked in); a query scans the samples of
// the rows and t-window that can reach (x, y) and keeps the highest
// z + sqrt(r^2 - rho^2).
class SampledCurves {
 public:
  SampledCurves(const Pattern& pat, const StitchParams& sp, int per_stitch)
      : sp_(sp), n_(per_stitch), rows_(pat.rows()), cols_(pat.cols()) {
    const double two_pi = 6.283185307179586;
    pts_.resize(size_t(rows_) * size_t(cols_) * size_t(n_));
    for (int k = 0; k < rows_; ++k)
      for (int i = 0; i < cols_ * n_; ++i) {
        CurvePoint c = yarn_curve_exact(pat, sp, k, two_pi * double(i) / n_);
        pts_[size_t(k) * size_t(cols_ * n_) + size_t(i)] = {float(c.p[0]), float(c.p[1]), float(c.p[2])};
      }
  }
  float top(float x, float y) const {
    const float two_pi = 6.2831853f, s = sp_.h + 0.5f, r2 = sp_.r * sp_.r;
    const int k0 = int(std::ceil((y - sp_.h - sp_.r) / s - 0.5f)), k1 = int(std::floor((y + sp_.h + sp_.r) / s - 0.5f));
    const float tmin = x - sp_.r - sp_.a, tmax = x + sp_.r + sp_.a;
    const int i0 = int(std::floor(tmin / two_pi * float(n_))), i1 = int(std::ceil(tmax / two_pi * float(n_)));
    float best = -1e30f;
    const int per_row = cols_ * n_;
    for (int k = k0; k <= k1; ++k) {
      const int kk = ((k % rows_) + rows_) % rows_;
      const float dy = float(k - kk) * s;
      for (int i = i0; i <= i1; ++i) {
        const int ii = ((i % per_row) + per_row) % per_row;
        const float dx = float(i - ii) / float(n_) * two_pi;
        const auto& q = pts_[size_t(kk) * size_t(per_row) + size_t(ii)];
        const float ex = q[0] + dx - x, ey = q[1] + dy - y, rho2 = ex * ex + ey * ey;
        if (rho2 < r2) best = std::max(best, q[2] + std::sqrt(r2 - rho2));
      }
    }
    return best;
  }

 private:
  StitchParams sp_;
  int n_, rows_, cols_;
  std::vector<std::array<float, 3>> pts_;
};

// Mean |z - z_truth| / r of both methods on the same points, against the
// explicit-tube ray caster.
double mean_err(const test::GroundTruthScene& sc, const SampledCurves* bf) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> U(0, 1);
  double sum = 0;
  int n = 0;
  for (int i = 0; i < 3000; ++i) {
    const double x = sc.x0 + (sc.x1 - sc.x0) * U(rng), y = sc.y0 + (sc.y1 - sc.y0) * U(rng);
    const test::TubeHit gt = sc.tubes.intersect({x, y, 10}, {0, 0, -1}, 0, 100);
    if (!gt.hit) continue;
    const float z = bf ? bf->top(float(x), float(y)) : sc.surface.query(float(x), float(y)).position.z;
    if (z < -1e29f) continue;
    sum += std::abs(double(z) - gt.p[2]);
    ++n;
  }
  return sum / n / double(sc.surface.params().r);
}

void BM_BruteForceSampled(benchmark::State& state) {
  const int per_stitch = int(state.range(0));
  StitchParams sp;
  static test::GroundTruthScene* sc = new test::GroundTruthScene(test::stockinette(), sp, 0, 8);
  SampledCurves bf(test::stockinette(), sp, per_stitch);
  Pts p = random_points(sc->surface, 4096, 1);
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(bf.top(p.x[i & 4095], p.y[i & 4095]));
    ++i;
  }
  state.counters["q/s"] = benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  state.counters["zerr_r"] = mean_err(*sc, &bf);
  state.counters["analytic_zerr_r"] = mean_err(*sc, nullptr);
}
BENCHMARK(BM_BruteForceSampled)->Arg(64)->Arg(256)->Arg(1024)->Arg(4096);

// Multi-scale aggregation per shading point, by footprint points; footprint
// of half a stitch (plain Sobol' placement) and of 4 stitches (cell-stratified,
// the point count grows with the cells covered).
void BM_Aggregate(benchmark::State& state) {
  KnitSurface s(test::seed(), StitchParams{});
  Pts p = random_points(s, 4096, 5);
  const int npts = int(state.range(0));
  const float size = float(state.range(1)) * 6.2832f / 2;
  const k::kvec3 wi = k::kv3_normalize(k::kv3(0.3f, 0.2f, 0.93f));
  size_t i = 0;
  double used = 0;
  for (auto _ : state) {
    const k::KnitAggregate a =
        k::knit_aggregate(s.geom(), s.codes(), s.colors(), p.x[i & 4095], p.y[i & 4095], k::kv3(size, 0, 0),
                          k::kv3(0, size, 0), wi, npts, 0.3f, 0.6f, 0, 0, 6.2832f, 32);
    used += a.points;
    benchmark::DoNotOptimize(a);
    ++i;
  }
  state.counters["points"] = used / double(state.iterations());
  state.counters["ns/point"] =
      benchmark::Counter(used, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.SetLabel(state.range(1) == 1 ? "half-stitch footprint" : "4-stitch footprint");
}
BENCHMARK(BM_Aggregate)->ArgsProduct({{4, 8, 16, 32}, {1, 8}});

// A multi-scale material's construction, which builds its class table and
// tabulated BSDF (arg 0), or reads them from the class-table cache (arg 1;
// knit/table_cache.h): the seed stitch, two classes. Every hardware thread
// builds; the read is one thread's. Run both in one go for their ratio:
// --benchmark_filter=BM_ClassTables
void BM_ClassTables(benchmark::State& state) {
  namespace fs = std::filesystem;
  const bool cached = state.range(0) == 1;
  const fs::path dir = fs::temp_directory_path() / ("knitshade-bench-cache-" + std::to_string(long(getpid())));
  KnitMaterialParams mp;
  mp.mode = KnitMode::MultiScale;
  const Pattern seed = test::seed();
  if (cached) {
    set_table_cache({dir.string()});
    const KnitMaterial warm(seed, mp);  // (writes the entry)
  }
  double seconds = 0;
  bool all_cached = true;
  for (auto _ : state) {
    const KnitMaterial m(seed, mp);
    seconds += m.table_seconds();
    all_cached = all_cached && m.table_from_cache() == cached;
    benchmark::DoNotOptimize(m.footprint_table());
  }
  set_table_cache({});
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (!all_cached) state.SkipWithError(cached ? "an entry was not read from the cache" : "a table came from a cache");
  state.counters["table_ms"] = 1e3 * seconds / double(state.iterations());
  state.SetLabel(cached ? "read from the class-table cache" : "built");
}
BENCHMARK(BM_ClassTables)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
