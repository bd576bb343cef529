#include "knit/aggregate_table.h"

#include <tbb/parallel_for.h>

#include "knit/table_progress.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

namespace knit {

namespace {

constexpr float kPi = 3.14159265358979f;

Vec3 direction(int it, int ip) {
  const float th = float(it) * kPi / float(FootprintTable::kThetaBins - 1);
  const float ph = float(ip) * 2 * kPi / float(FootprintTable::kPhiBins);
  return k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
}

// s[i] += w m[i] for i < n, n a multiple of 4: four lanes at a time where
// the compiler has vector types (GCC and Clang: it does not vectorise this
// sum unrolled inside the class loop by itself).
template <int n>
inline void add_scaled(float* s, const float* m, float w) {
  static_assert(n % 4 == 0, "whole vectors");
#if defined(__GNUC__)
  typedef float v4 __attribute__((vector_size(16), aligned(4)));
  for (int i = 0; i < n; i += 4) {
    v4 a, b;
    std::memcpy(&a, s + i, sizeof a);
    std::memcpy(&b, m + i, sizeof b);
    a += w * b;
    std::memcpy(s + i, &a, sizeof a);
  }
#else
  for (int i = 0; i < n; ++i) s[i] += w * m[i];
#endif
}

}  // namespace

namespace {

// A float's bfloat16: its upper 16 bits, rounded to nearest (ties to even);
// the statistics are finite.
uint16_t to_bf16(float v) {
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits += 0x7fffu + ((bits >> 16) & 1u);
  return uint16_t(bits >> 16);
}

// p_delta of `hits` out of `cells` (1 for no cells), kept a probability.
float pass_fraction(double hits, double cells) {
  return cells > 0 ? std::clamp(float(1 - hits / cells), 0.0f, 1.0f) : 1.0f;
}

// Adds tangent t to a sum of tangents: lines, not arrows, so t is turned
// to the side of the sum so far.
Vec3 add_line(Vec3 sum, Vec3 t) { return k::kv3_dot(sum, t) < 0 ? k::kv3_sub(sum, t) : k::kv3_add(sum, t); }

}  // namespace

int FootprintTable::cell_class(const KnitSurface& surface, int k, int c) {
  const k::KnitGeom& g = surface.geom();
  const k::KCell cl = k::knit_cell(g, surface.codes(), k::knit_row(g, k), c);
  if (cl.code == KNIT_CODE_FRONT) return 8;
  if (cl.code == KNIT_CODE_BACK) return 9;
  return (cl.code == KNIT_CODE_PURL ? 4 : 0) + (cl.sg.x < 0 ? 2 : 0) + (cl.sg.z < 0 ? 1 : 0);
}

FootprintTable::ClassCells FootprintTable::class_cells(const KnitSurface& surface) {
  const k::KnitGeom& g = surface.geom();
  // For large patterns a uniform sample of at most kMaxCells of them
  // (reservoir sampling, fixed seed), enough for the rays of one direction
  // and bounded in memory for a 4096 x 4096 pattern.
  constexpr size_t kMaxCells = 1024;
  ClassCells cells;
  std::array<size_t, kClasses> seen{};
  std::mt19937 rng(12345);
  for (int k = 0; k < g.rows; ++k)
    for (int c = 0; c < g.cols; ++c) {
      const size_t cls = size_t(cell_class(surface, k, c));
      const size_t n = seen[cls]++;
      if (n < kMaxCells) {
        cells[cls].emplace_back(k, c);
      } else {
        const size_t j = std::uniform_int_distribution<size_t>(0, n)(rng);
        if (j < kMaxCells) cells[cls][j] = {k, c};
      }
    }
  return cells;
}

std::array<double, FootprintTable::kClasses> FootprintTable::class_cell_counts() const {
  std::array<size_t, 256> n{};
  for (unsigned char c : class_of_) ++n[c];
  std::array<double, kClasses> counts{};
  for (int i = 0; i < kClasses; ++i) counts[size_t(i)] = double(n[size_t(i)]);
  return counts;
}

Vec3 FootprintTable::ray_origin(const k::KnitGeom& g, const std::pair<int, int>& cell, int node, int rays, int m,
                                int* sub, int* eighth) {
  // The point inside the cell from a (0,2)-net: each run of 4^j of its
  // points puts the same number in every sub-cell (and of 64 or more, in
  // every eighth). An eighth lies in one sub-cell: ox * 8 is ox * 4 doubled.
  const Vec3 q = k::knit_sobol2(node * rays + m);  // other points per direction
  const float ox = k::knit_frac(q.x + 0.5f), oy = k::knit_frac(q.y + 0.5f);
  if (sub) *sub = std::min(int(oy * kSub), kSub - 1) * kSub + std::min(int(ox * kSub), kSub - 1);
  if (eighth)
    *eighth = std::min(int(oy * kEighth), kEighth - 1) * kEighth + std::min(int(ox * kEighth), kEighth - 1);
  return k::kv3((float(cell.second) + ox) * K_2PI, (float(cell.first) + oy) * g.row_spacing, 0);
}

FootprintTable::FootprintTable(const KnitSurface& surface, const CapmOptions& capm, int rays_per_direction,
                               LayerCounts layer_counts, bool sub_cells, bool eighths) {
  const k::KnitGeom& g = surface.geom();
  // The cells of each class.
  const ClassCells cells = class_cells(surface);
  class_of_.resize(size_t(g.rows) * size_t(g.cols));
  for (int k = 0; k < g.rows; ++k)
    for (int c = 0; c < g.cols; ++c)
      class_of_[size_t(k::knit_cell_index(g, k, c))] = static_cast<unsigned char>(cell_class(surface, k, c));
  one_colour_ = std::all_of(surface.colors(), surface.colors() + class_of_.size(), [](int c) { return c == 0; });
  int slots = 0;
  for (int i = 0; i < kClasses; ++i) slot_[size_t(i)] = cells[size_t(i)].empty() ? -1 : slots++;
  slots_ = slots;
  if (slots == 1)
    single_class_ = int(std::find_if(slot_.begin(), slot_.end(), [](int s) { return s >= 0; }) - slot_.begin());
  for (int i = 0; i < kClasses; ++i)
    if (slot_[size_t(i)] >= 0) class_of_slot_[size_t(slot_[size_t(i)])] = i;
  // The class matrix's smallest periods, divisors of the pattern's size (a
  // rib written out over several rows repeats every row): counting over
  // one period counts the same cells, in fewer rows.
  const auto rows_repeat = [&](int p) {  // rows pr and pr - p agree for every pr >= p
    return std::equal(class_of_.begin() + ptrdiff_t(p) * g.cols, class_of_.end(), class_of_.begin());
  };
  const auto cols_repeat = [&](int q) {  // columns c and c - q agree in every row, c >= q
    for (int pr = 0; pr < g.rows; ++pr) {
      const unsigned char* row = &class_of_[size_t(pr) * size_t(g.cols)];
      if (!std::equal(row + q, row + g.cols, row)) return false;
    }
    return true;
  };
  period_rows_ = g.rows;
  for (int p = 1; p < g.rows; ++p)
    if (g.rows % p == 0 && rows_repeat(p)) {
      period_rows_ = p;
      break;
    }
  period_cols_ = g.cols;
  for (int q = 1; q < g.cols; ++q)
    if (g.cols % q == 0 && cols_repeat(q)) {
      period_cols_ = q;
      break;
    }
  const size_t cols1 = size_t(period_cols_) + 1;
  if (slots > 1 && size_t(period_rows_) * size_t(slots) * cols1 <= kMaxPrefix) {
    prefix_.assign(size_t(period_rows_) * size_t(slots) * cols1, 0);
    for (size_t pr = 0; pr < size_t(period_rows_); ++pr)
      for (size_t s = 0; s < size_t(slots); ++s) {
        uint16_t* p = &prefix_[(pr * size_t(slots) + s) * cols1];
        for (size_t c = 0; c < size_t(period_cols_); ++c)
          p[c + 1] = uint16_t(p[c] + (slot_[class_of_[pr * size_t(g.cols) + c]] == int(s) ? 1 : 0));
      }
  }
  moments_.assign(size_t(slots) * kThetaBins * kPhiBins * kMoments, 0.0f);
  constexpr int kSubCells = kSub * kSub;
  // (built in float, stored as bfloat16 at the end)
  std::vector<float> sub_f(sub_cells ? size_t(slots) * kSubCells * kThetaBins * kPhiBins * kMoments : 0, 0.0f);
  const auto sub_at = [&](size_t slot, int si, int node) {
    return &sub_f[((slot * kSubCells + size_t(si)) * kThetaBins * kPhiBins + size_t(node)) * kMoments];
  };
  constexpr int kEighths = kEighth * kEighth;
  // (rays a multiple of 64: a direction's rays then start at a multiple of
  // 64 in the net, and each run of 64 puts one in every eighth)
  const bool keep_eighths = sub_cells && eighths && rays_per_direction % kEighths == 0;
  std::vector<float> eighth_f(keep_eighths ? size_t(slots) * kEighths * kThetaBins * kPhiBins : 0, 0.0f);
  const int m_rays = std::max(1, rays_per_direction);
  // The layer counts under the hits: a quarter of the build in scalar
  // counting queries, so batched on CPUs with a vector path (the same
  // counts: tests/native/test_query_batch.cpp).
  const bool batch_layers = layer_counts == LayerCounts::Auto &&
                            surface.batch_isa(KnitSurface::BatchPath::Auto) != KnitSurface::BatchIsa::Scalar;
  // The sums over the rays of one direction: of a class's cells, or of one
  // of their sub-cells.
  struct Sums {
    double rays = 0, hits = 0, n[3] = {0, 0, 0}, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0, layers = 0, z = 0;
    double near[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    Vec3 tsum = k::kv3(0, 0, 0);
    void add(const k::KnitLineHit& h, Vec3 sl, int near_at) {
      hits += 1;
      n[0] += h.n.x;
      n[1] += h.n.y;
      n[2] += h.n.z;
      tsum = add_line(tsum, h.tangent);
      const float bx = sl.x, by = sl.y;
      sx += bx;
      sy += by;
      sxx += double(bx) * bx;
      sxy += double(bx) * by;
      syy += double(by) * by;
      z += h.p.z;
      near[near_at] += 1;
    }
    // The moments are the sums over the rays: hit fraction times the
    // hit-conditioned mean is the sum over hits divided by all rays.
    void write(float* mo) const {
      if (!(rays > 0)) return;
      const double inv = 1.0 / rays;
      static_assert(kSlope == kNormal + 3 && kSlope2 == kSlope + 2 && kLayers == kSlope2 + 3 && kZ == kLayers + 1 &&
                        kNear == kZ + 1 && kNear + 9 == kLinear && kTangent + 3 < kMoments,
                    "the moments in the order of `sums`");
      const double sums[] = {n[0], n[1], n[2], sx, sy, sxx, sxy, syy, layers, z};
      mo[kHit] = float(hits * inv);
      for (int q = 0; q < 10; ++q) mo[kNormal + q] = float(sums[q] * inv);
      for (int q = 0; q < 9; ++q) mo[kNear + q] = float(near[q] * inv);
      if (hits > 0) {  // the unit sign-aligned mean tangent times the hit fraction
        const Vec3 t = k::kv3_scale(k::kv3_normalize(tsum), mo[kHit]);
        mo[kTangent] = t.x;
        mo[kTangent + 1] = t.y;
        mo[kTangent + 2] = t.z;
      }
    }
  };
  static_assert(kClassTableJobsPerClass == kThetaBins, "table_build_units counts a job per theta bin");
  TableBuildProgress* const progress = table_build_progress();
  tbb::parallel_for(0, kClasses * kThetaBins, [&](int job) {
    const int cls = job / kThetaBins, it = job % kThetaBins;
    if (slot_[size_t(cls)] < 0) return;
    struct Done {  // (however the job ends)
      TableBuildProgress* p;
      ~Done() {
        if (p) p->add(kClassTableJobUnits);
      }
    } done{progress};
    const size_t slot = size_t(slot_[size_t(cls)]);
    const std::vector<std::pair<int, int>>& list = cells[size_t(cls)];
    std::vector<float> hx, hy;  // hit points whose layers are counted in one batch
    std::vector<unsigned char> hsub;  // and their sub-cells
    std::vector<SurfaceHit> under;
    for (int ip = 0; ip < kPhiBins; ++ip) {
      const Vec3 wi = direction(it, ip);
      const float side = wi.z < 0 ? -1.0f : 1.0f;
      Sums all;
      std::array<Sums, kSubCells> sub;
      std::array<int, kEighths> e_rays{}, e_hits{};  // per eighth
      all.rays = m_rays;
      hx.clear();
      hy.clear();
      hsub.clear();
      for (int m = 0; m < m_rays; ++m) {
        // Cells of the class in turn (a stride coprime with most sizes
        // spreads them), the point inside the cell from ray_origin's net.
        const std::pair<int, int>& cell = list[(size_t(m) * 7919u) % list.size()];
        int si = 0, ei = 0;
        const Vec3 o = ray_origin(g, cell, it * kPhiBins + ip, m_rays, m, &si, &ei);
        sub[size_t(si)].rays += 1;
        ++e_rays[size_t(ei)];
        const k::KnitCapm st = k::knit_capm_curved(g, surface.codes(), surface.colors(), o.x, o.y, wi, 0, 0,
                                                   capm.max_segment, capm.max_steps);
        if (st.state != KNIT_CAPM_HIT) continue;
        ++e_hits[size_t(ei)];
        const Vec3 sl = k::knit_ms_slopes(st.hit.n, side);  // as knit_aggregate takes them
        const int dk = std::clamp(st.hit.row - cell.first, -1, 1), dc = std::clamp(st.hit.col - cell.second, -1, 1);
        all.add(st.hit, sl, (dk + 1) * 3 + dc + 1);
        sub[size_t(si)].add(st.hit, sl, (dk + 1) * 3 + dc + 1);
        if (batch_layers) {
          hx.push_back(st.hit.p.x);
          hy.push_back(st.hit.p.y);
          hsub.push_back(static_cast<unsigned char>(si));
        } else {
          const int layers = k::knit_vertical_layers(g, surface.codes(), surface.colors(), st.hit.p.x, st.hit.p.y);
          all.layers += layers;
          sub[size_t(si)].layers += layers;
        }
      }
      if (!hx.empty()) {
        under.resize(hx.size());
        surface.query_batch(hx.data(), hy.data(), hx.size(), under.data());
        for (size_t i = 0; i < under.size(); ++i) {
          all.layers += under[i].layers;
          sub[size_t(hsub[i])].layers += under[i].layers;
        }
      }
      all.write(&moments_[((slot * kThetaBins + size_t(it)) * kPhiBins + size_t(ip)) * kMoments]);
      if (sub_cells)
        for (int si = 0; si < kSubCells; ++si) sub[size_t(si)].write(sub_at(slot, si, it * kPhiBins + ip));
      if (keep_eighths)
        for (int ei = 0; ei < kEighths; ++ei)
          if (e_rays[size_t(ei)] > 0)
            eighth_f[(slot * kEighths + size_t(ei)) * kThetaBins * kPhiBins + size_t(it * kPhiBins + ip)] =
                float(double(e_hits[size_t(ei)]) / double(e_rays[size_t(ei)]));
    }
  });
  // The rows at theta = 0 and pi are one direction each: their columns,
  // marched with different points, are averaged (the moments mix linearly;
  // the tangent is the sign-aligned mean's direction times the mean hit
  // fraction).
  const auto average_poles = [](float* block) {  // the kThetaBins x kPhiBins nodes of one class (or sub-cell)
    for (int it : {0, kThetaBins - 1}) {
      float* row = block + size_t(it) * kPhiBins * kMoments;
      std::array<float, kMoments> avg{};
      Vec3 tsum = k::kv3(0, 0, 0);
      for (int ip = 0; ip < kPhiBins; ++ip) {
        const float* m = row + size_t(ip) * kMoments;
        add_scaled<kLinear>(avg.data(), m, 1.0f / kPhiBins);
        tsum = add_line(tsum, k::kv3(m[kTangent], m[kTangent + 1], m[kTangent + 2]));
      }
      const Vec3 t = k::kv3_scale(k::kv3_normalize(tsum), avg[kHit]);
      avg[kTangent] = t.x;
      avg[kTangent + 1] = t.y;
      avg[kTangent + 2] = t.z;
      for (int ip = 0; ip < kPhiBins; ++ip) std::copy(avg.begin(), avg.end(), row + size_t(ip) * kMoments);
    }
  };
  const size_t block = size_t(kThetaBins) * kPhiBins * kMoments;
  for (size_t b = 0; b < size_t(slots); ++b) average_poles(&moments_[b * block]);
  for (size_t b = 0; sub_cells && b < size_t(slots) * kSubCells; ++b) average_poles(&sub_f[b * block]);
  // (the eighths' hit fractions likewise: a mean over each pole row)
  for (size_t b = 0; b < eighth_f.size() / (size_t(kThetaBins) * kPhiBins); ++b)
    for (int it : {0, kThetaBins - 1}) {
      float* row = &eighth_f[(b * kThetaBins + size_t(it)) * kPhiBins];
      float avg = 0;
      for (int ip = 0; ip < kPhiBins; ++ip) avg += row[ip] / kPhiBins;
      std::fill_n(row, kPhiBins, avg);
    }
  // (stored by direction node, eighth_index: a lookup reads one direction's eighths)
  eighth_hits_.resize(eighth_f.size());
  for (size_t i = 0; i < eighth_f.size(); ++i) {
    const size_t dirs = size_t(kThetaBins) * kPhiBins;
    eighth_hits_[eighth_index(int(i / (kEighths * dirs)), int(i % dirs), int(i / dirs % kEighths))] =
        to_bf16(eighth_f[i]);
  }
  if (one_colour_) {
    static_assert(kSubLinear1 == kNear + 1 && kSubStride1 >= kSubLinear1 + 3, "the one-colour sub-cell node");
    const size_t nodes = sub_f.size() / kMoments;
    sub_moments_.assign(nodes * kSubStride1, 0);
    for (size_t i = 0; i < nodes; ++i) {
      const float* m = &sub_f[i * kMoments];
      uint16_t* o = &sub_moments_[i * kSubStride1];
      for (int q = 0; q < kNear; ++q) o[q] = to_bf16(m[q]);  // (o[kNear] stays 0)
      for (int q = 0; q < 3; ++q) o[kSubLinear1 + q] = to_bf16(m[kTangent + q]);
    }
  } else {
    sub_moments_.resize(sub_f.size());
    for (size_t i = 0; i < sub_f.size(); ++i) sub_moments_[i] = to_bf16(sub_f[i]);
  }
}

std::vector<float> FootprintTable::sub_moments() const {
  const size_t node = kMoments;
  std::vector<float> out(sub_moments_.size() / (one_colour_ ? kSubStride1 : kMoments) * node, 0.0f);
  for (size_t i = 0; i < out.size() / node; ++i) {
    const int per_slot = kSub * kSub * kThetaBins * kPhiBins;
    const int slot = int(i / size_t(per_slot)), rest = int(i % size_t(per_slot));
    sub_node(slot, rest / (kThetaBins * kPhiBins), rest % (kThetaBins * kPhiBins), &out[i * node]);
  }
  return out;
}

std::vector<float> FootprintTable::eighth_hits() const {
  constexpr int kEighths = kEighth * kEighth, kNodes = kThetaBins * kPhiBins;
  std::vector<float> out;
  out.reserve(eighth_hits_.size());
  for (int slot = 0; slot < int(eighth_hits_.size() / (kEighths * kNodes)); ++slot)
    for (int e = 0; e < kEighths; ++e)
      for (int node = 0; node < kNodes; ++node) out.push_back(from_bf16(eighth_hits_[eighth_index(slot, node, e)]));
  return out;
}

float FootprintTable::hit_fraction(int cls, const DirWeights& d) const {
  const int slot = slot_[size_t(cls)];
  return slot < 0 ? 0 : slot_hit_fraction(slot, d);  // absent: not for the pattern's own cells
}

float FootprintTable::slot_hit_fraction(int slot, const DirWeights& d) const {
  float h = 0;
  for (int q = 0; q < 4; ++q) h += d.w[size_t(q)] * moments(slot, d.node[size_t(q)])[kHit];
  // A convex combination of fractions, but the weights' float sum can
  // exceed 1 by an ulp: 1 + 2^-23 of a fully covered direction made
  // p_delta -1.2e-7, a negative shadow transmittance.
  return std::clamp(h, 0.0f, 1.0f);
}

std::array<float, 9> FootprintTable::near_shares(int cls, const DirWeights& d) const {
  std::array<float, 9> near{};
  const int slot = slot_[size_t(cls)];
  if (slot < 0) return near;
  float h = 0;
  for (int q = 0; q < 4; ++q) {
    const float* m = moments(slot, d.node[size_t(q)]);
    h += d.w[size_t(q)] * m[kHit];
    for (int i = 0; i < 9; ++i) near[size_t(i)] += d.w[size_t(q)] * m[kNear + i];
  }
  if (h > 0)
    for (float& v : near) v /= h;
  return near;
}

template <class Visit>
void FootprintTable::for_each_cell(const KnitSurface& surface, const k::KFootprint& f, Visit&& visit) const {
  const k::KnitGeom& g = surface.geom();
  auto cell = [&](int k, int c) { visit(int(class_of_[size_t(k::knit_cell_index(g, k, c))]), k, c); };
  if (all_cells(f)) {
    // Row by row, the column index wrapped by hand: two modulos per row
    // instead of two integer divisions per cell (knit_cell_index).
    const int c0 = k::k_modi(f.bx0, g.cols);
    for (int cy = 0; cy < f.ncy; ++cy) {
      const int k = f.by0 + cy;
      const size_t row = size_t(g.rows - 1 - k::k_modi(k, g.rows)) * size_t(g.cols);
      int cm = c0;
      for (int cx = 0; cx < f.ncx; ++cx) {
        visit(int(class_of_[row + size_t(cm)]), k, f.bx0 + cx);
        if (++cm == g.cols) cm = 0;
      }
    }
    return;
  }
  for (int i = 0; i < f.n; ++i) {
    const Vec3 p = k::knit_footprint_point(g, f, i);
    cell(int(std::floor(p.y / g.row_spacing)), int(std::floor(p.x / K_2PI)));
  }
}

bool FootprintTable::class_counts(const k::KFootprint& f,
                                  std::array<double, kClasses>& counts) const {
  counts.fill(0);
  if (!can_count()) return false;
  if (single_class_ >= 0) {
    counts[size_t(single_class_)] = double(f.ncx) * f.ncy;
    return true;
  }
  // Over one period of the class matrix (period_rows_ x period_cols_, which
  // divide the pattern's rows and columns: the same counts as over the
  // pattern, k::knit_cell_index's row order included).
  const int rows = period_rows_, cols = period_cols_;
  const int slots = slots_;
  const size_t cols1 = size_t(cols) + 1;
  // Columns [c0, c0 + ncx) of a row, wrapped: `full` whole rows and a rest.
  const int c0 = k::k_modi(f.bx0, cols);
  const int64_t full = f.ncx / cols;
  const int rest = f.ncx % cols;
  // Rows [by0, by0 + ncy), wrapped: the first min(ncy, rows) of them stand
  // for every row of the box, the first ncy % rows once more than the
  // others. A box of up to 1e5 x 1e5 cells (knit_footprint's cap) costs at
  // most a pass over the period's rows.
  const int nr = std::min(f.ncy, rows);
  const int64_t per = f.ncy / rows, extra = f.ncy % rows;
  std::array<int64_t, kClasses> n{};  // by slot
  // Period row of box row cy, counted down with wrap-around (one modulo).
  int pr = rows - 1 - k::k_modi(f.by0, rows);
  for (int cy = 0; cy < nr; ++cy, pr = pr > 0 ? pr - 1 : rows - 1) {
    const int64_t times = per + (cy < extra ? 1 : 0);
    for (int s = 0; s < slots; ++s) {
      const uint16_t* p = &prefix_[(size_t(pr) * size_t(slots) + size_t(s)) * cols1];
      int64_t m = full * p[cols];
      if (c0 + rest <= cols) {
        m += p[c0 + rest] - p[c0];
      } else {
        m += (p[cols] - p[c0]) + p[c0 + rest - cols];
      }
      n[size_t(s)] += times * m;
    }
  }
  for (int s = 0; s < slots; ++s) counts[size_t(class_of_slot_[size_t(s)])] = double(n[size_t(s)]);
  return true;
}

// Inline in both aggregates (a call cost 1% of a multi-scale render's
// instructions, callgrind).
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline bool FootprintTable::finish(k::KnitAggregate& a, int points, float p_delta, const float* sum, Vec3 tsum,
                                   float x, float y) {
  a.points = points;
  a.p_delta = p_delta;
  const float hit = 1 - a.p_delta;  // the hit fraction over the box
  a.hits = hit > 0 ? std::max(1, round_count(hit * float(a.points))) : 0;
  a.steps = 0;
  a.color_pick = -1;
  if (!(hit > 0 && sum[kHit] > 0)) {
    a.n = k::kv3(0, 0, 1);
    a.tangent = k::kv3(1, 0, 0);
    a.position = k::kv3(x, y, 0);
    return false;
  }
  // The hit-weighted means; the slopes' covariance about their mean.
  const float inv = 1 / sum[kHit];
  const float sx = sum[kSlope] * inv, sy = sum[kSlope + 1] * inv;
  a.n = k::kv3_normalize(k::kv3(sum[kNormal], sum[kNormal + 1], sum[kNormal + 2]));
  a.tangent = k::kv3_normalize(tsum);
  a.position = k::kv3(x, y, sum[kZ] * inv);
  a.sxx = std::max(sum[kSlope2] * inv - sx * sx, 0.0f);
  a.sxy = sum[kSlope2 + 1] * inv - sx * sy;
  a.syy = std::max(sum[kSlope2 + 2] * inv - sy * sy, 0.0f);
  a.layers = sum[kLayers] * inv;
  return true;
}

k::KnitAggregate FootprintTable::aggregate(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi,
                                           float* slot_hits) const {
  const k::KnitGeom& g = surface.geom();
  k::KnitAggregate a{};
  // The direction is the same for every cell, so the aggregate is a sum
  // over the classes present: each class's four direction nodes weighted by
  // its share of the box's cells (moments: hit-weighted, so that this one
  // weighted sum gives the hit-weighted means).
  const DirWeights dw = dir_weights(wi);
  // How many cells of each class the box holds, when the table can count
  // them (see class_counts), else by visiting them; with several colour
  // indices the colours visit the cells they need.
  std::array<double, kClasses> counts;
  const bool counted = class_counts(f, counts);
  std::array<float, kClasses> cls_hit;  // hit fractions of the visited classes, on first use
  cls_hit.fill(-1);
  std::array<std::array<float, 9>, kClasses> cls_near;  // row cls valid once near_ready[cls]
  std::array<bool, kClasses> near_ready{};
  struct Pick {
    int colour;
    float cum;
  };
  std::array<Pick, KNIT_MS_MAX_POINTS> picks;  // the first npicks are set
  int npicks = 0;
  double visit_hits = 0;  // hits of the visited cells (the colours' weights)
  if (!counted || !one_colour_) for_each_cell(surface, f, [&](int cls, int k, int c) {
    if (!counted) counts[size_t(cls)] += 1;
    if (one_colour_) return;
    float& h = cls_hit[size_t(cls)];
    if (h < 0) h = hit_fraction(cls, dw);
    if (h <= 0) return;
    const float w = h;
    visit_hits += w;
    if (!near_ready[size_t(cls)]) {
      cls_near[size_t(cls)] = near_shares(cls, dw);
      near_ready[size_t(cls)] = true;
    }
    const std::array<float, 9>& near = cls_near[size_t(cls)];
    // Colours of the yarns hit: the 3 x 3 block around the cell, by share.
    int colour = -1;
    float share = -1;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dc = -1; dc <= 1; ++dc) {
        const float q = near[size_t((dk + 1) * 3 + dc + 1)];
        if (q <= 0) continue;
        const int col = surface.colors()[k::knit_cell_index(g, k + dk, c + dc)];
        a.color_w[std::clamp(col, 0, KNIT_MS_COLORS - 1)] += w * q;
        if (q > share) {
          share = q;
          colour = col;
        }
      }
    if (npicks < KNIT_MS_MAX_POINTS) picks[size_t(npicks++)] = {colour, float(visit_hits)};
  });
  double cells = 0;
  for (double n : counts) cells += n;
  std::array<float, kLinear> sum{};
  Vec3 tsum = k::kv3(0, 0, 0);
  // p_delta exactly as pass_of() has it for shadow rays (the same sums in
  // the same order: a class's hit fraction as slot_hit_fraction forms it,
  // the counts, integers, summed exactly in any order), taken in the same pass.
  double hits = 0;
  if (cells > 0) {
    for (int slot = 0; slot < slots_; ++slot) {
      const double n = counts[size_t(class_of_slot_[size_t(slot)])];
      if (!(n > 0)) continue;
      const float share = float(n / cells);
      float h = 0;
      for (int q = 0; q < 4; ++q) {
        const float w = share * dw.w[size_t(q)];
        const float* m = moments(slot, dw.node[size_t(q)]);
        h += dw.w[size_t(q)] * m[kHit];
        add_scaled<kLinear>(sum.data(), m, w);
        // Tangents are lines, not arrows: sign-aligned with the sum so far.
        const Vec3 t = k::kv3_scale(k::kv3(m[kTangent], m[kTangent + 1], m[kTangent + 2]), w);
        tsum = add_line(tsum, t);
      }
      hits += n * double(std::clamp(h, 0.0f, 1.0f));
      if (slot_hits) slot_hits[slot] = share * std::clamp(h, 0.0f, 1.0f);
    }
  }
  // In points: the cells of a box of up to KNIT_MS_MAX_POINTS, else the
  // footprint's points (a counted box may hold up to 1e10 cells).
  if (!finish(a, all_cells(f) ? int(cells) : f.n, pass_fraction(hits, cells), sum.data(), tsum, f.x, f.y)) return a;
  if (one_colour_) {
    a.color_w[0] = 1;
    a.color_pick = 0;
    return a;
  }
  if (visit_hits <= 0) {
    // The visited cells (the points of a box too large to visit) all missed
    // where the counted ones did not: the colour of the centre's cell.
    const int col = surface.colors()[k::knit_cell_index(g, int(std::floor(f.y / g.row_spacing)),
                                                        int(std::floor(f.x / K_2PI)))];
    a.color_w[std::clamp(col, 0, KNIT_MS_COLORS - 1)] = 1;
    a.color_pick = col;
    return a;
  }
  const double inv_visit = 1 / visit_hits;
  for (float& w : a.color_w) w = float(w * inv_visit);
  // One cell's colour, chosen in proportion to its hits by the footprint's shift.
  const float u = k::knit_frac(f.shift_x * 7 + f.shift_y * 3 + 0.5f) * float(visit_hits);
  for (int i = 0; i < npicks; ++i)
    if (picks[size_t(i)].cum >= u || i == npicks - 1) {
      a.color_pick = picks[size_t(i)].colour;
      break;
    }
  return a;
}

float FootprintTable::pass_of(const std::array<double, kClasses>& counts, const DirWeights& dw,
                              float* slot_hits) const {
  double cells = 0, hits = 0;
  for (int slot = 0; slot < slots_; ++slot) {
    const double n = counts[size_t(class_of_slot_[size_t(slot)])];
    if (!(n > 0)) continue;
    cells += n;
    const float h = slot_hit_fraction(slot, dw);
    hits += n * double(h);
    if (slot_hits) slot_hits[slot] = float(n) * h;  // (any scale)
  }
  return pass_fraction(hits, cells);
}

float FootprintTable::p_delta(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi, float* slot_hits) const {
  const DirWeights dw = dir_weights(wi);
  std::array<double, kClasses> counts;
  if (!class_counts(f, counts))
    for_each_cell(surface, f, [&](int cls, int, int) { counts[size_t(cls)] += 1; });
  return pass_of(counts, dw, slot_hits);
}

namespace {

int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// std::floor and std::ceil to int64 for |v| < 2^62, without libm's calls
// (the build's baseline x86-64 has no rounding instruction): a quarter of
// every sub-cell box's set-up.
int64_t floor_i64(double v) {
  const int64_t t = int64_t(v);  // towards zero
  return double(t) > v ? t - 1 : t;
}
int64_t ceil_i64(double v) {
  const int64_t t = int64_t(v);
  return double(t) < v ? t + 1 : t;
}

}  // namespace

std::optional<FootprintTable::SubBox> FootprintTable::sub_box_at(float x, float y, float ex, float ey,
                                                                 const k::KnitGeom& g) {
  // (1e9 pattern units: beyond the kernel's own float range, and the
  // sub-cell indices stay far inside int64)
  if (!(ex >= kMinSubBox && ey >= kMinSubBox) || !(ex <= float(kMaxSubBox) && ey <= float(kMaxSubBox)) ||
      !(std::fabs(x) <= 1e9f && std::fabs(y) <= 1e9f))
    return std::nullopt;
  // A box edge in sub-cell units, kept an exact double (x / cw in float
  // loses the sub-cell at the 1e4 units the kernel allows).
  const auto range = [](float centre, float extent, float cell) {
    SubBox::Range r;
    const double c = double(centre) / double(cell), e = double(extent);
    r.lo = (c - 0.5 * e) * kSub;
    r.hi = (c + 0.5 * e) * kSub;
    r.first = floor_i64(r.lo);
    r.last = ceil_i64(r.hi) - 1;
    return r;
  };
  // (the same edges in eighths: doubled, still exact)
  const auto eighths = [](const SubBox::Range& q) {
    static_assert(kEighth == 2 * kSub, "an eighth is half a sub-cell");
    SubBox::Range r;
    r.lo = 2 * q.lo;
    r.hi = 2 * q.hi;
    r.first = floor_i64(r.lo);
    r.last = ceil_i64(r.hi) - 1;
    return r;
  };
  const auto count = [](const SubBox::Range& rx, const SubBox::Range& ry) {
    return (rx.last - rx.first + 1) * (ry.last - ry.first + 1);
  };
  SubBox box;
  box.rx = range(x, ex, K_2PI);
  box.ry = range(y, ey, g.row_spacing);
  box.x_ = x;
  box.y_ = y;
  if (count(box.rx, box.ry) > kMaxSubBox) return std::nullopt;
  box.rx8 = eighths(box.rx);
  box.ry8 = eighths(box.ry);
  box.eighths_ = count(box.rx8, box.ry8) <= kMaxEighthBox;
  return box;
}

bool FootprintTable::sub_box(float x, float y, float ex, float ey, const k::KnitGeom& g) {
  return sub_box_at(x, y, ex, ey, g).has_value();
}

template <int S, class Visit>
void FootprintTable::for_each_sub(const k::KnitGeom& g, const SubBox::Range& rx, const SubBox::Range& ry,
                                  Visit&& visit) {
  const int64_t kc0 = floor_div(rx.first, S);
  const int cm0 = k::k_modi(int(kc0), g.cols);  // (the box's columns stay far inside int: sub_box)
  for (int64_t j = ry.first; j <= ry.last; ++j) {
    const double wy = ry.overlap(j);
    if (!(wy > 0)) continue;
    const int64_t kr = floor_div(j, S);
    const int sy = int(j - kr * S);
    // The cell's place in the pattern as knit_cell_index has it, its column
    // wrapped by hand along the row (no integer division per sub-cell).
    const size_t row = size_t(g.rows - 1 - k::k_modi(int(kr), g.rows)) * size_t(g.cols);
    int64_t kc = kc0;
    int cm = cm0;
    for (int64_t i = rx.first; i <= rx.last; ++i) {
      if (i >= (kc + 1) * S) {
        ++kc;
        if (++cm == g.cols) cm = 0;
      }
      const double wx = rx.overlap(i);
      if (!(wx > 0)) continue;
      visit(int(kr), int(kc), row + size_t(cm), sy * S + int(i - kc * S), wx * wy);
    }
  }
}

void FootprintTable::check_sub_cells(const char* caller) const {
  if (!has_sub_cells())
    throw std::logic_error(std::string("FootprintTable::") + caller + ": the table has no sub-cells");
}

FootprintTable::SubBox FootprintTable::checked_sub_box(const k::KnitGeom& g, float x, float y, float ex, float ey,
                                                       const char* caller) const {
  check_sub_cells(caller);
  const std::optional<SubBox> box = sub_box_at(x, y, ex, ey, g);
  if (!box) throw std::invalid_argument(std::string("FootprintTable::") + caller + ": not a sub-cell box");
  return *box;
}

k::KnitAggregate FootprintTable::aggregate_sub(const KnitSurface& surface, float x, float y, float ex, float ey,
                                               Vec3 wi, float pick, float* slot_hits) const {
  return aggregate_sub(surface, checked_sub_box(surface.geom(), x, y, ex, ey, "aggregate_sub"), wi, pick,
                       slot_hits);
}

k::KnitAggregate FootprintTable::aggregate_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi, float pick,
                                               float* slot_hits) const {
  check_sub_cells("aggregate_sub");
  const k::KnitGeom& g = surface.geom();
  const float x = box.x_, y = box.y_;
  // The overlap areas summed per class and sub-cell: one weighted sum of
  // moments per pair present, however many cells the box touches.
  const SubAreas sa = sub_areas(g, box);
  const std::array<double, kClasses * kSub * kSub>& area = sa.area;
  const double total = sa.total;
  k::KnitAggregate a{};
  const DirWeights dw = dir_weights(wi);
  constexpr int kSubCells = kSub * kSub;
  std::array<float, kLinear> sum{};
  Vec3 tsum = k::kv3(0, 0, 0);
  const bool eighths = box.eighths_ && has_eighths();
  std::array<float, kClasses * kSubCells> hit_of;  // hit fraction per pair, for the colours
  std::fill_n(hit_of.begin(), slots_ * kSubCells, 0.0f);  // (the slots present)
  double hits = 0;
  // Each (class, sub-cell) pair's four direction nodes, weighted by its
  // share of the box times their bilinear weights; kStride values a node,
  // the first kLin summed (with one colour the neighbour shares are
  // neither kept nor summed), the tangent at kTan.
  const auto sum_pairs = [&](auto stride, auto lin, auto tan) {
    constexpr int kStride = decltype(stride)::value, kLin = decltype(lin)::value, kTan = decltype(tan)::value;
    for (int ps = 0; ps < slots_ * kSubCells; ++ps) {
      if (!(area[size_t(ps)] > 0)) continue;
      const float share = float(area[size_t(ps)] / total);
      const uint16_t* pair = &sub_moments_[size_t(ps) * kThetaBins * kPhiBins * kStride];
      float h = 0;
      for (int q = 0; q < 4; ++q) {
        const float w = share * dw.w[size_t(q)];
        const uint16_t* p = pair + size_t(dw.node[size_t(q)]) * kStride;
        float m[kLin], t[3];
        for (int i = 0; i < kLin; ++i) m[i] = from_bf16(p[i]);
        for (int i = 0; i < 3; ++i) t[i] = from_bf16(p[kTan + i]);
        h += dw.w[size_t(q)] * m[kHit];
        add_scaled<kLin>(sum.data(), m, w);
        tsum = add_line(tsum, k::kv3_scale(k::kv3(t[0], t[1], t[2]), w));
      }
      hit_of[size_t(ps)] = std::clamp(h, 0.0f, 1.0f);
      hits += double(share) * double(hit_of[size_t(ps)]);
      if (slot_hits && !eighths) slot_hits[ps / kSubCells] += share * hit_of[size_t(ps)];
    }
  };
  if (total > 0) {
    if (one_colour_)
      sum_pairs(std::integral_constant<int, kSubStride1>{}, std::integral_constant<int, kSubLinear1>{},
                std::integral_constant<int, kSubLinear1>{});
    else
      sum_pairs(std::integral_constant<int, kMoments>{}, std::integral_constant<int, kLinear>{},
                std::integral_constant<int, kTangent>{});
  }
  // The hit fraction (and the per-class hits) from the eighths where they
  // apply, exactly as p_delta_sub gives them; the means from the quarters.
  const float p_delta = eighths ? p_delta_sub(surface, box, wi, slot_hits) : std::clamp(float(1 - hits), 0.0f, 1.0f);
  if (!finish(a, sa.touched, p_delta, sum.data(), tsum, x, y)) return a;
  if (one_colour_) {
    a.color_w[0] = 1;
    a.color_pick = 0;
    return a;
  }
  // Colours: each touched sub-cell's hits go to the 3 x 3 block around its
  // cell by the sub-cell's shares; one of them picked in proportion to its
  // hits for patterns with more colours than bins.
  double visit_hits = 0;
  bool picked = false;
  const double target = double(k::knit_frac(pick)) * hits * total;
  for_each_sub(g, box.rx, box.ry, [&](int kr, int kc, size_t cell, int sub, double w) {
    const int slot = slot_[class_of_[cell]];
    const float h = hit_of[size_t(slot * kSubCells + sub)];
    if (!(h > 0)) return;
    float near[9] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    for (int q = 0; q < 4; ++q) {
      float m[kMoments];
      sub_node(slot, sub, dw.node[size_t(q)], m);
      for (int i = 0; i < 9; ++i) near[i] += dw.w[size_t(q)] * m[kNear + i];
    }
    float nsum = 0;
    for (float v : near) nsum += v;
    if (!(nsum > 0)) return;
    const double wh = w * double(h);
    visit_hits += wh;
    int colour = -1;
    float best = -1;
    for (int dk = -1; dk <= 1; ++dk)
      for (int dc = -1; dc <= 1; ++dc) {
        const float q = near[(dk + 1) * 3 + dc + 1] / nsum;
        if (q <= 0) continue;
        const int col = surface.colors()[k::knit_cell_index(g, kr + dk, kc + dc)];
        a.color_w[std::clamp(col, 0, KNIT_MS_COLORS - 1)] += float(wh * q);
        if (q > best) {
          best = q;
          colour = col;
        }
      }
    if (!picked) {  // the first sub-cell whose running sum reaches the target (else the last)
      a.color_pick = colour;
      picked = visit_hits >= target;
    }
  });
  if (visit_hits <= 0) {
    const int col = surface.colors()[k::knit_cell_index(g, int(std::floor(y / g.row_spacing)),
                                                        int(std::floor(x / K_2PI)))];
    std::fill(std::begin(a.color_w), std::end(a.color_w), 0.0f);
    a.color_w[std::clamp(col, 0, KNIT_MS_COLORS - 1)] = 1;
    a.color_pick = col;
    return a;
  }
  const double inv_visit = 1 / visit_hits;
  for (float& w : a.color_w) w = float(w * inv_visit);
  return a;
}

