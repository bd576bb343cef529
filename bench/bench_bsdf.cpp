// Cost of the near-field yarn BSDF: eval and sample per lobe and for the whole
// mixture, pdf, the ply profile (table lookup vs closed form), the validated
// host wrapper, and the closure weights the Cycles option (and the OSL shader)
// computes per shading point. Directions and random numbers cycle through
// precomputed arrays, so the figures are the kernel's cost per call.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "knit/bsdf.h"
#include "knit/ply_profile.h"

namespace {

using namespace knit;

constexpr int kN = 4096;  // power of two

struct Inputs {
  std::vector<Vec3> wo, wi;
  std::vector<float> u1, u2, u0;
  Inputs() {
    uint64_t s = 12345;
    auto next = [&]() {
      s = s * 6364136223846793005ull + 1442695040888963407ull;
      return float((s >> 40) & 0xFFFFFF) / 16777216.0f;
    };
    auto dir = [&]() {
      float z = 1.f - 2.f * next(), p = 6.2831853f * next(), r = std::sqrt(std::max(0.f, 1.f - z * z));
      return Vec3{r * std::cos(p), r * std::sin(p), z};
    };
    for (int i = 0; i < kN; ++i) {
      Vec3 o = dir();
      if (o.z < 0) o.z = -o.z;  // viewer above; wi on both sides
      wo.push_back(o);
      wi.push_back(dir());
      u0.push_back(next());
      u1.push_back(next());
      u2.push_back(next());
    }
  }
};

const Inputs& inputs() {
  static const Inputs in;
  return in;
}

k::KYarnBsdf yarn() {
  return k::yarn_bsdf_make(k::bsdf_mf_make(0.15f, 0.45f, 1.55f), k::bsdf_mf_make(0.3f, 0.6f, 1.55f),
                           Vec3{0.8f, 0.6f, 0.4f}, Vec3{0.7f, 0.5f, 0.3f}, 0.7f, 0.6f, 0.9f,
                           k::bsdf_att_make(1.f, 1));
}

template <class F>
void run(benchmark::State& state, F f) {
  const Inputs& in = inputs();
  int i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f(in, i));
    i = (i + 1) & (kN - 1);
  }
  state.SetItemsProcessed(state.iterations());
}

// ---- Lobes ------------------------------------------------------------------

void BM_SpecularR_Eval(benchmark::State& st) {
  k::KMicrofacet m = k::bsdf_mf_make(0.15f, 0.45f, 1.55f);
  run(st, [&](const Inputs& in, int i) { return k::bsdf_mf_reflect_eval(m, in.wo[i], in.wi[i]); });
}
void BM_SpecularR_Sample(benchmark::State& st) {
  k::KMicrofacet m = k::bsdf_mf_make(0.15f, 0.45f, 1.55f);
  run(st, [&](const Inputs& in, int i) { return k::bsdf_mf_reflect_sample(m, in.wo[i], in.u1[i], in.u2[i]); });
}
void BM_SpecularT_Eval(benchmark::State& st) {
  k::KMicrofacet m = k::bsdf_mf_make(0.3f, 0.6f, 1.55f);
  run(st, [&](const Inputs& in, int i) { return k::bsdf_mf_transmit_eval(m, in.wo[i], in.wi[i]); });
}
void BM_SpecularT_Sample(benchmark::State& st) {
  k::KMicrofacet m = k::bsdf_mf_make(0.3f, 0.6f, 1.55f);
  run(st, [&](const Inputs& in, int i) { return k::bsdf_mf_transmit_sample(m, in.wo[i], in.u1[i], in.u2[i]); });
}
void BM_BodyR_LommelSeeliger_Eval(benchmark::State& st) {
  k::KLommelSeeliger l = k::bsdf_ls_make(Vec3{0.8f, 0.6f, 0.4f});
  run(st, [&](const Inputs& in, int i) { return k::bsdf_ls_eval(l, in.wo[i], in.wi[i]); });
}
void BM_BodyR_LommelSeeliger_Sample(benchmark::State& st) {
  k::KLommelSeeliger l = k::bsdf_ls_make(Vec3{0.8f, 0.6f, 0.4f});
  run(st, [&](const Inputs& in, int i) { return k::bsdf_ls_sample(l, in.wo[i], in.u1[i], in.u2[i]); });
}
void BM_BodyT_Lambert_Eval(benchmark::State& st) {
  k::KLambertTransmission l = k::bsdf_lt_make(Vec3{0.7f, 0.5f, 0.3f});
  run(st, [&](const Inputs& in, int i) { return k::bsdf_lt_eval(l, in.wo[i], in.wi[i]); });
}
void BM_BodyT_Lambert_Sample(benchmark::State& st) {
  k::KLambertTransmission l = k::bsdf_lt_make(Vec3{0.7f, 0.5f, 0.3f});
  run(st, [&](const Inputs& in, int i) { return k::bsdf_lt_sample(l, in.wo[i], in.u1[i], in.u2[i]); });
}
void BM_Attenuation_Tau(benchmark::State& st) {
  k::KAttenuation a = k::bsdf_att_make(1.f, 2);
  run(st, [&](const Inputs& in, int i) { return k::bsdf_att_tau(a, in.wo[i], in.wi[i]); });
}

