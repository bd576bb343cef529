// FootprintTable: multi-scale aggregation for footprints of a stitch cell or
// more, without marching (docs/multiscale.md, "Footprints of cells: the
// class table").
//
// Over a footprint that covers whole cells, the aggregate of
// knit_aggregate is an average over cells of what each cell shows from the
// view direction. A cell's geometry is set by its stitch code and the depth
// signs its neighbours above and below give it (stitch.h), so cells fall
// into at most ten classes: knit or purl with head and sinker signs each
// + or -, and the two slip stitches. The table holds, per class present in
// the pattern and per view direction on a (theta, phi) grid over the whole
// sphere, the CAPM statistics of rays spread over the cells of that class:
// hit fraction, mean normal and tangent, slope moments, mean layer count and
// height. A footprint's aggregate is then the hit-weighted sum over the
// cells it covers (bilinear in direction), at a cost independent of the
// number of marches it replaces.
//
// Colours: a ray entering cell (k, c) may hit the yarn of a neighbouring
// cell (loops overlap, and oblique rays travel); the table keeps, per class
// and direction, the share of hits on each cell of the 3 x 3 block around
// the entry cell, and a footprint's colour histogram mixes the neighbours'
// colours with those shares.
//
// What it leaves out: the blend with a left or right neighbour of another
// profile, the curvature of the base (the table is built on a flat base),
// and hits more than one cell away from the entry cell (counted as the
// nearest of the 3 x 3 block). tests/native/test_footprint_table.cpp
// measures it against explicit tubes and against the marched aggregate.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <optional>
#include <utility>
#include <vector>

#include "knit/fast_math.h"
#include "knit/surface.h"

namespace knit {

// The four nodes around unit direction d on a (theta, phi) grid over the
// whole sphere, theta nodes i pi / (theta_nodes - 1), phi nodes
// j 2 pi / phi_nodes (node = i phi_nodes + j), and their bilinear weights:
// the direction grids of the class table and of its tabulated BSDF.
struct SphereNodes {
  std::array<int, 4> node;
  std::array<float, 4> w;
};
// (Inline: every table lookup starts here.)
inline SphereNodes sphere_nodes(Vec3 wi, int theta_nodes, int phi_nodes) {
  constexpr float pi = 3.14159265358979f;
  const float th = atan2_coarse(std::sqrt(wi.x * wi.x + wi.y * wi.y), wi.z);  // in [0, pi]
  float ph = atan2_coarse(wi.y, wi.x);
  if (ph < 0) ph += 2 * pi;
  const float ft = std::clamp(th / pi * float(theta_nodes - 1), 0.0f, float(theta_nodes - 1));
  const int i0 = std::min(int(ft), theta_nodes - 1), i1 = std::min(i0 + 1, theta_nodes - 1);
  const float wt = ft - float(i0);
  const float fp = ph / (2 * pi) * float(phi_nodes);
  const int j0 = std::min(int(fp), phi_nodes - 1), j1 = j0 + 1 < phi_nodes ? j0 + 1 : 0;
  const float wp = std::clamp(fp - float(j0), 0.0f, 1.0f);
  SphereNodes d;
  d.node = {i0 * phi_nodes + j0, i0 * phi_nodes + j1, i1 * phi_nodes + j0, i1 * phi_nodes + j1};
  d.w = {(1 - wt) * (1 - wp), (1 - wt) * wp, wt * (1 - wp), wt * wp};
  return d;
}

// std::lround for a count or mean that is >= 0 and far below 2^31: the
// same value (in double, v + 0.5 is exact and truncation is the floor),
// without libm's call (0.5% of a multi-scale render's instructions).
inline int round_count(float v) { return int(double(v) + 0.5); }

class FootprintTable {
 public:
  static constexpr int kThetaBins = 24;  // nodes i pi / 23 over [0, pi] (both sides; none at the horizon)
  static constexpr int kPhiBins = 16;    // nodes j 2 pi / 16
  static constexpr int kClasses = 10;

