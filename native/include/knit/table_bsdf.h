// TableBsdf: the tabulated shading of the multi-scale class table
// (docs/multiscale.md, "The table's shading: a tabulated BSDF").
//
// A footprint read from the class table used to be shaded as one yarn
// point: the yarn BSDF at the hits' mean normal, its specular lobes widened
// by the slope covariance (LEAN). Tubes show normals over a whole
// hemisphere, which no widened lobe around a mean normal describes, and
// that shading had no self-shadowing: under one light the swatch's
// specular came out 57-89% too dark, and the shadows it lacked hid part of
// that in scenes lit from several sides.
//
// This table holds instead, per class present and per pair of view and
// light directions on a coarse (theta, phi) grid over the whole sphere, the
// mean over the yarn points that the view rays hit of
//
//     f(wo, wi) |wi . n|
//
// with the near field's own shading at each point (the yarn BSDF in the
// point's ply frame, its ply shadow; YarnHitParts), and the share of it
// that reaches the point: its self-shadowing march towards the light meets
// no other yarn. The yarn BSDF is linear in the two body colours, so each
// pair keeps four numbers: the colour-free part A and the factors Br and
// Bt of the reflection and transmission colours, f |wi.z| = A + Br kd_r +
// Bt kd_t per channel, and the lit share. Directions are in the fabric's
// frame (x along the pattern's x, z its front normal); the aggregate is
// conditioned on a hit (the pass through the gaps is the class table's
// p_delta). The shadowed rest is light that meets other yarn of the
// footprint first: the renderer's walk scatters it there again
// (Material::bounce_table), taking that yarn as the footprint's classes
// seen from the other way; that walk is summed into the table as it is
// built (folded(), per class and colour of the palette), and the values
// are then the material's colours. What it leaves out: the base's
// curvature, and
// the sub-cells' own shading (a footprint below a cell mixes its classes'
// tables by the sub-cells' hit fractions).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "knit/aggregate_table.h"

namespace knit {

class KnitMaterial;

class TableBsdf {
 public:
  static constexpr int kTheta = 12;  // nodes i pi / 11 over [0, pi] (none on the horizon)
  static constexpr int kPhi = 12;    // nodes j 2 pi / 12
  static constexpr int kNodes = kTheta * kPhi;

  // Built for `material`, whose class table it follows (its classes and
  // their cells): `hits_per_view` view rays per class and view node, each
  // hit shaded towards every light node, and the first hits_per_view /
  // march_stride of them (a stratified prefix of the rays' net)
  // shadow-marched there too: V enters as the lit share of f over those.
  // Every core.
  //
  // The build has three stages, and the class-table cache keeps each, so
  // that a material which differs from a cached one only in what a later
  // stage reads starts from the cached earlier one:
  // - Shadows: the view rays' first hits and the self-shadowing of the
  //   first hits_per_view / march_stride rays' hits towards every light
  //   node (whether the march met other yarn): geometry only, none of the
  //   yarn BSDF's or ply's parameters. Its marches are most of the build
  //   (61%).
  // - Marched: the values, the yarn BSDF evaluated at the hits (the view
  //   rays marched again, and the shadows read from a Shadows table when
  //   one is given), which hold none of the material's colours (the parts
  //   per body colour and the lit share).
  // - Finished (finished()): the walk folded in the palette's colours where
  //   table_fold applies, and the sampling rows; a few hundredths of the
  //   build's time.
  // `shadows_in`: a table of stage Shadows for this geometry (the same
  // pattern, stitch and CAPM parameters and build settings), whose shadows
  // are read instead of marched. `shadows_out`, when given, receives the
  // build's shadows as a table of stage Shadows. Stage Shadows itself is
  // not built here (its tables come from shadows_out).
  enum class Stage { Shadows, Marched, Finished };
  TableBsdf(const KnitMaterial& material, const FootprintTable& table, int hits_per_view = 512,
            int march_stride = 8, Stage stage = Stage::Finished, const TableBsdf* shadows_in = nullptr,
            std::shared_ptr<const TableBsdf>* shadows_out = nullptr);
  // This table finished for `material`, which must be the material it was
  // marched for up to its colours and table_fold (the class-table cache's
  // key says which parameters those are), with `table` its class table.
  // Throws std::logic_error when this table is not of stage Marched.
  TableBsdf finished(const KnitMaterial& material, const FootprintTable& table) const;
  Stage stage() const {
    return values_.empty() ? Stage::Shadows : rows_.empty() ? Stage::Marched : Stage::Finished;
  }
  // Stage Shadows: whether the march from hit m (of the first rays) of view
  // node `view`, class slot `slot`, towards light node `light` met other
  // yarn; false for a ray that missed.
  bool shadowed(int slot, int view, int m, int light) const {
    const uint64_t w = shadow_bits_[((size_t(slot) * kNodes + size_t(view)) * size_t(marches_) + size_t(m)) *
                                        kShadowWords + size_t(light) / 64];
    return (w >> (light % 64)) & 1u;
  }
  int marches() const { return marches_; }
  int classes() const { return classes_; }  // class slots (folded: entries are classes x colours)

