#include "knit/table_bsdf.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "knit/shading.h"
#include "knit/table_progress.h"

namespace knit {

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr float kDTheta = kPi / float(TableBsdf::kTheta - 1);
constexpr float kDPhi = 2 * kPi / float(TableBsdf::kPhi);

uint16_t bf16(float v) {  // rounded to nearest; the values are finite and >= 0
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits += 0x7fffu + ((bits >> 16) & 1u);
  return uint16_t(bits >> 16);
}

float from_bf16(uint16_t v) {
  const uint32_t bits = uint32_t(v) << 16;
  float f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// Four floats as one vector (GCC and Clang vector extensions): the table's
// sums run four lanes at a time.
typedef float F4 __attribute__((vector_size(16)));
typedef uint16_t H8 __attribute__((vector_size(16)));

F4 load4(const float* p) {
  F4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

// Four stored bfloat16 values as floats: each value's 16 bits become the
// upper half of a float's, the lower half zero. Written as one interleave
// of the values with zeros, a single unpack on x86 (the widening
// conversion and shift it replaced took a second load and four more
// operations with SSE2); the same bits either way.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "bf16x4 puts each value in the upper half of a float's bits");
F4 bf16x4(const uint16_t* p) {
  H8 h{};
  std::memcpy(&h, p, 4 * sizeof(uint16_t));
  const H8 bits = __builtin_shufflevector(H8{}, h, 0, 8, 1, 9, 2, 10, 3, 11);
  F4 f;
  std::memcpy(&f, &bits, sizeof f);
  return f;
}

// Sums over a mix's terms (view node t, class slot s) of w_t share_s times
// entry k * slots + s of the term's block, for k < N, four lanes each:
// block(view) is the view node's first entry, entry(p, i) the four values
// of entry i from there. The sampling rows (N = kTheta + 1), a theta row's
// nodes (N = kPhi) and one node (N = 1) are such sums. They start from the
// first term's products: an array cleared first cost as much as the sums.
template <size_t N, class Block, class Entry>
void mixed_sums(const TableBsdf::Mix& m, int slots, Block block, Entry entry, std::array<F4, N>& sum) {
  if (m.n == 0 || slots == 0) {
    sum.fill(F4{});
    return;
  }
  const auto* first = block(m.view[0]);
  for (size_t k = 0; k < N; ++k) sum[k] = (m.w[0] * m.share[0]) * entry(first, int(k) * slots);
  for (int t = 0; t < m.n; ++t) {
    const auto* p = block(m.view[size_t(t)]);
    for (int s = t == 0 ? 1 : 0; s < slots; ++s) {
      const float w = m.w[size_t(t)] * m.share[size_t(s)];
      for (size_t k = 0; k < N; ++k) sum[k] += w * entry(p, int(k) * slots + s);
    }
  }
}

// A node's (or a sum of nodes') sampling value: its four stored values
// weighed by the mix's sw. Folded, sw is 0, 0, 0, 1 and the value the
// fourth itself, the same number (the others finite), at one operation.
float sampling_value(const TableBsdf::Mix& m, const F4& v) {
  return m.sw[0] * v[0] + m.sw[1] * v[1] + m.sw[2] * v[2] + m.sw[3] * v[3];
}
float sampling_value(bool folded, const TableBsdf::Mix& m, const F4& v) {
  return folded ? v[3] : sampling_value(m, v);
}

// The heaviest of a direction's four bilinear corners (the first of equal
// ones): the node whose cell holds the direction, for sample()'s density.
int heaviest_corner(const SphereNodes& c) { return int(std::max_element(c.w.begin(), c.w.end()) - c.w.begin()); }

// Corner q's values among the four that eval has read.
const F4& corner_value(int q, const F4& v0, const F4& v1, const F4& v2, const F4& v3) {
  return q == 0 ? v0 : q == 1 ? v1 : q == 2 ? v2 : v3;
}

// sample()'s density in the cell of a node whose mixed sampling value is
// `value`: uniform over the sphere for a mix whose total is not positive.
float density_from(const TableBsdf::Mix& m, float value) {
  constexpr float kUniformPdf = TableBsdf::kUniform / (4 * kPi);
  const float total = m.rows[TableBsdf::kTheta];
  if (!(total > 0)) return 1 / (4 * kPi);
  return (1 - TableBsdf::kUniform) * value / total + kUniformPdf;
}

// A 32-bit integer hash (the finaliser of MurmurHash3): every input bit
// reaches every output bit.
uint32_t hash32(uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

// A direction in the frame (t, b, n): its components along them.
Vec3 to_local(Vec3 w, Vec3 t, Vec3 b, Vec3 n) { return k::kv3(k::kv3_dot(w, t), k::kv3_dot(w, b), k::kv3_dot(w, n)); }

}  // namespace

YarnHitParts::YarnHitParts(const KnitMaterial& material, const k::KnitLineHit& h, Vec3 wo)
    : sh_(material.point_shade(base_, h, wo.z < 0)) {
  // Colours (1, 0, 0) and (0, 1, 0) put the two body lobes in channels x
  // and y, the colour-free part in z.
  sh_.kd_r = Rgb{1, 0, 0};
  sh_.kd_t = Rgb{0, 1, 0};
  bsdf_ = material.kernel_bsdf(sh_);
  n_ = k::kv3_normalize(sh_.sn);
  t_ = k::kv3_normalize(k::kv3_sub(sh_.st, k::kv3_scale(n_, k::kv3_dot(sh_.st, n_))));
  b_ = k::kv3_cross(n_, t_);
  wo_l_ = to_local(wo, t_, b_, n_);
}

Vec3 YarnHitParts::parts(Vec3 wi) const {
  const Vec3 f = k::yarn_bsdf_eval(bsdf_, wo_l_, to_local(wi, t_, b_, n_));
  return k::kv3(f.z, f.x - f.z, f.y - f.z);
}

Vec3 TableBsdf::node_direction(int node) {
  const int it = node / kPhi, ip = node % kPhi;
  const float th = float(it) * kDTheta, ph = float(ip) * kDPhi;
  return k::kv3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
}

namespace {
// The theta rows' cells (theta within half a node spacing of the row's,
// clipped to [0, pi]): the cosines of their edges and their solid angles.
struct ThetaCells {
  std::array<float, TableBsdf::kTheta + 1> cos_edge;
  std::array<float, TableBsdf::kTheta> omega;
  ThetaCells() {
    for (int i = 0; i <= TableBsdf::kTheta; ++i)
      cos_edge[size_t(i)] = std::cos(std::clamp((float(i) - 0.5f) * kDTheta, 0.0f, kPi));
    for (int i = 0; i < TableBsdf::kTheta; ++i) omega[size_t(i)] = (cos_edge[size_t(i)] - cos_edge[size_t(i) + 1]) * kDPhi;
  }
};
const ThetaCells kThetaCells;
}  // namespace

float TableBsdf::cell_solid_angle(int i) { return kThetaCells.omega[size_t(i)]; }

TableBsdf::TableBsdf(const KnitMaterial& material, const FootprintTable& table, int hits_per_view,
                     int march_stride, Stage stage, const TableBsdf* shadows_in,
                     std::shared_ptr<const TableBsdf>* shadows_out) {
  const auto t0 = std::chrono::steady_clock::now();
  if (stage == Stage::Shadows) throw std::logic_error("TableBsdf: stage Shadows comes from shadows_out");
  const KnitSurface& surface = material.surface();
  const k::KnitGeom& g = surface.geom();
  const CapmOptions& capm = material.params().capm_options;
  const FootprintTable::ClassCells cells = FootprintTable::class_cells(surface);
  const int rays = std::max(1, hits_per_view);
  const int stride = std::max(1, march_stride);
  const int marches = std::max(1, rays / stride);
  slots_ = classes_ = table.classes_present();
  if (shadows_in && (shadows_in->stage() != Stage::Shadows || shadows_in->classes_ != classes_ ||
                     shadows_in->marches_ != marches))
    throw std::logic_error("TableBsdf: shadows_in is not the shadows of this table's geometry and settings");
  values_.assign(size_t(slots_) * kNodes * kNodes * kValues, 0);
  // The shadows, read (shadows_in) or marched and kept (shadows_out).
  std::vector<uint64_t> shadow_bits;
  if (shadows_out && !shadows_in) shadow_bits.assign(size_t(slots_) * kNodes * size_t(marches) * kShadowWords, 0);
  std::array<Vec3, kNodes> light;
  for (int l = 0; l < kNodes; ++l) light[size_t(l)] = node_direction(l);
  // The pole rows are one direction each: their first column is computed,
  // the others copy it (views) or its values (lights).
  const auto is_pole_copy = [](int node) { return (node / kPhi == 0 || node / kPhi == kTheta - 1) && node % kPhi; };
  std::vector<double> hit_frac(size_t(slots_) * kNodes, 0.0);  // per slot and view node: hits / rays
  static_assert(kTableBsdfJobsPerClass == kNodes, "table_build_units counts a job per view node");
  TableBuildProgress* const progress = table_build_progress();
  tbb::parallel_for(0, slots_ * kNodes, [&](int job) {
    const int slot = job / kNodes, view = job % kNodes;
    struct Done {  // (however the job ends)
      TableBuildProgress* p;
      ~Done() {
        if (p) p->add(kTableBsdfJobUnits);
      }
    } done{progress};
    if (is_pole_copy(view)) return;
    const std::vector<std::pair<int, int>>& list = cells[size_t(table.class_of_slot(slot))];
    const Vec3 wo = light[size_t(view)];
    // Sums over the hits of f |wi.n| per light node and channel (all), and
    // over the hits whose shadows are marched, with and without V.
    std::vector<double> all(size_t(kNodes) * 3, 0.0), lit(size_t(kNodes) * 3, 0.0), marched(size_t(kNodes) * 3, 0.0);
    int hits = 0;
    for (int m = 0; m < rays; ++m) {
      // The cell by a hash of (m, view): the class table's stride would tie
      // each cell to a stripe of the net's points, and cells of one class
      // differ here (the ply's phase runs on along the row), which biased
      // the mean by up to 15%.
      const std::pair<int, int>& cell = list[hash32(uint32_t(m) * 0x9e3779b9u ^ uint32_t(view) * 0x85ebca6bu) %
                                             list.size()];
      const Vec3 o = FootprintTable::ray_origin(g, cell, view, rays, m);
      const k::KnitCapm st = k::knit_capm_curved(g, surface.codes(), surface.colors(), o.x, o.y, wo, 0, 0,
                                                 capm.max_segment, capm.max_steps);
      if (st.state != KNIT_CAPM_HIT) continue;
      ++hits;
      const YarnHitParts hp(material, st.hit, wo);
      const bool march = m < marches;  // the net's first points: stratified too
      // (kept: every light node's shadow, whatever f is there, for other
      // yarn parameters to use)
      uint64_t* keep = march && !shadow_bits.empty()
                           ? &shadow_bits[((size_t(slot) * kNodes + size_t(view)) * size_t(marches) + size_t(m)) *
                                          kShadowWords]
                           : nullptr;
      for (int l = 0; l < kNodes; ++l) {
        if (is_pole_copy(l)) continue;
        const Vec3 p = hp.parts(light[size_t(l)]);
        const bool contributes = p.x > 0 || p.y > 0 || p.z > 0;
        if (!contributes && !keep) continue;
        const double v[3] = {double(p.x), double(p.y), double(p.z)};
        if (contributes)
          for (int c = 0; c < 3; ++c) all[size_t(l) * 3 + size_t(c)] += v[c];
        if (!march) continue;
        const bool shadowed = shadows_in ? shadows_in->shadowed(slot, view, m, l)
                                         : material.occluded_from(hp.base(), hp.shade(), light[size_t(l)], nullptr);
        if (keep && shadowed) keep[size_t(l) / 64] |= uint64_t(1) << (l % 64);
        if (!contributes) continue;
        for (int c = 0; c < 3; ++c) marched[size_t(l) * 3 + size_t(c)] += v[c];
        if (shadowed) continue;
        for (int c = 0; c < 3; ++c) lit[size_t(l) * 3 + size_t(c)] += v[c];
      }
    }
    const double inv = hits ? 1.0 / hits : 0.0;
    hit_frac[size_t(slot) * kNodes + size_t(view)] = double(hits) / rays;
    for (int l = 0; l < kNodes; ++l) {
      const size_t src = size_t(is_pole_copy(l) ? l - l % kPhi : l) * 3;
      uint16_t* out = &values_[((size_t(view) * kNodes + size_t(l)) * size_t(slots_) + size_t(slot)) * kValues];
      for (int c = 0; c < 3; ++c) out[c] = bf16(float(std::max(0.0, all[src + size_t(c)] * inv)));
      // The lit share of f over the marched hits (a ratio estimator: the
      // shadows' marches, on an eighth of the hits, are still two thirds of
      // the build's instructions, the BSDF's evaluations on all of them a
      // quarter, and those have the variance), one for the three parts,
      // weighed as a grey yarn's colours would weigh them.
      const double m = marched[src] + 0.5 * (marched[src + 1] + marched[src + 2]);
      const double v = lit[src] + 0.5 * (lit[src + 1] + lit[src + 2]);
      out[3] = bf16(float(m > 0 ? std::clamp(v / m, 0.0, 1.0) : 1.0));
    }
  });
  const size_t view_block = size_t(kNodes) * size_t(slots_) * kValues;
  for (int view = 0; view < kNodes; ++view) {
    if (!is_pole_copy(view)) continue;
    const uint16_t* src = &values_[size_t(view - view % kPhi) * view_block];
    std::copy(src, src + view_block, &values_[size_t(view) * view_block]);
    for (int slot = 0; slot < slots_; ++slot)
      hit_frac[size_t(slot) * kNodes + size_t(view)] = hit_frac[size_t(slot) * kNodes + size_t(view - view % kPhi)];
  }
  if (shadows_out) {
    std::shared_ptr<TableBsdf> sh(new TableBsdf());
    sh->slots_ = sh->classes_ = classes_;
    sh->marches_ = marches;
    sh->shadow_bits_ = shadows_in ? shadows_in->shadow_bits_ : std::move(shadow_bits);
    *shadows_out = std::move(sh);
  }
  hit_frac_ = std::move(hit_frac);
  if (stage == Stage::Finished) finish(material, table);
  seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TableBsdf TableBsdf::finished(const KnitMaterial& material, const FootprintTable& table) const {
  if (stage() != Stage::Marched) throw std::logic_error("TableBsdf::finished: the table is not of stage Marched");
  const auto t0 = std::chrono::steady_clock::now();
  TableBsdf t = *this;
  t.finish(material, table);
  t.seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

std::vector<double> TableBsdf::cell_shares(const FootprintTable& table) {
  // (counted over the whole pattern: the sample of class_cells, which the
  // build's rays start from, holds at most 1024 cells of a class, and its
  // sizes gave a large pattern's classes wrong weights)
  const std::array<double, FootprintTable::kClasses> counts = table.class_cell_counts();
  std::vector<double> share(size_t(table.classes_present()), 0.0);
  double all = 0;
  for (int slot = 0; slot < table.classes_present(); ++slot) {
    share[size_t(slot)] = counts[size_t(table.class_of_slot(slot))];
    all += share[size_t(slot)];
  }
  for (double& c : share) c /= std::max(all, 1.0);
  return share;
}

void TableBsdf::finish(const KnitMaterial& material, const FootprintTable& table) {
  const int palette = table.one_colour() ? 1 : material.params().bsdf.num_colors();
  if (material.params().table_fold && classes_ * palette <= kMaxEntries) {
    fold(material, palette, cell_shares(table), hit_frac_);
  }
  rows_.assign(size_t(slots_) * kNodes * (kTheta + 1) * 4, 0.0f);
  const auto row_sums = [&](int view, int i, int slot) {
    return &rows_[((size_t(view) * (kTheta + 1) + size_t(i)) * size_t(slots_) + size_t(slot)) * 4];
  };
  for (int view = 0; view < kNodes; ++view) {
    // Row sums over solid angle, as stored (bfloat16), and their total.
    for (int slot = 0; slot < slots_; ++slot) {
      for (int l = 0; l < kNodes; ++l) {
        const std::array<float, 4> v = value(slot, view, l);
        float* r = row_sums(view, l / kPhi, slot);
        for (int c = 0; c < 4; ++c) r[c] += cell_solid_angle(l / kPhi) * v[size_t(c)];
      }
      float* total = row_sums(view, kTheta, slot);
      for (int i = 0; i < kTheta; ++i)
        for (int c = 0; c < 4; ++c) total[c] += row_sums(view, i, slot)[c];
    }
  }
  // (the hit fractions served the fold: a finished table keeps none)
  hit_frac_ = std::vector<double>();
  derive_sampling();
}

void TableBsdf::derive_sampling() {
  static_assert(kTheta + 1 <= 16 && kPhi == 12, "srows_ holds four groups of rows, snodes_ three of nodes");
  srows_.clear();
  snodes_.clear();
  if (!folded_ || rows_.empty()) return;
  const size_t S = size_t(slots_);
  srows_.assign(size_t(kNodes) * 4 * S * 4, 0.0f);
  snodes_.assign(size_t(kNodes) * kTheta * 3 * S * 4, 0);
  for (int view = 0; view < kNodes; ++view)
    for (size_t slot = 0; slot < S; ++slot) {
      for (int i = 0; i <= kTheta; ++i)
        srows_[((size_t(view) * 4 + size_t(i / 4)) * S + slot) * 4 + size_t(i % 4)] = rows_at(view, i)[slot * 4 + 3];
      for (int l = 0; l < kNodes; ++l) {
        const int i = l / kPhi, j = l % kPhi;
        snodes_[(((size_t(view) * kTheta + size_t(i)) * 3 + size_t(j / 4)) * S + slot) * 4 + size_t(j % 4)] =
            at(view, l)[slot * kValues + 3];
      }
    }
}

namespace {
// Solves a x = b for the n columns of b (n x n, row-major, both), in
// place, by Gaussian elimination with partial pivoting.
void solve_in_place(std::vector<double>& a, std::vector<double>& b, int n) {
  const auto A = [&](int i, int j) -> double& { return a[size_t(i) * size_t(n) + size_t(j)]; };
  const auto B = [&](int i, int j) -> double& { return b[size_t(i) * size_t(n) + size_t(j)]; };
  for (int k = 0; k < n; ++k) {
    int p = k;
    for (int i = k + 1; i < n; ++i)
      if (std::fabs(A(i, k)) > std::fabs(A(p, k))) p = i;
    if (p != k)
      for (int j = 0; j < n; ++j) {
        std::swap(A(k, j), A(p, j));
        std::swap(B(k, j), B(p, j));
      }
    const double inv = 1.0 / A(k, k);
    for (int i = k + 1; i < n; ++i) {
      const double f = A(i, k) * inv;
      if (f == 0) continue;
      for (int j = k; j < n; ++j) A(i, j) -= f * A(k, j);
      for (int j = 0; j < n; ++j) B(i, j) -= f * B(k, j);
    }
  }
  for (int k = n - 1; k >= 0; --k) {
    const double inv = 1.0 / A(k, k);
    for (int j = 0; j < n; ++j) {
      double v = B(k, j);
      for (int i = k + 1; i < n; ++i) v -= A(k, i) * B(i, j);
      B(k, j) = v * inv;
    }
  }
}
}  // namespace

const std::vector<double>& TableBsdf::sphere_overlaps() {
  // The hats are products of a hat in theta and one in phi (sphere_nodes
  // interpolates linearly in each), so their overlaps are products too:
  // in phi, in closed form (2/3 of the spacing for a node with itself, 1/6
  // with a neighbour); in theta, with the sin(theta) of the solid angle, by
  // midpoint quadrature (each node's overlaps sum to its hat's integral
  // within 1e-6: TableBsdf.FoldedTableIsTheWalkInExpectation).
  static const std::vector<double> overlaps = [] {
    const double h = double(kPi) / (kTheta - 1), dphi = 2 * double(kPi) / kPhi;
    std::array<double, kTheta * kTheta> th{};
    const int steps = 4096;  // per theta interval
    for (int i = 0; i + 1 < kTheta; ++i)
      for (int k = 0; k < steps; ++k) {
        const double f = (k + 0.5) / steps, w = std::sin((i + f) * h) * h / steps;
        th[size_t(i) * kTheta + size_t(i)] += (1 - f) * (1 - f) * w;
        th[size_t(i + 1) * kTheta + size_t(i + 1)] += f * f * w;
        th[size_t(i) * kTheta + size_t(i + 1)] += (1 - f) * f * w;
        th[size_t(i + 1) * kTheta + size_t(i)] += (1 - f) * f * w;
      }
    const auto ph = [&](int j, int j2) {
      const int d = (j - j2 + kPhi) % kPhi;
      return d == 0 ? 2 * dphi / 3 : (d == 1 || d == kPhi - 1) ? dphi / 6 : 0.0;
    };
    std::vector<double> o(size_t(kNodes) * kNodes);
    for (int a = 0; a < kNodes; ++a)
      for (int b = 0; b < kNodes; ++b)
        o[size_t(a) * kNodes + size_t(b)] = th[size_t(a / kPhi) * kTheta + size_t(b / kPhi)] * ph(a % kPhi, b % kPhi);
    return o;
  }();
  return overlaps;
}

void TableBsdf::fold(const KnitMaterial& material, int colours, const std::vector<double>& cell_share,
                     const std::vector<double>& hit_frac) {
  // The walk (material_yarn.cpp, Material::bounce_table): at a yarn point
  // seen from view v, light from l arrives lit (tot q) or meets other yarn
  // of the footprint first (tot (1 - q)), yarn seen from -l, which scatters
  // what reaches it in turn. On the nodes, with quadrature weights omega
  // (below) and rev the reversed node (theta -> pi - theta, phi -> phi +
  // pi: the grid maps onto itself):
  //
  //   F_s[v][l] = Lit_s[v][l] + sum_y (sum_l' Sh_s[v][l'] omega[l'][rev y]) G[y][l],
  //   G[y][l]   = sum_s pi_s(y) F_s[y][l],
  //
  // where G is the yarn met inside the footprint, seen from view node y:
  // any class, in proportion to its share of the hits seen from y (its
  // share of the cells times its hit fraction from y), as a footprint of
  // whole pattern repeats mixes them. G solves (I - K) G = Lbar with
  // K[y][x] = sum_l' Sbar[y][l'] omega[l'][rev x], Sbar and Lbar the
  // pi-weighted Sh and Lit; then each F_s is one product. Not linear in
  // the yarn colours, so per channel and per colour of the palette: yarn
  // met inside a footprint takes its colour (a footprint of several
  // colours mixes their entries).
  //
  // The quadrature is the walk's own: eval interpolates bilinearly in theta
  // and phi, both at the shadowed light direction w and at the view -w of
  // the yarn met there, so the operator's weight between light node l and
  // the met yarn's view node x is the overlap of their hat functions,
  // omega[l][rev x] = integral over w of hat_l(w) hat_x(-w) (sphere_overlaps).
  // With each node's cell's solid angle on the diagonal instead (the hats'
  // lumped mass), the fold came out 0.2-0.5% brighter than the walk.
  const YarnBsdfParams& bp = material.params().bsdf;
  constexpr int N = kNodes;
  const std::vector<double>& omega = sphere_overlaps();
  const auto rev = [](int node) {
    return (kTheta - 1 - node / kPhi) * kPhi + (node % kPhi + kPhi / 2) % kPhi;
  };
  const size_t S = size_t(slots_), NN = size_t(N) * size_t(N);
  std::vector<double> pi(S * N, 0.0);
  for (int y = 0; y < N; ++y) {
    double sum = 0;
    for (size_t s = 0; s < S; ++s) sum += cell_share[s] * hit_frac[s * N + size_t(y)];
    for (size_t s = 0; s < S; ++s) pi[s * N + size_t(y)] = sum > 0 ? cell_share[s] * hit_frac[s * N + size_t(y)] / sum : 0;
  }
  const size_t K = size_t(colours);
  std::vector<float> out(K * S * NN * 4, 0.0f);  // [colour][slot][v][l][R, G, B, mean]
  tbb::parallel_for(0, 3 * colours, [&](int job) {  // the colours' channels apart
    const int ch = job % 3;
    const size_t k = size_t(job / 3);
    std::vector<double> lit(S * NN), sh(S * NN), a(NN), g(NN), shw(N);
    const Rgb kr = bp.reflect_colors[k], kt = bp.transmit_colors[k];
    const double kdr = ch == 0 ? kr.r : ch == 1 ? kr.g : kr.b, kdt = ch == 0 ? kt.r : ch == 1 ? kt.g : kt.b;
    for (size_t s = 0; s < S; ++s)
      for (int v = 0; v < N; ++v)
        for (int l = 0; l < N; ++l) {
          const std::array<float, 4> x = value(int(s), v, l);
          const double tot = std::max(0.0, double(x[0]) + double(x[1]) * kdr + double(x[2]) * kdt);
          const size_t i = s * NN + size_t(v) * N + size_t(l);
          lit[i] = tot * double(x[3]);
          sh[i] = tot - lit[i];
        }
    // shw = the shadowed row of view v (per slot, or pi-weighted) times
    // omega, at the met yarn's view nodes y.
    const auto shadowed_weights = [&](const double* row) {
      for (int y = 0; y < N; ++y) {
        const double* om = &omega[size_t(rev(y))];  // column rev(y) (omega is symmetric)
        double acc = 0;
        for (int l = 0; l < N; ++l) acc += row[l] * om[size_t(l) * N];
        shw[size_t(y)] = acc;
      }
    };
    std::vector<double> sbar(N);
    for (int y = 0; y < N; ++y) {
      for (int l = 0; l < N; ++l) {
        double sb = 0, lb = 0;
        for (size_t s = 0; s < S; ++s) {
          const double w = pi[s * N + size_t(y)];
          sb += w * sh[s * NN + size_t(y) * N + size_t(l)];
          lb += w * lit[s * NN + size_t(y) * N + size_t(l)];
        }
        sbar[size_t(l)] = sb;
        g[size_t(y) * N + size_t(l)] = lb;
      }
      shadowed_weights(sbar.data());
      // A row of K sums to the shadowed albedo seen from y, below one for
      // an energy-conserving yarn BSDF; the table's sampling noise could
      // put it at one or above (the series would not converge), and such a
      // row is scaled back to 0.999.
      double albedo = 0;
      for (int x = 0; x < N; ++x) albedo += shw[size_t(x)];
      const double scale = albedo > 0.999 ? 0.999 / albedo : 1.0;
      for (int x = 0; x < N; ++x) a[size_t(y) * N + size_t(x)] = (x == y ? 1.0 : 0.0) - scale * shw[size_t(x)];
    }
    solve_in_place(a, g, N);
    for (size_t s = 0; s < S; ++s)
      for (int v = 0; v < N; ++v) {
        shadowed_weights(&sh[s * NN + size_t(v) * N]);
        for (int l = 0; l < N; ++l) {
          double f = lit[s * NN + size_t(v) * N + size_t(l)];
          for (int y = 0; y < N; ++y) f += shw[size_t(y)] * g[size_t(y) * N + size_t(l)];
          out[(((k * S + s) * N + size_t(v)) * N + size_t(l)) * 4 + size_t(ch)] = float(std::max(0.0, f));
        }
      }
  });
  // (Not folded, the walk kept, should anything have come out other than
  // finite: no NaN reaches an image.)
  if (!std::all_of(out.begin(), out.end(), [](float v) { return std::isfinite(v); })) return;
  // Entry s * K + k: class slot s in colour k.
  const size_t E = S * K;
  values_.assign(E * NN * kValues, 0);
  for (size_t k = 0; k < K; ++k)
    for (size_t s = 0; s < S; ++s)
      for (int v = 0; v < N; ++v)
        for (int l = 0; l < N; ++l) {
          const float* f = &out[(((k * S + s) * N + size_t(v)) * N + size_t(l)) * 4];
          uint16_t* dst = &values_[((size_t(v) * N + size_t(l)) * E + s * K + k) * kValues];
          for (int c = 0; c < 3; ++c) dst[c] = bf16(f[c]);
          dst[3] = bf16((f[0] + f[1] + f[2]) / 3);
        }
  slots_ = int(E);
  colours_ = colours;
  folded_ = true;
}

std::array<float, 4> TableBsdf::value(int slot, int view, int l) const {
  const uint16_t* p = at(view, l) + size_t(slot) * kValues;
  return {from_bf16(p[0]), from_bf16(p[1]), from_bf16(p[2]), from_bf16(p[3])};
}

TableBsdf::Mix TableBsdf::mix(const float* slot_hits, Vec3 wo, float cr, float ct, float u_view,
                              const float* colour_w) const {
  Mix m;
  m.sw = folded_ ? std::array<float, 4>{0, 0, 0, 1} : std::array<float, 4>{1, cr, ct, 0};
  float total = 0;
  for (int s = 0; s < classes_; ++s) total += std::max(0.0f, slot_hits[s]);
  if (!(total > 0)) return m;
  // Per entry: the class's share times the colour's (one colour: a factor
  // of exactly one).
  float cw[kMaxEntries] = {1}, csum = 0;
  if (colour_w)
    for (int k = 0; k < colours_; ++k) cw[k] = std::max(0.0f, colour_w[k]);
  for (int k = 0; k < colours_; ++k) csum += cw[k];
  if (!(csum > 0)) {
    cw[0] = 1;
    csum = 1;
  }
  for (int s = 0; s < classes_; ++s)
    for (int k = 0; k < colours_; ++k)
      m.share[size_t(s * colours_ + k)] = std::max(0.0f, slot_hits[s]) / total * (cw[k] / csum);
  remix(m, wo, u_view);
  return m;
}

void TableBsdf::remix(Mix& m, Vec3 wo, float u_view) const {
  m.n = 0;
  const SphereNodes c = sphere_nodes(wo, kTheta, kPhi);
  if (u_view >= 0) {
    // One node, with probability its weight (the last one with weight
    // when rounding leaves u_view past the sum).
    float acc = 0;
    for (int q = 0; q < 4; ++q) {
      if (!(c.w[size_t(q)] > 0)) continue;
      m.view[0] = c.node[size_t(q)];
      m.w[0] = 1;
      m.n = 1;
      acc += c.w[size_t(q)];
      if (u_view < acc) break;
    }
  } else {
    for (int q = 0; q < 4; ++q) {
      if (!(c.w[size_t(q)] > 0)) continue;
      m.view[size_t(m.n)] = c.node[size_t(q)];
      m.w[size_t(m.n)] = c.w[size_t(q)];
      ++m.n;
    }
  }
  // The sampling rows, once per shading point (sample and pdf read them):
  // the view node's rows of every class lie together.
  if (!srows_.empty()) {
    // Folded: the sampling values alone, four rows a vector.
    std::array<F4, 4> sum;
    mixed_sums(
        m, slots_, [&](int view) { return &srows_[size_t(view) * 4 * size_t(slots_) * 4]; },
        [](const float* p, int i) { return load4(p + 4 * i); }, sum);
    for (int i = 0; i <= kTheta; ++i) m.rows[size_t(i)] = sum[size_t(i / 4)][i % 4];
    return;
  }
  std::array<F4, kTheta + 1> sum;
  mixed_sums(
      m, slots_, [&](int view) { return rows_at(view, 0); }, [](const float* p, int i) { return load4(p + 4 * i); },
      sum);
  for (int i = 0; i <= kTheta; ++i) m.rows[size_t(i)] = sampling_value(m, sum[size_t(i)]);
}

Vec3 TableBsdf::eval(const Mix& m, Vec3 wi, Vec3 kd_r, Vec3 kd_t, Vec3* total, float* density_out) const {
  const SphereNodes c = sphere_nodes(wi, kTheta, kPhi);
  // Sums of the lit parts (A, Br, Bt times the lit share) and, when asked,
  // of the parts themselves, four lanes at a time; the classes of a pair of
  // nodes lie side by side. One sum per light node: four chains of
  // additions side by side, not one four times as long.
  F4 lit0{}, lit1{}, lit2{}, lit3{}, all0{}, all1{}, all2{}, all3{};
  // The density's node (the heaviest corner) is one of the four read here:
  // its mixed value is summed on the way, term by term as node_value sums
  // it, so the density is the same to the bit without reading it again.
  const int q = heaviest_corner(c);
  F4 nq{};
  if (folded_) {
    // The folded values: the channels themselves, nothing shadowed.
    for (int t = 0; t < m.n; ++t) {
      const int v = m.view[size_t(t)];
      const uint16_t *p0 = at(v, c.node[0]), *p1 = at(v, c.node[1]), *p2 = at(v, c.node[2]), *p3 = at(v, c.node[3]);
      for (int s = 0; s < slots_; ++s) {
        const float ws = m.w[size_t(t)] * m.share[size_t(s)];
        const F4 v0 = bf16x4(p0 + kValues * s), v1 = bf16x4(p1 + kValues * s), v2 = bf16x4(p2 + kValues * s),
                 v3 = bf16x4(p3 + kValues * s);
        lit0 += (ws * c.w[0]) * v0;
        lit1 += (ws * c.w[1]) * v1;
        lit2 += (ws * c.w[2]) * v2;
        lit3 += (ws * c.w[3]) * v3;
        nq += ws * corner_value(q, v0, v1, v2, v3);
      }
    }
    const F4 f = (lit0 + lit1) + (lit2 + lit3);
    const Vec3 r = k::kv3(f[0], f[1], f[2]);
    if (total) *total = r;
    if (density_out) *density_out = density_from(m, nq[3]);  // (sampling_value, folded)
    return r;
  }
  for (int t = 0; t < m.n; ++t) {
    const int v = m.view[size_t(t)];
    const uint16_t *p0 = at(v, c.node[0]), *p1 = at(v, c.node[1]), *p2 = at(v, c.node[2]), *p3 = at(v, c.node[3]);
    for (int s = 0; s < slots_; ++s) {
      const float ws = m.w[size_t(t)] * m.share[size_t(s)];
      const float w0 = ws * c.w[0], w1 = ws * c.w[1], w2 = ws * c.w[2], w3 = ws * c.w[3];
      const F4 v0 = bf16x4(p0 + kValues * s), v1 = bf16x4(p1 + kValues * s), v2 = bf16x4(p2 + kValues * s),
               v3 = bf16x4(p3 + kValues * s);
      lit0 += (w0 * v0[3]) * v0;
      lit1 += (w1 * v1[3]) * v1;
      lit2 += (w2 * v2[3]) * v2;
      lit3 += (w3 * v3[3]) * v3;
      if (total) {
        all0 += w0 * v0;
        all1 += w1 * v1;
        all2 += w2 * v2;
        all3 += w3 * v3;
      }
      nq += ws * corner_value(q, v0, v1, v2, v3);
    }
  }
  const F4 lit = (lit0 + lit1) + (lit2 + lit3);
  const F4 all = (all0 + all1) + (all2 + all3);
  const auto rgb = [&](const F4& v) {
    return k::kv3(v[0] + v[1] * kd_r.x + v[2] * kd_t.x, v[0] + v[1] * kd_r.y + v[2] * kd_t.y,
                  v[0] + v[1] * kd_r.z + v[2] * kd_t.z);
  };
  if (total) *total = rgb(all);
  if (density_out) *density_out = density_from(m, sampling_value(m, nq));
  return rgb(lit);
}

float TableBsdf::node_value(const Mix& m, int l) const {
  std::array<F4, 1> v;
  mixed_sums(
      m, slots_, [&](int view) { return at(view, l); },
      [](const uint16_t* p, int i) { return bf16x4(p + kValues * i); }, v);
  return sampling_value(folded_, m, v[0]);
}

float TableBsdf::pdf(const Mix& m, Vec3 wi) const { return density(m, sphere_nodes(wi, kTheta, kPhi)); }

float TableBsdf::density(const Mix& m, const SphereNodes& c) const {
  return density_from(m, node_value(m, c.node[size_t(heaviest_corner(c))]));
}

bool TableBsdf::sample(const Mix& m, float u0, float u1, float u2, Vec3& wi, float* pdf_out, float* u_rest) const {
  if (m.n == 0) return false;
  const float total = m.rows[kTheta];
  float z, ph;
  if (!(total > 0) || u0 < kUniform) {
    z = 1 - 2 * u1;  // uniform over the sphere
    ph = 2 * kPi * u2;
    if (u_rest) *u_rest = total > 0 ? u0 / kUniform : u0;
  } else {
    // A light node's cell in proportion to its value times its solid
    // angle: the theta row first, then the node in it.
    float target = (u0 - kUniform) / (1 - kUniform) * total;
    int i = 0;
    for (; i < kTheta - 1; ++i) {
      const float r = m.rows[size_t(i)];
      if (target < r) break;
      target -= r;
    }
    // The row's node values in one pass over each term's contiguous row
    // (its nodes, each with its classes); folded, the sampling values
    // alone, four nodes a vector.
    std::array<float, kPhi> nv;
    if (!snodes_.empty()) {
      std::array<F4, kPhi / 4> row;
      mixed_sums(
          m, slots_, [&](int view) { return &snodes_[(size_t(view) * kTheta + size_t(i)) * 3 * size_t(slots_) * 4]; },
          [](const uint16_t* p, int k) { return bf16x4(p + 4 * k); }, row);
      for (int j = 0; j < kPhi; ++j) nv[size_t(j)] = row[size_t(j / 4)][j % 4];
    } else {
      std::array<F4, kPhi> row;
      mixed_sums(
          m, slots_, [&](int view) { return at(view, i * kPhi); },
          [](const uint16_t* p, int k) { return bf16x4(p + kValues * k); }, row);
      for (int j = 0; j < kPhi; ++j) nv[size_t(j)] = sampling_value(m, row[size_t(j)]);
    }
    const float om = cell_solid_angle(i);
    int j = 0;
    float v = 0;
    for (; j < kPhi; ++j) {
      v = nv[size_t(j)] * om;
      if (target < v || j == kPhi - 1) break;
      target -= v;
    }
    if (u_rest) *u_rest = v > 0 ? std::clamp(target / v, 0.0f, 0.99999994f) : 0.5f;
    const float clo = kThetaCells.cos_edge[size_t(i)], chi = kThetaCells.cos_edge[size_t(i) + 1];
    z = clo + (chi - clo) * u1;
    ph = (float(j) - 0.5f + u2) * kDPhi;
  }
  const float s = std::sqrt(std::max(0.0f, 1 - z * z));
  wi = k::kv3(s * std::cos(ph), s * std::sin(ph), z);
  if (pdf_out) *pdf_out = pdf(m, wi);
  return true;
}

}  // namespace knit