// ---- Whole BSDF (Eq. 1) ---------------------------------------------------------

void BM_Yarn_Eval(benchmark::State& st) {
  k::KYarnBsdf y = yarn();
  run(st, [&](const Inputs& in, int i) { return k::yarn_bsdf_eval(y, in.wo[i], in.wi[i]); });
}
void BM_Yarn_Pdf(benchmark::State& st) {
  k::KYarnBsdf y = yarn();
  run(st, [&](const Inputs& in, int i) { return k::yarn_bsdf_pdf(y, in.wo[i], in.wi[i]); });
}
void BM_Yarn_Sample(benchmark::State& st) {
  k::KYarnBsdf y = yarn();
  run(st, [&](const Inputs& in, int i) { return k::yarn_bsdf_sample(y, in.wo[i], in.u1[i], in.u2[i]); });
}
void BM_Yarn_SampleWithGaps(benchmark::State& st) {
  k::KYarnBsdf y = yarn();
  run(st, [&](const Inputs& in, int i) {
    return k::yarn_bsdf_sample_gaps(y, 0.2f, in.wo[i], in.u0[i], in.u1[i], in.u2[i]);
  });
}
void BM_Yarn_HostEval(benchmark::State& st) {
  YarnBsdf b;
  BsdfPoint pt;
  run(st, [&](const Inputs& in, int i) { return b.eval(in.wo[i], in.wi[i], pt); });
}

// ---- As Cycles renders it (bsdf_cycles.h): what the shader computes per point --

void BM_Cycles_Make(benchmark::State& st) {
  k::KYarnBsdf y = yarn();
  run(st, [&](const Inputs& in, int i) { return k::yarn_cycles_make(y, in.wo[i]).w.spec; });
}
void BM_Cycles_VndfMeans(benchmark::State& st) {
  run(st, [&](const Inputs& in, int i) { return k::bsdf_cycles_vndf_means(0.3f, 0.6f, in.wo[i], 1.55f, 1.f); });
}
void BM_Cycles_TransmitMean(benchmark::State& st) {
  run(st, [&](const Inputs& in, int i) { return k::bsdf_cycles_transmit_mean(0.5f + in.u1[i], 1.55f); });
}

// ---- Ply profile --------------------------------------------------------------

void BM_Ply_TableLookup(benchmark::State& st) {
  PlyProfile p;
  run(st, [&](const Inputs& in, int i) { return p.lookup(6.2831853f * in.u1[i], 10.f * in.u2[i]); });
}
void BM_Ply_Procedural(benchmark::State& st) {
  PlyProfile p;
  run(st, [&](const Inputs& in, int i) { return p.procedural(6.2831853f * in.u1[i], 10.f * in.u2[i]); });
}
void BM_Ply_BuildTable(benchmark::State& st) {
  PlyParams pp;
  for (auto _ : st) benchmark::DoNotOptimize(PlyProfile(pp));
}

BENCHMARK(BM_SpecularR_Eval);
BENCHMARK(BM_SpecularR_Sample);
BENCHMARK(BM_SpecularT_Eval);
BENCHMARK(BM_SpecularT_Sample);
BENCHMARK(BM_BodyR_LommelSeeliger_Eval);
BENCHMARK(BM_BodyR_LommelSeeliger_Sample);
BENCHMARK(BM_BodyT_Lambert_Eval);
BENCHMARK(BM_BodyT_Lambert_Sample);
BENCHMARK(BM_Attenuation_Tau);
BENCHMARK(BM_Yarn_Eval);
BENCHMARK(BM_Yarn_Pdf);
BENCHMARK(BM_Yarn_Sample);
BENCHMARK(BM_Yarn_SampleWithGaps);
BENCHMARK(BM_Yarn_HostEval);
BENCHMARK(BM_Cycles_Make);
BENCHMARK(BM_Cycles_VndfMeans);
BENCHMARK(BM_Cycles_TransmitMean);
BENCHMARK(BM_Ply_TableLookup);
BENCHMARK(BM_Ply_Procedural);
BENCHMARK(BM_Ply_BuildTable);

}  // namespace

BENCHMARK_MAIN();