float FootprintTable::p_delta_sub(const KnitSurface& surface, float x, float y, float ex, float ey, Vec3 wi,
                                  float* slot_hits) const {
  return p_delta_sub(surface, checked_sub_box(surface.geom(), x, y, ex, ey, "p_delta_sub"), wi, slot_hits);
}

namespace {

using D4 = std::array<double, 4>;  // a value at each of the four direction nodes

// A folded cell's hits, sum_hits' cell_sum, one sub-cell at a time:
// sum over rows y (those set in `rows`) and columns x of S sub-cells of
// wy[y] wx[x] hit4(slot, y S + x).
template <int S, class Hit4>
auto cells_of(const Hit4& hit4) {
  return [&hit4](int slot, const double* wx, const double* wy, uint32_t rows) {
    D4 sum{};
    for (int y = 0; y < S; ++y) {
      if (!((rows >> y) & 1u)) continue;
      D4 line{};
      for (int x = 0; x < S; ++x) {
        if (!(wx[x] > 0)) continue;
        const D4 h = hit4(slot, y * S + x);
        for (int q = 0; q < 4; ++q) line[size_t(q)] += wx[x] * h[size_t(q)];
      }
      for (int q = 0; q < 4; ++q) sum[size_t(q)] += wy[y] * line[size_t(q)];
    }
    return sum;
  };
}

}  // namespace

