// KnitMaterial: the knit model as a renderer sees it. At a hit of the base
// mesh it runs the geometry (CAPM or the flat height query, near-field or
// multi-scale) and returns what shading needs: pass straight through, or a
// yarn shading frame, the BSDF point (colour, layers, ply shadow, p_delta) and
// the kernel BSDF to evaluate there. docs/renderer.md, docs/multiscale.md.
//
// Conventions. The base mesh is the top of the yarn shell (paper Sec. 3.3,
// Alg. 1): a ray hitting the mesh from the front enters pattern space at
// (x, y, shell_top); a ray arriving from behind has crossed the shell before
// reaching the mesh and is marched from where it entered the shell's bottom.
// Pattern space is isotropic: pattern units = pattern_per_world x world
// units in every direction (tangents t, b and normal n).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "knit/aggregate_table.h"
#include "knit/bsdf.h"
#include "knit/ply_profile.h"
#include "knit/surface.h"
#include "knit/table_bsdf.h"

namespace knit {

enum class KnitMode { NearField = 0, MultiScale = 1 };

// How a host shades the yarn: the near-field yarn BSDF (yarn_bsdf.h) with
// everything the native renderer does, or as the OSL shader renders it in
// Cycles (bsdf_cycles.h; docs/cycles.md): the BSDF as Cycles' four closures,
// light and bounces leaving from the base hit (no self-shadowing), and in
// multi-scale mode every footprint aggregated by marches with LEAN-widened
// lobes (no class table, no tabulated BSDF, also below a cell).
enum class KnitBsdfModel { Exact = 0, Cycles = 1 };

// (A field added here must also go into the class-table cache's key,
// put_key in src/table_cache.cpp, if the class table may depend on it.)
struct KnitMaterialParams {
  StitchParams stitch;
  YarnBsdfParams bsdf;
  PlyParams ply;
  bool ply_detail = true;       // wrap the ply/fibre profile around the yarn
  KnitMode mode = KnitMode::NearField;
  bool capm = true;             // false: no parallax, the height query at the hit's (u, v)
  int footprint_points = 4;     // multi-scale Sobol' points per cell-sized footprint (docs/multiscale.md)
  bool footprint_table = true;  // multi-scale footprints of a cell or more: the class table, not marches
  // Multi-scale with the class table: the smallest footprint, in stitch
  // cells in both directions, that the table serves, in [0.25, 1]. Below 1,
  // footprints of table_min_cells up to a cell come from its sub-cell
  // statistics (docs/multiscale.md, "Footprints below a cell: sub-cells";
  // the default was 0.5 until the eighths' hit fractions, "Eighths of a
  // cell: the gaps").
  float table_min_cells = 0.25f;
  // Multi-scale with the class table: shade its footprints with the
  // tabulated BSDF (TableBsdf: the near field's shading and self-shadowing
  // averaged per class and pair of directions, built with the table);
  // false: the yarn BSDF at the footprint's mean normal, its lobes widened
  // by the normals' spread (LEAN), without self-shadowing.
  bool table_bsdf = true;
  // With table_bsdf: the light that meets other yarn of a footprint first,
  // and scatters there, is summed into the table when it is built
  // (TableBsdf::folded: per class and colour of the palette, for up to
  // TableBsdf::kMaxEntries of them), not followed by the renderer's walk
  // (Material::bounce_table); false: the walk.
  bool table_fold = true;
  bool self_shadowing = true;   // near field: light and bounces from a yarn hit cross the rest of the shell
  // Multi-scale: a footprint below a stitch cell (in either direction) is
  // shaded as the near field at the hit (the pixel's samples cover the
  // footprint); false: the marched aggregate of its points (docs/multiscale.md).
  bool near_field_below_cell = true;
  float uv_scale = 40.0f;       // pattern units per UV unit (x = uv_scale u, y = uv_scale v)
  CapmOptions capm_options;
  // Cycles: KnitMaterial takes footprint_table, table_bsdf,
  // near_field_below_cell and self_shadowing as false, whatever they are
  // here (params() shows what it uses), and marches every multi-scale
  // footprint with footprint_points points, as the shader does.
  KnitBsdfModel bsdf_model = KnitBsdfModel::Exact;