  // How the build counts the layers under its hits: Auto batches them
  // (KnitSurface::query_batch) where the CPU has a vector path, else one
  // counting query at a time, as Scalar always does (for tests).
  enum class LayerCounts { Auto, Scalar };
  // Marches `rays_per_direction` rays (flat base) per class present and per
  // direction; uses every hardware thread.
  // sub_cells: also keep the per-sub-cell statistics (aggregate_sub) and,
  // with eighths, the hit fractions per eighth of a cell; a table without
  // sub-cells takes 36 KiB per class present instead of 276 KiB (372 KiB
  // for patterns of several colour indices; 48 KiB less without eighths).
  FootprintTable(const KnitSurface& surface, const CapmOptions& capm, int rays_per_direction = 256,
                 LayerCounts layer_counts = LayerCounts::Auto, bool sub_cells = true, bool eighths = true);
  bool has_sub_cells() const { return !sub_moments_.empty(); }
  bool has_eighths() const { return !eighth_hits_.empty(); }
  // The node statistics (kMoments floats per class present and direction
  // node), for tests.
  const std::vector<float>& node_moments() const { return moments_; }

  // The aggregate over footprint f (stratified: a cell or more in both
  // directions, see knit_footprint) seen from wi_local (unit, towards the
  // viewer, either side). The geometry averages every cell of f's box,
  // counted per class (class_counts); the colours of a pattern of several
  // colour indices visit the box's cells when there are at most
  // KNIT_MS_MAX_POINTS of them, else the cells of f's points. (Without
  // prefix counts, a pattern too large for them, the geometry visits the
  // same cells as the colours.)
  // slot_hits (kClasses floats, when given): per class slot, the box's
  // share of cells of that class times its hit fraction (TableBsdf::mix).
  k::KnitAggregate aggregate(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi_local,
                             float* slot_hits = nullptr) const;
  // Only its p_delta (shadow rays; and with slot_hits, zeroed by the
  // caller, the per-slot hits as aggregate gives them, up to scale: all a
  // footprint of one colour index shaded with the tabulated BSDF needs).
  float p_delta(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi_local,
                float* slot_hits = nullptr) const;

