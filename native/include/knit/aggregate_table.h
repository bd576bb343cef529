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

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "knit/surface.h"

namespace knit {

class FootprintTable {
 public:
  static constexpr int kThetaBins = 24;  // nodes i pi / 23 over [0, pi] (both sides; none at the horizon)
  static constexpr int kPhiBins = 16;    // nodes j 2 pi / 16
  static constexpr int kClasses = 10;

  // Marches `rays_per_direction` rays (flat base) per class present and per
  // direction; uses every hardware thread.
  FootprintTable(const KnitSurface& surface, const CapmOptions& capm, int rays_per_direction = 256);

  // The aggregate over footprint f (stratified: a cell or more in both
  // directions, see knit_footprint) seen from wi_local (unit, towards the
  // viewer, either side). The geometry averages every cell of f's box,
  // counted per class (class_counts); the colours of a pattern of several
  // colour indices visit the box's cells when there are at most
  // KNIT_MS_MAX_POINTS of them, else the cells of f's points. (Without
  // prefix counts, a pattern too large for them, the geometry visits the
  // same cells as the colours.)
  k::KnitAggregate aggregate(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi_local) const;
  // Only its p_delta (shadow rays).
  float p_delta(const KnitSurface& surface, const k::KFootprint& f, Vec3 wi_local) const;

  // Class (0..9) of cell (row k from the bottom, column c) of the surface.
  static int cell_class(const KnitSurface& surface, int k, int c);

  size_t bytes() const {
    return sizeof(*this) + stats_.size() * sizeof(Stats) + class_of_.size() + prefix_.size() * sizeof(uint16_t);
  }
  int classes_present() const;

 private:
  struct Stats {
    float hit = 0;                   // fraction of rays that hit yarn
    float nx = 0, ny = 0, nz = 1;    // mean hit normal (not normalised)
    float tx = 1, ty = 0, tz = 0;    // mean tangent (sign-aligned, unit)
    float sx = 0, sy = 0;            // mean slopes
    float sxx = 0, sxy = 0, syy = 0; // slope second moments
    float layers = 0;                // mean layer count under the hits
    float z = 0;                     // mean hit height
    float near[9] = {};              // share of the hits on yarn of cell (k + dk, c + dc), dk, dc in -1..1
  };
  // The four grid nodes around a direction and their bilinear weights.
  struct DirWeights {
    std::array<int, 4> node;  // theta * kPhiBins + phi
    std::array<float, 4> w;
  };
  static DirWeights dir_weights(Vec3 wi_local);
  Stats lookup(int cls, const DirWeights& d) const;
  float hit_fraction(int cls, const DirWeights& d) const;  // lookup(cls, d).hit alone
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
  bool class_counts(const KnitSurface& surface, const k::KFootprint& f, std::array<double, kClasses>& counts) const;
  // Adds the counted cells to `cells`, their hits to `hits` and sets the
  // hits by class, from the classes' hit fractions in direction d.
  void counted_hits(const std::array<double, kClasses>& counts, const DirWeights& d,
                    std::array<double, kClasses>& cls_hits, double& cells, double& hits) const;

  std::array<int, kClasses> slot_{};  // index into stats_ blocks, -1 when the class is absent
  std::vector<Stats> stats_;          // [slot][theta][phi]
  std::vector<unsigned char> class_of_;  // class of each pattern cell, by knit_cell_index
  bool one_colour_ = true;               // every cell has colour index 0
  int single_class_ = -1;                // the class of every cell, when the pattern has one
  // Per pattern row (as in class_of_) and slot: how many of the row's first
  // c cells have that slot's class, c = 0..cols; empty when there is one
  // class or rows x slots x (cols + 1) exceeds kMaxPrefix.
  static constexpr size_t kMaxPrefix = size_t(1) << 16;
  std::vector<uint16_t> prefix_;
  std::array<int, kClasses> class_of_slot_{};
};

}  // namespace knit