  // A footprint's shading seen from wo (fabric frame, unit, either side):
  // the view nodes to mix, their weights, and the classes' shares of the
  // hits. `slot_hits` holds, per class slot of the table, the footprint's
  // hits on that class (any scale; FootprintTable::aggregate's
  // slot_hits). colour_w: folded with several colours, the footprint's
  // shares of the palette's colours (null: the first colour alone); unused
  // otherwise. With u_view in [0, 1), one of the four view nodes around
  // wo stands for their bilinear blend: node q with probability its
  // weight, picked by u_view. That is the blend in expectation at a quarter
  // of the cost of every later evaluation and sample, for renderers, which
  // average many samples anyway; negative u_view: the blend itself.
  // Entries per node pair at most: the classes present, or folded, the
  // classes times the palette's colours.
  static constexpr int kMaxEntries = 16;
  struct Mix {
    int n = 0;  // view nodes mixed; 0 when no class has hits
    std::array<int32_t, 4> view{};
    std::array<float, 4> w{};
    // The entries' shares of the hits: per class, or folded, per class and
    // colour (entry class * colours + colour).
    std::array<float, kMaxEntries> share{};
    // Sampling: the weights of the four stored values in a node's sampling
    // value (1, cr, ct, 0 with mix's body colours' channel means: A + cr
    // Br + ct Bt; folded, 0, 0, 0, 1: the channels' mean); and the mix's
    // sampling values summed over each theta row's cells times their solid
    // angle, and over the sphere (at kTheta).
    std::array<float, 4> sw{};
    std::array<float, kTheta + 1> rows{};
  };
  Mix mix(const float* slot_hits, Vec3 wo, float cr, float ct, float u_view = -1,
          const float* colour_w = nullptr) const;
  // The same classes seen from another direction wo.
  void remix(Mix& m, Vec3 wo, float u_view = -1) const;

  // f(wo, wi) |wi.z| V(wi) of the mix towards wi (fabric frame, unit), per
  // channel, with body colours kd_r, kd_t: the light that reaches the
  // yarn points along wi. `total`, when given, receives f |wi.z| without
  // V: the lit part and the part shadowed by other yarn together; `density`
  // receives pdf(m, wi) from the same direction lookup. Folded (below):
  // the folded values, whose colours are the material's own (kd_r and
  // kd_t unused), and `total` the same, since nothing is shadowed.
  Vec3 eval(const Mix& m, Vec3 wi, Vec3 kd_r, Vec3 kd_t, Vec3* total = nullptr, float* density = nullptr) const;
  // The sampling density of sample() (solid angle): piecewise constant per
  // light node's cell, in proportion to the mix's total (lit and shadowed)
  // there with the mix's colour means, blended with a uniform share of the
  // sphere.
  float pdf(const Mix& m, Vec3 wi) const;
  // A direction from pdf() with three uniform numbers; false when the mix
  // is empty. Sets wi and, when asked, its density and a fourth uniform
  // number left over from u0's choices.
  bool sample(const Mix& m, float u0, float u1, float u2, Vec3& wi, float* pdf = nullptr,
              float* u_rest = nullptr) const;

  // Share of sample() drawn uniformly over the sphere (covers every
  // direction where the tabulated value is not zero).
  static constexpr float kUniform = 0.15f;

  // Folded: the table holds, per class and pair of nodes, the light from
  // wi that reaches the footprint's yarn directly or after any number of
  // scatterings off other yarn of the footprint, towards wo, in the
  // material's colours (RGB, and their mean for sampling; one entry per
  // class and colour of the palette): the walk through the shadowed part
  // (Material::bounce_table), summed at build time. Built so with
  // KnitMaterialParams::table_fold when the classes times the colours (one
  // for patterns of one colour index) are at most kMaxEntries
  // (docs/multiscale.md, "The walk folded into the table").
  bool folded() const { return folded_; }
  // Colours per class in the entries: folded, the palette's (1 for a
  // pattern of one colour index); else 1.
  int colours() const { return colours_; }