float FootprintTable::p_delta_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi, float* slot_hits) const {
  NodeSums sums;
  return p_delta_sub(surface, box, wi, slot_hits, sums);
}

float FootprintTable::p_delta_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi, float* slot_hits,
                                  NodeSums& sums) const {
  check_sub_cells("p_delta_sub");
  const DirWeights dw = dir_weights(wi);
  if (sums.node == dw.node) return blend(sums, dw, slot_hits);
  sums = NodeSums{};
  sums.node = dw.node;
  const k::KnitGeom& g = surface.geom();
  // Each touched (class slot, sub-cell) pair's hit fraction at the four
  // nodes around wi, weighted by the box's overlap area on the pair: of
  // eighths where the table keeps them and the box touches few enough.
  if (box.eighths_ && has_eighths()) {
    // (a slot's eighths of one direction node lie together: the four
    // nodes' 64 each are all a box reads)
    std::array<size_t, 4> at;  // the four nodes' offsets from node 0
    for (int q = 0; q < 4; ++q) at[size_t(q)] = eighth_index(0, dw.node[size_t(q)], 0);
    const auto hit4 = [&](int slot, int sub) {
      const uint16_t* p = &eighth_hits_[eighth_index(slot, 0, sub)];
      D4 h;
      for (int q = 0; q < 4; ++q) h[size_t(q)] = double(from_bf16(p[at[size_t(q)]]));
      return h;
    };
#if defined(__GNUC__)
    // A folded cell's sum a row of eight eighths at a time: a row's 8
    // bfloat16 values of a node are 16 bytes, read as four 32-bit lanes
    // whose low halves are the even eighths and high halves the odd ones,
    // each row weighted by wy into two vectors a node (even and odd
    // eighths); the columns' weights applied once at the end.
    typedef float v4 __attribute__((vector_size(16)));
    typedef uint32_t u4 __attribute__((vector_size(16)));
    static_assert(kEighth == 8, "a row is two vectors");
    const auto cell_sum = [&](int slot, const double* wx, const double* wy, uint32_t rows) {
      const uint16_t* base = &eighth_hits_[eighth_index(slot, 0, 0)];
      const v4 zero = {0, 0, 0, 0};
      v4 ae[4] = {zero, zero, zero, zero}, ao[4] = {zero, zero, zero, zero};
      for (; rows; rows &= rows - 1) {
        const int y = __builtin_ctz(rows);
        const float wr = float(wy[y]);
        for (int q = 0; q < 4; ++q) {
          u4 r;
          std::memcpy(&r, base + at[size_t(q)] + size_t(y) * kEighth, sizeof r);
          const u4 even = r << 16, odd = r & 0xffff0000u;
          v4 fe, fo;
          std::memcpy(&fe, &even, sizeof fe);
          std::memcpy(&fo, &odd, sizeof fo);
          ae[q] += wr * fe;
          ao[q] += wr * fo;
        }
      }
      const v4 we = {float(wx[0]), float(wx[2]), float(wx[4]), float(wx[6])};
      const v4 wo = {float(wx[1]), float(wx[3]), float(wx[5]), float(wx[7])};
      D4 sum;
      for (int q = 0; q < 4; ++q) {
        const v4 row = we * ae[q] + wo * ao[q];
        sum[size_t(q)] = double((row[0] + row[1]) + (row[2] + row[3]));
      }
      return sum;
    };
#else
    const auto cell_sum = cells_of<kEighth>(hit4);
#endif
    sum_hits<kEighth>(g, box.rx8, box.ry8, hit4, cell_sum, sums);
  } else {
    // the four nodes' offsets within a pair's block
    const size_t stride = one_colour_ ? size_t(kSubStride1) : size_t(kMoments);
    const size_t pair_block = size_t(kThetaBins) * kPhiBins * stride;
    std::array<size_t, 4> at;
    for (int q = 0; q < 4; ++q) at[size_t(q)] = size_t(dw.node[size_t(q)]) * stride + kHit;
    const auto hit4 = [&](int slot, int sub) {
      const uint16_t* p = &sub_moments_[size_t(slot * kSub * kSub + sub) * pair_block];
      D4 h;
      for (int q = 0; q < 4; ++q) h[size_t(q)] = double(from_bf16(p[at[size_t(q)]]));
      return h;
    };
    sum_hits<kSub>(g, box.rx, box.ry, hit4, cells_of<kSub>(hit4), sums);
  }
  return blend(sums, dw, slot_hits);
}