  // Throws std::invalid_argument naming the field and value.
  void validate() const;
  // These parameters as a KnitMaterial uses them (the implications of
  // bsdf_model Cycles above).
  KnitMaterialParams effective() const;
};

// What the host knows at a hit of the base mesh.
struct BaseHit {
  float u = 0, v = 0;                 // texture coordinates
  Vec3 t{1, 0, 0}, b{0, 1, 0}, n{0, 0, 1};  // orthonormal world frame: t along dP/du, n the front side
  float pattern_per_world = 1;        // uv_scale / |dP/du|: pattern units per world unit
  float kx = 0, ky = 0;               // normal curvature along t and b (1 / world units; > 0 convex)
  // Footprint of the pixel in UV (multi-scale): (du/dx, dv/dx), (du/dy, dv/dy).
  float dudx = 0, dvdx = 0, dudy = 0, dvdy = 0;
  // Multi-scale: the footprint's centre minus (u, v). A renderer that knows
  // where a camera sample lies in its pixel centres the footprint at the
  // pixel's centre, so that all of a pixel's samples aggregate one box and
  // the pixel is not averaged twice (by its box, then by its samples'
  // spread). The near field ignores it: its point is (u, v).
  float box_du = 0, box_dv = 0;
  // Where a FrameProvider's lookups near (u, v) may start (FrameProvider::
  // frame_near's hint: for a mesh, the triangle hit); -1 when unknown.
  int64_t frame_hint = -1;
};

struct KnitShade {
  bool pass_through = true;  // no yarn on this ray: continue straight on (point.p_delta = 1)
  bool from_back = false;    // the ray reached the fabric from behind the mesh
  Vec3 st{}, sb{}, sn{};     // world shading frame: yarn tangent, bitangent, surface normal
  Vec3 offset{};             // world offset from the base hit to the yarn hit
  BsdfPoint point;           // colour index, layers, ply shadow, p_delta
  Rgb kd_r, kd_t;            // body colours at this point (multi-scale: mixed over the footprint)
  k::KMicrofacet spec_r{}, spec_t{};  // specular lobes at this point (multi-scale: LEAN-widened)
  int steps = 0;             // CAPM segments marched (summed over footprint points)
  bool from_table = false;   // multi-scale: the footprint came from the class table (no march)
  bool from_sub_cells = false;  // ... from its sub-cells (a footprint below a cell)
  // Multi-scale, shaded as the near field: the footprint was a quarter of a
  // cell or more in both directions, so table_min_cells 0.25 would have
  // read it from the table's sub-cells (the renderer's report counts them).
  bool quarter_cell = false;
  bool aggregated = false;   // multi-scale: the footprint's points were marched and aggregated
  // Multi-scale from the class table with table_bsdf: shade with this
  // tabulated BSDF and mix, in the frame (st, sb, sn) of the base (the
  // specular lobes are then unused).
  const TableBsdf* table_bsdf = nullptr;
  TableBsdf::Mix mix;
  // Near field: the yarn point hit, inside the shell (pattern space). Light
  // and bounces leaving it cross the rest of the shell first: occluded_from
  // and shade_from march from it.
  bool in_shell = false;
  Vec3 p_yarn{};
};

class KnitMaterial;

// The multi-scale footprints of one pixel's camera samples. With the
// footprint centred at the pixel (the renderer's footprint_centre "pixel",
// BaseHit::box_du), every camera sample of a pixel finds the pixel's box
// again from its own hit, to first order: to 1e-4-1e-3 of the box's extent
// where the view is steep, a few hundredths where it grazes. A renderer
// that keeps one memo per pixel and passes it to KnitMaterial::route_of
// lets the later samples take the first one's box and its class-table
// sums (FootprintTable::NodeSums, per direction node) instead of finding
// and summing the box again: a box read from the sub-cells whose centre
// and extent agree with a kept one's to kTolerance of its extent is that
// box (docs/multiscale.md, "One box a pixel, kept"). It keeps two (a pixel
// may see the fabric twice, through a gap), of any materials. Empty to
// start; never shared between threads or pixels.
class FootprintMemo {
 public:
  static constexpr float kTolerance = 1.0f / 32;
  // Boxes found (sub_box_at and, the first time a direction needs them,
  // summed) and boxes taken from the memo.
  int64_t found() const { return found_; }
  int64_t reused() const { return reused_; }

 private:
  friend class KnitMaterial;
  struct Entry {
    const KnitMaterial* material = nullptr;
    float x = 0, y = 0, ex = 0, ey = 0;  // centre (pattern units) and extent (cells)
    std::optional<FootprintTable::SubBox> box;
    FootprintTable::NodeSums sums;
  };
  std::array<Entry, 2> entries_;
  int next_ = 0;
  int64_t found_ = 0, reused_ = 0;
};

class KnitMaterial {
 public:
  KnitMaterial(Pattern pattern, KnitMaterialParams params);  // validates