  size_t bytes() const {
    return sizeof(*this) + values_.size() * sizeof(uint16_t) +
           (rows_.size() + srows_.size()) * sizeof(float) + snodes_.size() * sizeof(uint16_t) +
           hit_frac_.size() * sizeof(double) + shadow_bits_.size() * sizeof(uint64_t);
  }
  double build_seconds() const { return seconds_; }  // (0 when read from the class-table cache)
  // The tabulated A, Br, Bt (without V) and the lit share of entry `slot`
  // (a class slot; folded, class slot * colours() + colour), view node
  // `view`, light node `light` (as stored; folded: red, green, blue and
  // their mean), for tests; and a node's direction.
  std::array<float, 4> value(int slot, int view, int light) const;
  static Vec3 node_direction(int node);
  // The overlaps of the nodes' bilinear hat functions (eval's
  // interpolation) over the sphere, kNodes x kNodes, symmetric: the fold's
  // quadrature weights. Computed once.
  static const std::vector<double>& sphere_overlaps();
  // Per class slot of `table`, its share of the pattern's cells (all of
  // them counted, however large the pattern), as the fold weighs the
  // classes of the yarn a footprint meets.
  static std::vector<double> cell_shares(const FootprintTable& table);

 private:
  friend struct TableCacheCodec;  // reads and writes the state below (src/table_cache.cpp)
  TableBsdf() = default;          // (for TableCacheCodec, which fills it)
  // The density of sample() in the cell of the node nearest to a
  // direction (theta and phi within half a node spacing: the heaviest of
  // its bilinear corners `c`), and the solid angle of a row's cells.
  float density(const Mix& m, const SphereNodes& c) const;
  static float cell_solid_angle(int theta_row);
  // The mix's sampling value at light node l (its values weighed by sw).
  float node_value(const Mix& m, int l) const;

  // The walk folded into the values (folded()), given per class slot its
  // share of the cells and, per view node, its hit fraction; the entries
  // become the classes times `colours`, the palette's first colours.
  void fold(const KnitMaterial& material, int colours, const std::vector<double>& cell_share,
            const std::vector<double>& hit_frac);
  // The finishing stage (finished()): the fold where it applies, then the
  // sampling rows.
  void finish(const KnitMaterial& material, const FootprintTable& table);
  // Folded and finished: srows_ and snodes_ from rows_ and values_ (after
  // finish, and after the class-table cache has read a table); otherwise
  // clears them.
  void derive_sampling();

  static constexpr int kValues = 4;
  int slots_ = 0;  // entries per node pair
  int classes_ = 0;
  int colours_ = 1;
  bool folded_ = false;
  // The classes' stored values at a pair of nodes, and the classes' row
  // sums at a view node and theta row.
  const uint16_t* at(int view, int light) const {
    return &values_[(size_t(view) * kNodes + size_t(light)) * size_t(slots_) * kValues];
  }
  const float* rows_at(int view, int theta_row) const {
    return &rows_[(size_t(view) * (kTheta + 1) + size_t(theta_row)) * size_t(slots_) * 4];
  }
  // [view node][light node][slot][A, Br, Bt, lit share] as bfloat16: the
  // classes of one pair of nodes side by side, as a footprint mixes them
  // (one or two cache lines per lookup).
  std::vector<uint16_t> values_;
  // [view node][theta row, then the sphere][slot][A, Br, Bt, lit share]: the
  // values summed over the row's light nodes times their cells' solid
  // angle, and over all rows (sample, pdf; four floats for four lanes).
  // (empty until the table is finished)
  std::vector<float> rows_;
  // Folded (sampling weights 0, 0, 0, 1): the sampling values alone, the
  // fourth stored value, four lanes of rows or nodes at a time, so that
  // remix and sample sum a quarter of the vectors. srows_: [view node][row
  // group g < 4][slot][row 4 g + lane], rows 0..kTheta of rows_ (lanes
  // past kTheta zero); snodes_: [view node][theta row][node group g < 3]
  // [slot][the row's node 4 g + lane], of values_ (bfloat16, as stored
  // there). Derived, not cached. (empty otherwise)
  std::vector<float> srows_;
  std::vector<uint16_t> snodes_;
  // Per class slot and view node, the share of the view rays that hit yarn
  // (the fold's weights of the classes met inside a footprint; empty once
  // the table is finished).
  std::vector<double> hit_frac_;
  // Stage Shadows: [slot][view node][ray m < marches_][light node bits],
  // shadowed() (else empty).
  static constexpr size_t kShadowWords = (kNodes + 63) / 64;
  int marches_ = 0;
  std::vector<uint64_t> shadow_bits_;
  double seconds_ = 0;
};

}  // namespace knit