float FootprintTable::blend(const NodeSums& sums, const DirWeights& dw, float* slot_hits) const {
  if (!(sums.total > 0)) return 1;
  const auto mixed = [&](const std::array<double, 4>& v) {
    return (double(dw.w[0]) * v[0] + double(dw.w[1]) * v[1]) + (double(dw.w[2]) * v[2] + double(dw.w[3]) * v[3]);
  };
  const double inv = 1 / sums.total;
  if (slot_hits)
    for (int s = 0; s < slots_; ++s) slot_hits[s] += float(mixed(sums.by_slot[size_t(s)]) * inv);
  return std::clamp(float(1 - mixed(sums.hits) * inv), 0.0f, 1.0f);
}

template <int S, class Hit4, class CellSum>
void FootprintTable::sum_hits(const k::KnitGeom& g, const SubBox::Range& rx, const SubBox::Range& ry,
                              Hit4&& hit4, CellSum&& cell_sum, NodeSums& sums) const {
  const auto add = [](D4& to, const D4& v) {
    for (int q = 0; q < 4; ++q) to[size_t(q)] += v[size_t(q)];
  };
  if (period_rows_ == 1 || period_cols_ == 1) {
    // Classes that change along one axis only (one class, ribs, welts): a
    // sub-cell's area is its column's overlap times its row's, and its pair
    // is its class and its place in the cell, so the box folds onto the
    // places of one cell per class met along that axis (at most S * S
    // pairs a class, however long the box).
    const bool by_column = period_rows_ == 1;  // (else every column is alike)
    // fold: the overlaps of range r summed onto the S places of a cell, per
    // class slot met along the classes' axis (else all in slot 0), and
    // which places got any (bits of `places`).
    const auto fold = [&](const SubBox::Range& r, bool classes, double* w, uint32_t* places) {
      double sum = 0;
      const int n = by_column ? g.cols : g.rows;
      int64_t cell = floor_div(r.first, S);
      int place = int(r.first - cell * S);
      // (class_of_ as knit_cell_index has it: along a row, or down a column;
      // the cell's index wrapped by hand, no division per sub-cell)
      int m = classes ? k::k_modi(int(cell), n) : 0;
      const auto slot_at = [&](int mm) {
        return slot_[class_of_[by_column ? size_t(mm) : size_t(g.rows - 1 - mm) * size_t(g.cols)]];
      };
      int slot = classes ? slot_at(m) : 0;
      for (int64_t i = r.first; i <= r.last; ++i, ++place) {
        if (place == S) {
          place = 0;
          if (classes) {
            if (++m == n) m = 0;
            slot = slot_at(m);
          }
        }
        const double v = r.overlap(i);
        if (!(v > 0)) continue;
        places[slot] |= 1u << place;
        w[slot * S + place] += v;
        sum += v;
      }
      return sum;
    };
    // (only the slots present cleared: a memset of the whole arrays cost
    // more than the fold)
    double wc[kClasses * S], wo[S];  // along the classes' axis, along the other
    uint32_t met[kClasses], other = 0;
    static_assert(S <= 32, "a cell's places are bits of a word");
    std::fill_n(wc, slots_ * S, 0.0);
    std::fill_n(wo, S, 0.0);
    std::fill_n(met, slots_, 0u);
    sums.total = fold(by_column ? rx : ry, true, wc, met) * fold(by_column ? ry : rx, false, wo, &other);
    for (int slot = 0; slot < slots_; ++slot) {
      if (!met[slot]) continue;
      const double* along = wc + slot * S;
      const D4 sh = by_column ? cell_sum(slot, along, wo, other) : cell_sum(slot, wo, along, met[slot]);
      sums.by_slot[size_t(slot)] = sh;
      add(sums.hits, sh);
    }
  } else {
    for_each_sub<S>(g, rx, ry, [&](int, int, size_t cell, int sub, double w) {
      const int slot = slot_[class_of_[cell]];
      const D4 h = hit4(slot, sub);
      D4& by = sums.by_slot[size_t(slot)];
      for (int q = 0; q < 4; ++q) by[size_t(q)] += w * h[size_t(q)];
      sums.total += w;
    });
    for (int slot = 0; slot < slots_; ++slot) add(sums.hits, sums.by_slot[size_t(slot)]);
  }
}

FootprintTable::SubAreas FootprintTable::sub_areas(const k::KnitGeom& g, const SubBox& box) const {
  SubAreas sa;
  std::fill_n(sa.area.begin(), slots_ * kSub * kSub, 0.0);
  for_each_sub(g, box.rx, box.ry, [&](int, int, size_t cell, int sub, double w) {
    sa.area[size_t(slot_[class_of_[cell]] * kSub * kSub + sub)] += w;
    sa.total += w;
    ++sa.touched;
  });
  return sa;
}

}  // namespace knit