  const KnitMaterialParams& params() const { return params_; }
  const KnitSurface& surface() const { return surface_; }
  const YarnBsdf& bsdf() const { return bsdf_; }
  const PlyProfile& ply() const { return ply_; }

  // Geometry and shading point for a ray travelling along ray_dir (world,
  // unit) that hit the base mesh. `frame` bends CAPM rays on curved meshes
  // (null: the base curvature in `hit`, flat when zero). `shift` is the
  // multi-scale footprint sample shift, in [0, 1)^2. `u`, when in [0, 1),
  // is the caller's number for the pass through the gaps (it passes when
  // u < the result's p_delta); where the path stays on a footprint shaded
  // with the tabulated BSDF, (u - p_delta) / (1 - p_delta) then picks the
  // mix's view node (TableBsdf::mix's u_view). Negative: their blend.
  KnitShade shade(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame,
                  std::array<float, 2> shift = {0.5f, 0.5f}, float u = -1) const;

  // How shade() and transmittance() treat a hit (near field, the class
  // table's whole cells or sub-cells, the marched aggregate) and the
  // footprint they read, found from the hit alone. A renderer that asks
  // uses_shift() before shading finds it once (route_of) and passes it to
  // the overloads below, which must get the same hit.
  class HitRoute {
   private:
    friend class KnitMaterial;
    int route = 0;  // (a KnitMaterial::Route)
    Vec3 fx{}, fy{}, e{};
    std::optional<FootprintTable::SubBox> box;
    FootprintTable::NodeSums* sums = nullptr;  // the box's sums kept in a FootprintMemo
  };
  // `memo`: the pixel's FootprintMemo, for a camera sample's hit (or the
  // same ray passed on through the fabric); the route then refers to it,
  // and must be shaded before the memo is used again.
  HitRoute route_of(const BaseHit& hit, FootprintMemo* memo = nullptr) const;
  KnitShade shade(const BaseHit& hit, const HitRoute& route, Vec3 ray_dir, const FrameProvider* frame,
                  std::array<float, 2> shift = {0.5f, 0.5f}, float u = -1) const;

  // Whether shade() and transmittance() at this hit read their `shift`:
  // only multi-scale footprints that are marched, or read from the class
  // table for their colours or points. A renderer may skip drawing it
  // otherwise (the results are the same for any shift).
  bool uses_shift(const BaseHit& hit) const;
  bool uses_shift(const HitRoute& route) const;
  // Whether shade() and transmittance() treat this hit as near field: the
  // near-field mode, or a multi-scale footprint below a stitch cell (and
  // outside the class table's sub-cells) with near_field_below_cell.
  bool near_field_at(const BaseHit& hit) const;
  // In near-field mode, whether multi-scale mode would read this hit's
  // footprint from its class table instead of marching it: a footprint of
  // table_min_cells of a stitch cell or more in both directions (whole
  // cells, or the sub-cells below a cell). The render report's hint counts
  // them. Always false in multi-scale mode.
  bool table_would_serve(const BaseHit& hit) const;

  // Fraction of light a shadow ray along ray_dir passes through the fabric
  // here: near-field 0 or 1 (a gap or a yarn), multi-scale p_delta.
  float transmittance(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame,
                      std::array<float, 2> shift = {0.5f, 0.5f}) const;
  float transmittance(const BaseHit& hit, const HitRoute& route, Vec3 ray_dir, const FrameProvider* frame,
                      std::array<float, 2> shift = {0.5f, 0.5f}) const;