  // Footprints of half a cell or more (docs/multiscale.md, "Footprints
  // below a cell: sub-cells"): the table also keeps each class's statistics
  // per sub-cell, a quarter of the cell on a side (kSub x kSub of them,
  // from the same rays, stored as bfloat16), and a
  // box of ex x ey cells centred on pattern point (x, y) is the sum over
  // the sub-cells it overlaps, each weighted by the area of the overlap.
  // The hit fractions alone are also kept per eighth of a cell (kEighth x
  // kEighth, "Eighths of a cell: the gaps"): a box that touches at most
  // kMaxEighthBox of them takes its hit fraction and per-class hits (its
  // p_delta, and the tabulated BSDF's mix) from the eighths, its means
  // from the quarters.
  // Its domain: at least kMinSubBox (a quarter) of a cell in both
  // directions and at most kMaxSubBox sub-cells touched (sub_box). Bigger boxes take aggregate()'s
  // whole cells. `pick` in [0, 1) picks the colour of one hit sub-cell for
  // patterns with more colours than the histogram has bins.
  static constexpr int kSub = 4;
  static constexpr int kMaxSubBox = 64;
  static constexpr int kEighth = 8;
  static constexpr int kMaxEighthBox = 64;
  static constexpr float kMinSubBox = 0.25f;  // cells: one sub-cell on a side
  static bool sub_box(float x, float y, float ex, float ey, const k::KnitGeom& g);
  // A box sub_box accepted, in sub-cell units: only sub_box_at makes one,
  // so the overloads taking it need not check it again (the routing of a
  // hit checks once, shades and attenuates with it).
  class SubBox {
   private:
    friend class FootprintTable;
    struct Range {
      double lo, hi;  // the box, in sub-cells (exact doubles: x / cw in float loses the sub-cell at 1e4 units)
      int64_t first, last;  // the sub-cells it touches
      // The box's overlap with sub-cell i (<= 0: none).
      double overlap(int64_t i) const { return std::min(hi, double(i + 1)) - std::max(lo, double(i)); }
    };
    Range rx{}, ry{};
    Range rx8{}, ry8{};     // the same box in eighths of a cell
    bool eighths_ = false;  // it touches at most kMaxEighthBox of them
    float x_ = 0, y_ = 0;
  };
  // The box of ex x ey cells at (x, y), when sub_box accepts it.
  static std::optional<SubBox> sub_box_at(float x, float y, float ex, float ey, const k::KnitGeom& g);
  // slot_hits (kClasses floats, zeroed by the caller, when given): per
  // class slot, the box's area share of that class times its sub-cells'
  // hit fractions, summed. The overloads taking coordinates throw for a
  // box sub_box refuses and for a table without sub-cells; those taking a
  // SubBox only for the latter.
  k::KnitAggregate aggregate_sub(const KnitSurface& surface, float x, float y, float ex, float ey, Vec3 wi_local,
                                 float pick = 0.5f, float* slot_hits = nullptr) const;
  k::KnitAggregate aggregate_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi_local, float pick = 0.5f,
                                 float* slot_hits = nullptr) const;
  float p_delta_sub(const KnitSurface& surface, float x, float y, float ex, float ey, Vec3 wi_local,
                    float* slot_hits = nullptr) const;
  float p_delta_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi_local, float* slot_hits = nullptr) const;
  // A box's hits at the four direction nodes around a direction, before
  // their bilinear weights: per node, the box's hits and each class
  // slot's, as areas, over its area `total`. p_delta_sub is these blended
  // by the direction's weights (the blend of four hit fractions is a
  // fraction, so the sums are linear in the nodes' values). A renderer
  // that reads one box in many directions close together (the camera
  // samples of a pixel; FootprintMemo) keeps them: the overload below
  // sums the box only when `sums` holds other nodes, and then keeps the
  // new sums there. `sums` must belong to this table and this box.
  struct NodeSums {
    std::array<int32_t, 4> node{{-1, -1, -1, -1}};
    std::array<double, 4> hits{};
    std::array<std::array<double, 4>, kClasses> by_slot{};
    double total = 0;
  };
  float p_delta_sub(const KnitSurface& surface, const SubBox& box, Vec3 wi_local, float* slot_hits,
                    NodeSums& sums) const;
  // The per-sub-cell statistics (kMoments floats per class present,
  // sub-cell and direction node, as stored: rounded to bfloat16; the
  // neighbour shares zero for a pattern of one colour index), for tests.
  std::vector<float> sub_moments() const;
  // The hit fraction per class present, eighth of a cell (sy * kEighth +
  // sx) and direction node, as stored (bfloat16); empty without eighths.
  // For tests.
  std::vector<float> eighth_hits() const;
  bool one_colour() const { return one_colour_; }

  // Class (0..9) of cell (row k from the bottom, column c) of the surface.
  static int cell_class(const KnitSurface& surface, int k, int c);
  // The (row, column) cells of each class the build spreads its rays over:
  // all of them, or a uniform sample of 1024 for a large pattern.
  using ClassCells = std::array<std::vector<std::pair<int, int>>, kClasses>;
  static ClassCells class_cells(const KnitSurface& surface);
  // How many cells of each class the pattern holds: all of them, where
  // class_cells keeps a sample of a large pattern's.
  std::array<double, kClasses> class_cell_counts() const;
  // Where ray m of `rays` for direction node `node` enters cell `cell`
  // (pattern x, y; z 0): a (0,2)-net over the cell, different per node;
  // `sub` and `eighth`, when given, receive its sub-cell and its eighth.
  static Vec3 ray_origin(const k::KnitGeom& g, const std::pair<int, int>& cell, int node, int rays, int m,
                         int* sub = nullptr, int* eighth = nullptr);
  // The slot of class cls (-1 when absent) and the class of a slot.
  int slot_of(int cls) const { return slot_[size_t(cls)]; }
  int class_of_slot(int slot) const { return class_of_slot_[size_t(slot)]; }
  // How many cells of each class f's box holds, as the aggregate counts
  // them (all -1 when the table cannot count them: it then visits the
  // cells), and the periods it counts over. For tests.
  std::array<double, kClasses> box_counts(const k::KFootprint& f) const {
    std::array<double, kClasses> counts;
    if (!class_counts(f, counts)) counts.fill(-1);
    return counts;
  }
  // Whether aggregate() and p_delta() read no footprint points (and so no
  // sample shift): one colour index, and cells counted per class.
  bool counts_without_points() const { return one_colour_ && can_count(); }
  int period_rows() const { return period_rows_; }
  int period_cols() const { return period_cols_; }

  size_t bytes() const {
    return sizeof(*this) + moments_.size() * sizeof(float) + sub_moments_.size() * sizeof(uint16_t) +
           eighth_hits_.size() * sizeof(uint16_t) + class_of_.size() + prefix_.size() * sizeof(uint16_t);
  }
  int classes_present() const { return slots_; }

 private:
  friend struct TableCacheCodec;  // reads and writes the state below (src/table_cache.cpp)
  FootprintTable() = default;     // (for TableCacheCodec, which fills it)
  // The four grid nodes around a direction and their bilinear weights.
  using DirWeights = SphereNodes;  // node = theta * kPhiBins + phi
  static DirWeights dir_weights(Vec3 wi_local) { return sphere_nodes(wi_local, kThetaBins, kPhiBins); }
  // A node's statistics as the table keeps them, kMoments floats: the hit
  // fraction, then the hit-conditioned means times the hit fraction (so
  // that any mix of nodes and classes is one weighted sum, its hit-weighted
  // means that sum over its hit fraction), then the unit mean tangent times
  // the hit fraction.
  enum Moment : int {
    kHit = 0,      // fraction of the rays that hit yarn
    kNormal = 1,   // nx, ny, nz: hit normal (the mean is not normalised)
    kSlope = 4,    // sx, sy: slopes of the hit normal (knit_ms_slopes)
    kSlope2 = 6,   // sxx, sxy, syy: their second moments
    kLayers = 9,   // layer count under the hit
    kZ = 10,       // hit height
    kNear = 11,    // 9 shares of the hits on the yarn of cell (k + dk, c + dc), at (dk + 1) * 3 + dc + 1
    kLinear = 20,  // the moments above mix linearly
    kTangent = 20, // tx, ty, tz (times hit): a line, mixed sign-aligned
    kMoments = 24,
    // A sub-cell node of a one-colour pattern: kHit..kZ and a zero (the
    // first neighbour share's place), then the tangent and a zero.
    kSubLinear1 = 12,
    kSubStride1 = 16
  };
  const float* moments(int slot, int node) const {
    return &moments_[(size_t(slot) * kThetaBins * kPhiBins + size_t(node)) * kMoments];
  }
  // Node `node` of sub-cell `sub` of class slot `slot`, unpacked into m
  // (kMoments floats; with one colour index the neighbour shares, which
  // are not kept, read as zeros).
  void sub_node(int slot, int sub, int node, float* m) const {
    const uint16_t* p = sub_node_at(slot * kSub * kSub + sub, node);
    if (!one_colour_) {
      for (int i = 0; i < kMoments; ++i) m[i] = from_bf16(p[i]);
      return;
    }
    for (int i = 0; i < kMoments; ++i) m[i] = 0.0f;
    for (int i = 0; i < kSubLinear1; ++i) m[i] = from_bf16(p[i]);
    for (int i = 0; i < 3; ++i) m[kTangent + i] = from_bf16(p[kSubLinear1 + i]);
  }
  // The stored node `node` of (class slot, sub-cell) pair `pair` (slot *
  // kSub^2 + sub-cell), and a stored value read back as a float.
  // Where eighth_hits_ keeps the hit fraction of (class slot, direction
  // node, eighth).
  static size_t eighth_index(int slot, int node, int eighth) {
    return (size_t(slot) * kThetaBins * kPhiBins + size_t(node)) * kEighth * kEighth + size_t(eighth);
  }
  const uint16_t* sub_node_at(int pair, int node) const {
    const size_t stride = one_colour_ ? size_t(kSubStride1) : size_t(kMoments);
    return &sub_moments_[(size_t(pair) * kThetaBins * kPhiBins + size_t(node)) * stride];
  }
  static float from_bf16(uint16_t v) {
    const uint32_t bits = uint32_t(v) << 16;
    float f;
    std::memcpy(&f, &bits, sizeof f);
    return f;
  }
  // The overlap areas of a box (see aggregate_sub) summed per (class slot,
  // sub-cell) pair, their total and the sub-cells touched (the areas of
  // the slots present only: the rest is left uncleared).
  struct SubAreas {
    std::array<double, kClasses * kSub * kSub> area;
    double total = 0;
    int touched = 0;
  };
  SubAreas sub_areas(const k::KnitGeom& g, const SubBox& box) const;
  // The box at (x, y) for the overloads taking coordinates: throws for a
  // table without sub-cells or a box outside their domain, naming `caller`.
  SubBox checked_sub_box(const k::KnitGeom& g, float x, float y, float ex, float ey, const char* caller) const;
  void check_sub_cells(const char* caller) const;
  // The sub-cells a box touches and their overlap areas: calls
  // visit(row k, column c, the cell's index in class_of_ (knit_cell_index),
  // sub-cell index, area) for each; S sub-cells a side (kSub, or kEighth
  // with the box's eighths' ranges).
  template <int S = kSub, class Visit>
  static void for_each_sub(const k::KnitGeom& g, const SubBox::Range& rx, const SubBox::Range& ry, Visit&& visit);
  // The box's NodeSums over its ranges rx, ry of S sub-cells a cell:
  // hit4(slot, sub-cell) the hit fractions of a (slot, sub-cell) pair at
  // the four nodes; where the box folds onto one cell per class,
  // cell_sum(slot, wx, wy, rows) the sum over the cell's sub-cells of
  // wy[row] wx[column] times their four fractions, over the rows whose
  // bits are set in `rows` (those with wy > 0).
  template <int S, class Hit4, class CellSum>
  void sum_hits(const k::KnitGeom& g, const SubBox::Range& rx, const SubBox::Range& ry, Hit4&& hit4,
                CellSum&& cell_sum, NodeSums& sums) const;
  // p_delta_sub's blend of `sums` by the direction's weights.
  float blend(const NodeSums& sums, const DirWeights& dw, float* slot_hits) const;
  // Fills a from `points`, the box's p_delta, its summed moments `sum`
  // (kLinear floats) and tangent sum `tsum`: the hit count, and the
  // hit-weighted means (normal, tangent, height at (x, y), slope covariance,
  // layers). False when nothing is hit (a has the defaults of a miss).
  static bool finish(k::KnitAggregate& a, int points, float p_delta, const float* sum, Vec3 tsum, float x, float y);
  float hit_fraction(int cls, const DirWeights& d) const;  // bilinear in direction
  float slot_hit_fraction(int slot, const DirWeights& d) const;  // the same by slot
  // The shares of a class's hits on the 3 x 3 block around the cell, in direction d.
  std::array<float, 9> near_shares(int cls, const DirWeights& d) const;
  // Visits (class, row, column) of the cells of f.
  template <class Visit>
  void for_each_cell(const KnitSurface& surface, const k::KFootprint& f, Visit&& visit) const;
  // Whether for_each_cell visits every cell of f's box (at most
  // KNIT_MS_MAX_POINTS of them), else the cells of f's points; how many.
  static bool all_cells(const k::KFootprint& f) {
    return int64_t(f.ncx) * int64_t(f.ncy) <= KNIT_MS_MAX_POINTS;  // up to 1e5 x 1e5 cells: no int product
  }
  // The number of cells of each class for f without visiting them: all of
  // them for a pattern of one class, else from the per-row
  // prefix counts, a few additions per row of the box (at most one pass over
  // the pattern's rows for a box of any height) instead of a visit per cell;
  // false when there are no prefix counts (a pattern too large for them).
  bool class_counts(const k::KFootprint& f, std::array<double, kClasses>& counts) const;
  // Whether class_counts can count (one class, or prefix counts).
  bool can_count() const { return single_class_ >= 0 || !prefix_.empty(); }
  // p_delta of cells counted by class (1 for none), seen from direction d.
  float pass_of(const std::array<double, kClasses>& counts, const DirWeights& d, float* slot_hits = nullptr) const;

  std::array<int, kClasses> slot_{};  // index into moments_ blocks, -1 when the class is absent
  int slots_ = 0;                     // classes present
  std::vector<float> moments_;       // [slot][theta][phi][kMoments]
  // [slot][sub-cell][theta][phi][kMoments, or kSubStride1 with one colour
  // index: the neighbour shares only serve the colours], sub-cell =
  // sy * kSub + sx, as bfloat16: a float's upper half, rounded to nearest
  // (8 significant bits, 0.4% at most, far below the statistics' sampling
  // error of several percent), read back by a shift.
  std::vector<uint16_t> sub_moments_;
  // [slot][theta][phi][eighth]: the hit fraction per eighth of a cell on a
  // side (sy * kEighth + sx), as bfloat16 (a lookup reads the 64 of each
  // of its four direction nodes together); empty without sub-cells.
  std::vector<uint16_t> eighth_hits_;
  std::vector<unsigned char> class_of_;  // class of each pattern cell, by knit_cell_index
  bool one_colour_ = true;               // every cell has colour index 0
  int single_class_ = -1;                // the class of every cell, when the pattern has one
  // The smallest row and column periods of class_of_ (divisors of the
  // pattern's rows and columns), over which class_counts counts.
  int period_rows_ = 1, period_cols_ = 1;
  // Per period row (as in class_of_) and slot: how many of the row's first
  // c cells have that slot's class, c = 0..period_cols_; empty when there is
  // one class or period_rows_ x slots x (period_cols_ + 1) exceeds kMaxPrefix.
  static constexpr size_t kMaxPrefix = size_t(1) << 16;
  std::vector<uint16_t> prefix_;
  std::array<int, kClasses> class_of_slot_{};
};

}  // namespace knit