  // Self-shadowing (near field, `from` a shade() or shade_from() result with
  // in_shell): whether the straight path from its yarn point along dir_world
  // (unit, e.g. towards a light) meets other yarn before it leaves the
  // shell. `hit` is the base hit `from` was shaded at.
  bool occluded_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world, const FrameProvider* frame) const;
  // A bounce inside the shell: the yarn the ray from `from`'s yarn point
  // along dir_world meets before leaving the shell, shaded (pass_through
  // when it leaves without meeting any).
  KnitShade shade_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world, const FrameProvider* frame) const;

  // The ply profile's length coordinate along the yarn (PlyProfile::lookup's
  // s) at curve parameter t (KnitLineHit::t; yarn_curve_exact's t, which
  // runs 2 pi per stitch from x = 0) of row `row` (KnitLineHit::row, from
  // the bottom, unwrapped): t times the mean arc length per unit of t over a
  // stitch of knit, plus the row's own phase, the golden-ratio sequence of
  // the row times a stitch's length (so that the plies of rows above one
  // another are not in step, as they are not in a knitted piece). It is
  // part of the yarn's definition, so the explicit-yarn ground truth takes
  // it from here too (render/yarn_tubes): the ply helix turns by the same
  // angle over every stitch, and within a stitch in step with t rather than
  // with the true arc length (the loop's speed |dY/dt| varies along it;
  // docs/bsdf.md, "Ply phase").
  float ply_arc(float t, int row) const {
    const double g = double(row) * 0.6180339887498949;
    return t * arc_per_t_ + float(g - std::floor(g)) * (K_2PI * arc_per_t_);
  }

  // The kernel BSDF at a shading point (colour from the palette, roughness,
  // layers and ply shadow from `sh`).
  k::KYarnBsdf kernel_bsdf(const KnitShade& sh) const;
  // The near field's shading of yarn hit h of a ray that met the base at
  // `hit` (from behind when from_back), as shade() gives it.
  KnitShade point_shade(const BaseHit& hit, const k::KnitLineHit& h, bool from_back) const;

  // Memory the model keeps: pattern arrays, ply table, parameters, the
  // multi-scale footprint table (bytes).
  size_t state_bytes() const;
  const FootprintTable* footprint_table() const { return table_.get(); }
  // Whether the class table serves a footprint spanned by fx, fy (pattern
  // units) at pattern point (x, y): whole cells or sub-cells.
  bool table_serves(float x, float y, Vec3 fx, Vec3 fy) const;
  // Wall time the constructor spent building the multi-scale class table
  // (0 without one): most of a multi-scale material's set-up.
  double table_seconds() const { return table_seconds_; }
  // Whether the class table and its tabulated BSDF were read from the
  // class-table cache (knit/table_cache.h) rather than built; the entry's
  // path (empty when the cache is off); and what went wrong with the cache,
  // if anything (a damaged entry, a folder that cannot be written: the
  // tables were then built as without it), for the host to show.
  // table_marches_from_cache: the tables were not in the cache but their
  // marches were (a material that differs from a cached one only in its
  // colours or table_fold), and were finished here (TableBsdf::finished,
  // hundredths of a second) rather than marched again.
  // table_shadows_from_cache: neither were, but the tables' shadows were
  // (a material that differs from a cached one in its yarn BSDF's or ply's
  // parameters too): the yarn BSDF was evaluated at the view rays' hits
  // again, with the cached shadows (about a third of a build).
  bool table_from_cache() const { return table_from_cache_; }
  bool table_marches_from_cache() const { return table_marches_from_cache_; }
  bool table_shadows_from_cache() const { return table_shadows_from_cache_; }
  const std::string& table_cache_file() const { return table_cache_file_; }
  const std::string& table_cache_note() const { return table_cache_note_; }
  // The class table's tabulated BSDF (multi-scale with footprint_table and
  // table_bsdf), else null.
  const TableBsdf* table_bsdf() const { return table_bsdf_.get(); }

 private:
  k::KnitCapm march(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame, bool blocked_only = false) const;
  // March from `start` (pattern space) for a ray along ray_dir (world) on
  // the base of `hit`: the frame field or hit's curvature bends it.
  // blocked_only: see KnitSurface::march (and knit_capm_march_curved, the
  // march without a frame field).
  k::KnitCapm march_state(const BaseHit& hit, const k::KnitCapm& start, Vec3 ray_dir,
                          const FrameProvider* frame, bool blocked_only = false) const;
  // The longest straight segment of a march on a base of normal curvature
  // (kx, ky) (pattern units): capm_options' max_segment, shortened so that
  // the base turns by at most max_bend along it (the OSL shader's rule).
  float curved_segment(float kx, float ky) const;
  // March from `from`'s yarn point along dir_world (see occluded_from).
  k::KnitCapm march_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world,
                         const FrameProvider* frame, bool blocked_only = false) const;
  // A shade with the material's unwidened specular lobes and no yarn yet.
  const KnitShade& unshaded() const { return unshaded_; }
  // Near-field shading at yarn hit h of a ray that met the base at `hit`.
  void shade_yarn(const BaseHit& hit, const k::KnitLineHit& h, const FrameProvider* frame, KnitShade& sh) const;
  // Points marched over a footprint spanned by fx, fy (pattern units).
  int footprint_points_for(Vec3 fx, Vec3 fy) const;
  // The hit's pixel footprint in pattern space: the spanning vectors of its
  // UV differentials, times uv_scale.
  void footprint_axes(const BaseHit& hit, Vec3& fx, Vec3& fy) const {
    const float us = params_.uv_scale;
    fx = k::kv3(us * hit.dudx, us * hit.dvdx, 0);
    fy = k::kv3(us * hit.dudy, us * hit.dvdy, 0);
  }
  // How shade() and transmittance() treat a hit: the near field (one CAPM
  // ray); a multi-scale footprint of a cell or more in both directions
  // (knit_footprint_stratified's test) from the class table's whole
  // cells; one of table_min_cells or more but below a cell in some
  // direction from its sub-cells (FootprintTable::sub_box); else the
  // marched aggregate. Sets the footprint's axes and extent (cells) for
  // the multi-scale routes.
  enum class Route { NearField, Cells, SubCells, Marched };
  // The multi-scale footprint's centre in pattern space (x, y; z 0): the
  // hit's UV moved by BaseHit::box_du, box_dv, times uv_scale.
  Vec3 footprint_centre(const BaseHit& hit) const {
    return k::kv3(params_.uv_scale * (hit.u + hit.box_du), params_.uv_scale * (hit.v + hit.box_dv), 0);
  }
  // For Route::SubCells, `sub` (when given) gets the footprint's box.
  // With `memo` (and `sub`), a box kept there stands for the hit's own
  // and `sums` gets its sums (FootprintMemo).
  Route route(const BaseHit& hit, Vec3& fx, Vec3& fy, Vec3& extent,
              std::optional<FootprintTable::SubBox>* sub = nullptr, FootprintMemo* memo = nullptr,
              FootprintTable::NodeSums** sums = nullptr) const;
  // The box of the footprint of `extent` cells (below a cell in some
  // direction) at pattern point (x, y), when the class table's sub-cells
  // serve it.
  std::optional<FootprintTable::SubBox> sub_cells_serve(float x, float y, Vec3 extent) const;
  // Whether a footprint of `extent` cells is large enough for the sub-cells
  // (table_min_cells; the table has them): sub_cells_serve's first test.
  bool sub_cells_reach(Vec3 extent) const;
  // Whether a footprint of `extent` cells spans table_min_cells in both
  // directions (sub_cells_reach's and table_would_serve's test).
  bool spans_table_min_cells(Vec3 extent) const {
    return extent.x >= params_.table_min_cells && extent.y >= params_.table_min_cells;
  }
  // Shades sh with the tabulated BSDF: the mix of the classes' hits
  // `slot_hits` seen from wi (colours already in sh; colour_w, the
  // footprint's shares of the palette's colours for a folded table, null
  // for the first colour alone), in the base's frame; false, sh's shading
  // untouched, when no class has hits to weigh.
  bool use_table_bsdf(const BaseHit& hit, Vec3 wi, const float* slot_hits, float u, KnitShade& sh,
                      const float* colour_w = nullptr) const;
  void set_colors(KnitShade& sh, int color_index) const;
  // Palette mixed by a footprint's colour histogram (KNIT_MS_COLORS bins).
  void mix_colors(KnitShade& sh, const float* weights) const;

  KnitMaterialParams params_;
  KnitSurface surface_;
  YarnBsdf bsdf_;
  PlyProfile ply_;
  std::shared_ptr<const FootprintTable> table_;  // multi-scale with footprint_table: built at construction
  std::shared_ptr<const TableBsdf> table_bsdf_;  // with table_ when params_.table_bsdf
  double table_seconds_ = 0;  // what table_seconds() returns
  bool table_from_cache_ = false, table_marches_from_cache_ = false, table_shadows_from_cache_ = false;
  std::string table_cache_file_, table_cache_note_;
  float arc_per_t_ = 1;     // mean arc length of the yarn per unit of curve parameter
  float mean_shadow_ = 1;   // ply shadow averaged around and along the yarn
  KnitShade unshaded_;      // what unshaded() returns, set up once
};

// The near field's shading of one yarn hit h of `material` seen from wo, on
// a flat base whose frame is pattern space, as TableBsdf sums it: parts(wi)
// is f |wi.n| towards wi split into the colour-free part and the factors of
// the two body colours (A, Br, Bt; the yarn BSDF is linear in them); base()
// and shade() are what KnitMaterial::occluded_from marches from.
class YarnHitParts {
 public:
  YarnHitParts(const KnitMaterial& material, const k::KnitLineHit& h, Vec3 wo);
  Vec3 parts(Vec3 wi) const;
  const BaseHit& base() const { return base_; }
  const KnitShade& shade() const { return sh_; }

 private:
  BaseHit base_;
  KnitShade sh_;
  k::KYarnBsdf bsdf_{};
  Vec3 t_{}, b_{}, n_{}, wo_l_{};
};

}  // namespace knit
