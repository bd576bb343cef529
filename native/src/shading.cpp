// KnitMaterial: geometry and shading point of the knit model at a base hit.
#include "knit/shading.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "knit/table_progress.h"
#include "knit/yarns.h"
#include "table_cache_internal.h"

namespace knit {
namespace {

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

Vec3 add3(Vec3 a, Vec3 b, Vec3 c) { return k::kv3_add(k::kv3_add(a, b), c); }

// World vector of local components l in the frame (t, b, n).
Vec3 to_world(Vec3 l, Vec3 t, Vec3 b, Vec3 n) {
  return add3(k::kv3_scale(t, l.x), k::kv3_scale(b, l.y), k::kv3_scale(n, l.z));
}

// The frame at pattern offset (dx, dy) on a base of constant curvature: the
// entry frame turned as in k::knit_curved_frame_dir.
void curved_frame(Vec3 t0, Vec3 b0, Vec3 n0, float kx, float ky, float dx, float dy, Vec3& t, Vec3& b,
                  Vec3& n) {
  const float ax = kx * dx, ay = ky * dy;
  const float cx = std::cos(ax), sx = std::sin(ax), cy = std::cos(ay), sy = std::sin(ay);
  const Vec3 t1 = k::kv3_sub(k::kv3_scale(t0, cx), k::kv3_scale(n0, sx));
  const Vec3 n1 = k::kv3_add(k::kv3_scale(t0, sx), k::kv3_scale(n0, cx));
  t = t1;
  b = k::kv3_sub(k::kv3_scale(b0, cy), k::kv3_scale(n1, sy));
  n = k::kv3_add(k::kv3_scale(b0, sy), k::kv3_scale(n1, cy));
}

// The ply profile of a material: its parameters must be valid when the
// detail is on; when it is off, invalid ones fall back to the defaults.
PlyProfile ply_profile_for(const KnitMaterialParams& p) {
  if (p.ply_detail) return PlyProfile(p.ply);
  try {
    p.ply.validate();
  } catch (const std::invalid_argument&) {
    return PlyProfile();
  }
  return PlyProfile(p.ply);
}

}  // namespace

void KnitMaterialParams::validate() const {
  stitch.validate();
  bsdf.validate();
  if (ply_detail) ply.validate();
  auto bad = [](const std::string& field, const std::string& value, const char* rule) {
    throw std::invalid_argument("KnitMaterialParams." + field + " = " + value + ": " + rule);
  };
  if (!std::isfinite(uv_scale) || !(uv_scale > 0) || uv_scale > 1e6f)
    bad("uv_scale", num(uv_scale), "must be finite, > 0 and at most 1e6");
  if (!(table_min_cells >= FootprintTable::kMinSubBox && table_min_cells <= 1.0f))
    bad("table_min_cells", num(table_min_cells), "must be in [0.25, 1]");
  if (footprint_points < 1 || footprint_points > KNIT_MS_MAX_POINTS)
    bad("footprint_points", std::to_string(footprint_points), "must be in [1, 64]");
  if (capm_options.max_steps < 1 || capm_options.max_steps > 4096)
    bad("capm_options.max_steps", std::to_string(capm_options.max_steps), "must be in [1, 4096]");
  if (!capm_segment_in_range(capm_options.max_segment))
    bad("capm_options.max_segment", num(capm_options.max_segment),
        ("must be > 0 and at most " + num(kMaxCapmSegment)).c_str());
  if (!(capm_options.max_bend > 0) || !std::isfinite(capm_options.max_bend))
    bad("capm_options.max_bend", num(capm_options.max_bend), "must be finite and > 0");
  if (bsdf_model != KnitBsdfModel::Exact && bsdf_model != KnitBsdfModel::Cycles)
    bad("bsdf_model", std::to_string(int(bsdf_model)), "must be Exact (0) or Cycles (1)");
}

KnitMaterialParams KnitMaterialParams::effective() const {
  KnitMaterialParams p = *this;
  if (p.bsdf_model == KnitBsdfModel::Cycles) {
    // What Cycles can do: the shader has no class table (nor the tabulated
    // BSDF built with it) and aggregates whatever the footprint's size, and
    // Cycles shades at the base hit, where light and bounces leave.
    p.footprint_table = false;
    p.table_bsdf = false;
    p.near_field_below_cell = false;
    p.self_shadowing = false;
  }
  return p;
}

KnitMaterial::KnitMaterial(Pattern pattern, KnitMaterialParams params)
    : params_((params.validate(), params.effective())),
      surface_(std::move(pattern), params_.stitch),
      bsdf_(params_.bsdf),
      ply_(ply_profile_for(params_)) {
  const Pattern& pat = surface_.pattern();
  if (pat.num_colors() > params_.bsdf.num_colors())
    throw std::invalid_argument("KnitMaterialParams.bsdf: the pattern uses " + std::to_string(pat.num_colors()) +
                                " colour indices but " + std::to_string(params_.bsdf.num_colors()) +
                                " yarn colours are given");
  // Mean arc length per unit of curve parameter, over one stitch of knit.
  const Pattern knit = Pattern::from_rows({{0}});
  double len = 0;
  const int n = 256;
  for (int i = 0; i < n; ++i) {
    const CurvePoint c = yarn_curve_exact(knit, params_.stitch, 0, 6.283185307179586 * (i + 0.5) / n);
    len += std::sqrt(c.dp[0] * c.dp[0] + c.dp[1] * c.dp[1] + c.dp[2] * c.dp[2]);
  }
  arc_per_t_ = float(len / n);
  double g = 0;
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 16; ++j) g += ply_.lookup(6.2831853f * (i + 0.5f) / 64, 0.37f * float(j)).shadow;
  mean_shadow_ = params_.ply_detail ? float(g / (64 * 16)) : 1.0f;
  // As Cycles renders it: the shader's mean, from the procedural profile.
  if (params_.ply_detail && params_.bsdf_model == KnitBsdfModel::Cycles)
    mean_shadow_ = k::ply_mean_shadow(ply_.kernel_params(), 8, 4);
  const YarnBsdfParams& bp = params_.bsdf;
  unshaded_.spec_r = k::bsdf_mf_make(bp.roughness_x, bp.roughness_y, bp.eta);
  unshaded_.spec_t = k::bsdf_mf_make(bp.trans_roughness_x, bp.trans_roughness_y, bp.eta);
  // Not for slip stitches: their floats cross cell boundaries and blend
  // with the loops beside them, which the classes do not describe (p_delta
  // off by up to 0.075 on heel stitch, docs/multiscale.md); those patterns
  // keep the marched aggregate.
  if (params_.mode == KnitMode::MultiScale && params_.footprint_table && surface_.geom().has_floats == 0) {
    const auto t0 = std::chrono::steady_clock::now();
    ClassTableBuild build;
    build.sub_cells = params_.table_min_cells < 1;
    build.table_bsdf = params_.table_bsdf;
    const TableCacheSettings cache = table_cache();
    const int rows = surface_.pattern().rows(), cols = surface_.pattern().cols();
    // The finished tables from the cache, else the latest stage of the build
    // that it holds (TableBsdf::Stage: the marches, then the shadows) and the
    // stages after it made here, else the whole build; every stage made here
    // is stored. Notes: the entries found damaged, then what was done
    // instead; then the stores that failed.
    std::vector<std::string> damaged, stores;
    const auto load = [&](const ClassTableEntry& e, std::shared_ptr<const TableBsdf>& bsdf) {
      std::string note;
      const bool ok = load_class_tables(e, build, rows, cols, table_, bsdf, note);
      if (!note.empty()) damaged.push_back(note);
      return ok;
    };
    const auto store = [&](const ClassTableEntry& e, const TableBsdf* bsdf) {
      std::string note;
      store_class_tables(e, cache, *table_, bsdf, note);
      if (!note.empty() && std::find(stores.begin(), stores.end(), note) == stores.end()) stores.push_back(note);
    };
    // (the progress observer's begin and end around the builds: the class
    // table's jobs, then the tabulated BSDF's marches)
    TableBuildProgress* const progress = table_build_progress();
    struct ProgressScope {  // (end() also when a build throws)
      TableBuildProgress* p;
      bool open = false;
      void close() {
        if (open) p->end();
        open = false;
      }
      ~ProgressScope() { close(); }
    } scope{progress};
    const auto build_table = [&] {
      if (progress) {
        int classes = 0;
        for (const auto& list : FootprintTable::class_cells(surface_)) classes += !list.empty();
        progress->begin(table_build_units(classes, true, build.table_bsdf));
        scope.open = true;
      }
      table_ = std::make_shared<const FootprintTable>(surface_, params_.capm_options, build.rays_per_direction,
                                                      FootprintTable::LayerCounts::Auto, build.sub_cells);
    };
    const ClassTableEntry done = class_table_entry(*this, build, cache, TableBsdf::Stage::Finished);
    table_cache_file_ = done.path;
    table_from_cache_ = load(done, table_bsdf_);
    if (!table_from_cache_) {
      if (build.table_bsdf) {
        // The finished tables from the marches, the marches from the
        // shadows: the earliest stage not cached is built, and each stage
        // built is stored.
        const ClassTableEntry marches = class_table_entry(*this, build, cache, TableBsdf::Stage::Marched);
        std::shared_ptr<const TableBsdf> marched;
        table_marches_from_cache_ = load(marches, marched);
        if (!table_marches_from_cache_) {
          const ClassTableEntry shadows = class_table_entry(*this, build, cache, TableBsdf::Stage::Shadows);
          std::shared_ptr<const TableBsdf> cached_shadows;
          table_shadows_from_cache_ = load(shadows, cached_shadows);
          if (table_shadows_from_cache_) {
            if (progress) {
              progress->begin(table_build_units(table_->classes_present(), false, true));
              scope.open = true;
            }
            marched = std::make_shared<const TableBsdf>(*this, *table_, build.hits_per_view, build.march_stride,
                                                        TableBsdf::Stage::Marched, cached_shadows.get());
          } else {
            build_table();
            std::shared_ptr<const TableBsdf> shadows_built;
            marched = std::make_shared<const TableBsdf>(*this, *table_, build.hits_per_view, build.march_stride,
                                                        TableBsdf::Stage::Marched, nullptr, &shadows_built);
            store(shadows, shadows_built.get());
          }
          scope.close();
          store(marches, marched.get());
        }
        table_bsdf_ = std::make_shared<const TableBsdf>(marched->finished(*this, *table_));
        store(done, table_bsdf_.get());
      } else {
        // (the class table alone: geometry, so `done` is the shadows' entry,
        // class_table_entry)
        build_table();
        scope.close();
        store(done, nullptr);
      }
    }
    std::string notes;
    for (const std::string& d : damaged) notes += (notes.empty() ? "" : "; ") + d;
    if (!damaged.empty())
      notes += table_from_cache_           ? ""
               : table_marches_from_cache_ ? "; finished the tables from the cached marches"
               : table_shadows_from_cache_ ? "; marched the tables again from the cached shadows"
                                           : "; built the tables again";
    for (const std::string& f : stores) notes += (notes.empty() ? "" : "; ") + f;
    table_cache_note_ = notes;
    table_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
}

size_t KnitMaterial::state_bytes() const {
  // The object itself (parameters, the ply table) and what it keeps on the
  // heap: the pattern arrays (held by its surface) and the colour palettes
  // (in the material's and the BSDF's parameters).
  auto heap = [](const Pattern& p) {
    return (p.codes().size() + p.colors_or_zero().size() + (p.has_colors() ? p.codes().size() : 0)) *
           sizeof(int32_t);
  };
  return sizeof(*this) + heap(surface_.pattern()) + 4 * sizeof(Rgb) * size_t(params_.bsdf.num_colors()) +
         (table_ ? table_->bytes() : 0) + (table_bsdf_ ? table_bsdf_->bytes() : 0);
}

k::KnitCapm KnitMaterial::march(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame,
                                bool blocked_only) const {
  const float x = params_.uv_scale * hit.u, y = params_.uv_scale * hit.v;
  const Vec3 wi = k::kv3_neg(k::kv3_to_local(ray_dir, hit.t, hit.b, hit.n));
  return march_state(hit, k::knit_capm_start(surface_.geom(), x, y, wi), ray_dir, frame, blocked_only);
}

k::KnitCapm KnitMaterial::march_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world,
                                     const FrameProvider* frame, bool blocked_only) const {
  // Started a twentieth of the radius along the ray: the tube the point lies
  // on is then entered behind the start (its entry does not count), which
  // float rounding at pattern coordinates up to ~1e4 cannot undo; another
  // tube closer than that to the point is missed.
  const Vec3 d = k::kv3_normalize(k::kv3_to_local(dir_world, hit.t, hit.b, hit.n));
  const Vec3 p = k::kv3_madd(from.p_yarn, d, 0.05f * surface_.geom().r);
  return march_state(hit, k::knit_capm_begin_at(p, d), dir_world, frame, blocked_only);
}

bool KnitMaterial::occluded_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world,
                                 const FrameProvider* frame) const {
  if (!from.in_shell || !params_.self_shadowing) return false;
  return march_from(hit, from, dir_world, frame, true).state == KNIT_CAPM_HIT;
}

KnitShade KnitMaterial::shade_from(const BaseHit& hit, const KnitShade& from, Vec3 dir_world,
                                   const FrameProvider* frame) const {
  KnitShade sh = unshaded();
  sh.from_back = from.from_back;
  if (!from.in_shell || !params_.self_shadowing) return sh;
  const k::KnitCapm st = march_from(hit, from, dir_world, frame);
  sh.steps = st.steps;
  if (st.state != KNIT_CAPM_HIT) {
    sh.point.p_delta = 1;
    return sh;
  }
  sh.in_shell = true;
  shade_yarn(hit, st.hit, frame, sh);
  return sh;
}

k::KnitCapm KnitMaterial::march_state(const BaseHit& hit, const k::KnitCapm& start, Vec3 ray_dir,
                                      const FrameProvider* frame, bool blocked_only) const {
  const float x = params_.uv_scale * hit.u, y = params_.uv_scale * hit.v;
  if (frame) return surface_.march(start, ray_dir, frame, params_.capm_options, blocked_only, hit.frame_hint);
  const float S = hit.pattern_per_world;
  const float kx = hit.kx / S, ky = hit.ky / S;
  return k::knit_capm_march_curved(surface_.geom(), surface_.codes(), surface_.colors(), start, x, y,
                                   k::kv3_normalize(k::kv3_to_local(ray_dir, hit.t, hit.b, hit.n)), kx, ky,
                                   curved_segment(kx, ky), params_.capm_options.max_steps, blocked_only ? 1 : 0);
}

float KnitMaterial::curved_segment(float kx, float ky) const {
  const float kmax = std::max(std::abs(kx), std::abs(ky));
  const CapmOptions& o = params_.capm_options;
  return kmax > 0 ? std::min(o.max_segment, o.max_bend / kmax) : o.max_segment;
}

int KnitMaterial::footprint_points_for(Vec3 fx, Vec3 fy) const {
  // A footprint below a stitch cell gets the share of footprint_points its
  // area covers, at least one point: the points of a tiny footprint would
  // all march the same ray (the near-field limit). A cell or more: all of
  // them (the kernel adds more for many cells).
  // (The OSL shader passes footprint_points whatever the footprint's size.)
  if (params_.bsdf_model == KnitBsdfModel::Cycles) return params_.footprint_points;
  const float cell = K_2PI * surface_.geom().row_spacing;
  const float area = std::abs(fx.x * fy.y - fx.y * fy.x) / cell;
  if (!(area < 1)) return params_.footprint_points;  // also NaN
  // (the 1e-3 keeps an exact share from rounding up to one point more)
  return std::clamp(int(std::ceil(float(params_.footprint_points) * area - 1e-3f)), 1, params_.footprint_points);
}

void KnitMaterial::mix_colors(KnitShade& sh, const float* weights) const {
  const YarnBsdfParams& bp = params_.bsdf;
  Rgb r{0, 0, 0}, t{0, 0, 0};
  float best = -1;
  for (int c = 0; c < std::min(KNIT_MS_COLORS, bp.num_colors()); ++c) {
    const float w = weights[c];
    if (w <= 0) continue;
    const Rgb& kr = bp.reflect_colors[size_t(c)];
    const Rgb& kt = bp.transmit_colors[size_t(c)];
    r = {r.r + w * kr.r, r.g + w * kr.g, r.b + w * kr.b};
    t = {t.r + w * kt.r, t.g + w * kt.g, t.b + w * kt.b};
    if (w > best) {
      best = w;
      sh.point.color = c;
    }
  }
  sh.kd_r = r;
  sh.kd_t = t;
}

void KnitMaterial::set_colors(KnitShade& sh, int color_index) const {
  const int c = std::clamp(color_index, 0, params_.bsdf.num_colors() - 1);
  sh.point.color = c;
  sh.kd_r = params_.bsdf.reflect_colors[size_t(c)];
  sh.kd_t = params_.bsdf.transmit_colors[size_t(c)];
}

KnitMaterial::Route KnitMaterial::route(const BaseHit& hit, Vec3& fx, Vec3& fy, Vec3& e,
                                        std::optional<FootprintTable::SubBox>* sub, FootprintMemo* memo,
                                        FootprintTable::NodeSums** sums) const {
  if (params_.mode != KnitMode::MultiScale) return Route::NearField;
  footprint_axes(hit, fx, fy);
  e = k::knit_footprint_extent(surface_.geom(), fx, fy);
  // A cell or more in both directions (knit_footprint_stratified's test).
  if (e.x >= 1.0f && e.y >= 1.0f) return table_ ? Route::Cells : Route::Marched;
  const Vec3 c = footprint_centre(hit);
  if (memo && sub && sums && sub_cells_reach(e)) {
    // A box kept for this pixel that agrees with the hit's own (same
    // material, centre and extent within kTolerance of its extent).
    const float tol = FootprintMemo::kTolerance;
    const float cw = K_2PI, ch = surface_.geom().row_spacing;
    for (FootprintMemo::Entry& m : memo->entries_)
      if (m.material == this && std::fabs(c.x - m.x) <= tol * m.ex * cw && std::fabs(c.y - m.y) <= tol * m.ey * ch &&
          std::fabs(e.x - m.ex) <= tol * m.ex && std::fabs(e.y - m.ey) <= tol * m.ey) {
        *sub = m.box;
        *sums = &m.sums;
        ++memo->reused_;
        return Route::SubCells;
      }
  }
  if (std::optional<FootprintTable::SubBox> box = sub_cells_serve(c.x, c.y, e)) {
    if (memo && sub && sums) {
      // Kept in place of the older of the two.
      FootprintMemo::Entry& m = memo->entries_[size_t(memo->next_)];
      memo->next_ = 1 - memo->next_;
      m.material = this;
      m.x = c.x;
      m.y = c.y;
      m.ex = e.x;
      m.ey = e.y;
      m.box = box;
      m.sums = FootprintTable::NodeSums{};
      *sums = &m.sums;
      ++memo->found_;
    }
    if (sub) *sub = box;
    return Route::SubCells;
  }
  return params_.near_field_below_cell ? Route::NearField : Route::Marched;
}

bool KnitMaterial::sub_cells_reach(Vec3 e) const {
  return table_ && table_->has_sub_cells() && spans_table_min_cells(e);
}

std::optional<FootprintTable::SubBox> KnitMaterial::sub_cells_serve(float x, float y, Vec3 e) const {
  if (!sub_cells_reach(e)) return std::nullopt;
  return FootprintTable::sub_box_at(x, y, e.x, e.y, surface_.geom());
}

bool KnitMaterial::table_serves(float x, float y, Vec3 fx, Vec3 fy) const {
  if (!table_) return false;
  const Vec3 e = k::knit_footprint_extent(surface_.geom(), fx, fy);
  return (e.x >= 1.0f && e.y >= 1.0f) || sub_cells_serve(x, y, e).has_value();
}

bool KnitMaterial::near_field_at(const BaseHit& hit) const {
  Vec3 fx, fy, e;
  return route(hit, fx, fy, e) == Route::NearField;
}

bool KnitMaterial::table_would_serve(const BaseHit& hit) const {
  if (params_.mode == KnitMode::MultiScale) return false;
  Vec3 fx, fy;
  footprint_axes(hit, fx, fy);
  return spans_table_min_cells(k::knit_footprint_extent(surface_.geom(), fx, fy));
}

KnitMaterial::HitRoute KnitMaterial::route_of(const BaseHit& hit, FootprintMemo* memo) const {
  HitRoute r;
  r.route = int(route(hit, r.fx, r.fy, r.e, &r.box, memo, &r.sums));
  return r;
}

bool KnitMaterial::uses_shift(const BaseHit& hit) const { return uses_shift(route_of(hit)); }

bool KnitMaterial::uses_shift(const HitRoute& r) const {
  switch (Route(r.route)) {
    case Route::NearField:
      return false;  // one ray, no footprint points
    case Route::SubCells:
      return params_.bsdf.num_colors() > KNIT_MS_COLORS;  // only to pick one colour of many
    case Route::Cells:
      return !table_->counts_without_points();  // the colours' or the box's points
    case Route::Marched:
      break;
  }
  return true;
}

KnitShade KnitMaterial::shade(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame,
                              std::array<float, 2> shift, float u) const {
  return shade(hit, route_of(hit), ray_dir, frame, shift, u);
}

KnitShade KnitMaterial::shade(const BaseHit& hit, const HitRoute& r, Vec3 ray_dir, const FrameProvider* frame,
                              std::array<float, 2> shift, float u) const {
  KnitShade sh = unshaded();
  const YarnBsdfParams& bp = params_.bsdf;
  const float S = hit.pattern_per_world;
  // The footprint's centre (BaseHit::box_du); the near field's point is (x, y).
  const Vec3 centre = footprint_centre(hit);
  const float xc = centre.x, yc = centre.y;
  const float x = params_.uv_scale * hit.u, y = params_.uv_scale * hit.v;
  const Vec3 wi = k::kv3_neg(k::kv3_to_local(ray_dir, hit.t, hit.b, hit.n));
  sh.from_back = wi.z < 0;
  const float top = surface_.shell_top();

  const Vec3 &fx = r.fx, &fy = r.fy, &e = r.e;
  const std::optional<FootprintTable::SubBox>& box = r.box;
  const Route rt = Route(r.route);
  sh.quarter_cell = rt == Route::NearField && params_.mode == KnitMode::MultiScale && table_ &&
                    FootprintTable::sub_box(xc, yc, e.x, e.y, surface_.geom());  // (e is set in multi-scale only)
  if (table_bsdf_ && (rt == Route::Cells || rt == Route::SubCells) && table_->one_colour()) {
    // The tabulated BSDF of a footprint of one colour index needs only the
    // hit fractions: its p_delta and each class's share of its hits (the
    // aggregate's means would go unused). Shaded at the base hit.
    std::array<float, FootprintTable::kClasses> slot_hits{};
    float p;
    if (rt == Route::SubCells) {
      p = r.sums ? table_->p_delta_sub(surface_, *box, wi, slot_hits.data(), *r.sums)
                 : table_->p_delta_sub(surface_, *box, wi, slot_hits.data());
      sh.from_sub_cells = true;
    } else {
      const k::KFootprint f =
          k::knit_footprint(surface_.geom(), xc, yc, fx, fy, footprint_points_for(fx, fy), shift[0], shift[1]);
      p = table_->p_delta(surface_, f, wi, slot_hits.data());
    }
    sh.from_table = true;
    sh.steps = 0;
    sh.point.p_delta = p;
    if (!(p < 1) || (u >= 0 && u < p)) return sh;  // (the caller passes through a gap)
    set_colors(sh, 0);
    if (use_table_bsdf(hit, wi, slot_hits.data(), u, sh)) {
      sh.pass_through = false;
      sh.point.layers = 1;
      sh.point.shadow = mean_shadow_;
      sh.offset = k::kv3(0, 0, 0);
      return sh;
    }
    sh = unshaded();  // (no class with hits to weigh: the aggregate below)
    sh.from_back = wi.z < 0;
  }
  if (rt != Route::NearField) {
    k::KnitAggregate a;
    // (the points only for the whole cells' and the marched footprints)
    const int points = rt == Route::SubCells ? 0 : footprint_points_for(fx, fy);
    std::array<float, FootprintTable::kClasses> slot_hits{};  // the tabulated BSDF's mix
    float* const mix_out = table_bsdf_ ? slot_hits.data() : nullptr;
    if (rt == Route::SubCells) {
      a = table_->aggregate_sub(surface_, *box, wi, shift[0], mix_out);  // flat-base, as below
      sh.from_table = true;
      sh.from_sub_cells = true;
    } else if (rt == Route::Cells) {
      const k::KFootprint f = k::knit_footprint(surface_.geom(), xc, yc, fx, fy, points, shift[0], shift[1]);
      a = table_->aggregate(surface_, f, wi, mix_out);  // flat-base statistics: no curvature needed
      sh.from_table = true;
    } else {
      // The footprint's points share the frame at the hit; a frame field
      // contributes its curvature there (pattern units).
      const Vec3 kap = frame ? frame->curvature(xc, yc) : k::kv3(hit.kx / S, hit.ky / S, 0);
      a = k::knit_aggregate(surface_.geom(), surface_.codes(), surface_.colors(), xc, yc, fx, fy, wi, points,
                            shift[0], shift[1], kap.x, kap.y, curved_segment(kap.x, kap.y),
                            params_.capm_options.max_steps);
      sh.aggregated = true;
    }
    sh.steps = int(a.steps * float(a.points) + 0.5f);
    if (a.hits == 0) {
      sh.point.p_delta = 1;
      return sh;
    }
    sh.pass_through = false;
    sh.point.p_delta = a.p_delta;
    sh.point.layers = std::max(1, round_count(a.layers));
    sh.point.shadow = mean_shadow_;
    // Body colour: the palette mixed by the footprint's colour histogram, or
    // (more colours than the histogram has bins) the colour of one hit; the
    // same weights for a folded tabulated BSDF's colours.
    std::array<float, TableBsdf::kMaxEntries> colour_w{};
    const float* cw = a.color_w;
    if (bp.num_colors() > KNIT_MS_COLORS) {
      set_colors(sh, a.color_pick);
      colour_w[size_t(std::clamp(sh.point.color, 0, TableBsdf::kMaxEntries - 1))] = 1;
      cw = colour_w.data();
    } else if (bp.num_colors() == 1 && a.color_w[0] == 1.0f) {
      set_colors(sh, 0);  // what mixing the one colour at weight 1 gives, bit for bit
    } else {
      mix_colors(sh, a.color_w);
    }
    if (mix_out && use_table_bsdf(hit, wi, slot_hits.data(), u, sh, cw)) {
      const Vec3 d = k::kv3_sub(a.position, k::kv3(xc, yc, top));
      sh.offset = k::kv3_scale(to_world(d, hit.t, hit.b, hit.n), 1.0f / S);
      return sh;
    }
    // Shading frame: mean normal, mean tangent made orthogonal to it; the
    // LEAN covariance, rotated into that frame, widens the specular lobes
    // (knit_ms_lobe, which the OSL shader calls too).
    const k::KMsLobe lobe = k::knit_ms_lobe(a.n, a.tangent, a.sxx, a.sxy, a.syy, bp.roughness_x, bp.roughness_y,
                                            bp.trans_roughness_x, bp.trans_roughness_y);
    sh.spec_r = k::bsdf_mf_make(lobe.alpha_u, lobe.alpha_v, bp.eta);
    sh.spec_t = k::bsdf_mf_make(lobe.trans_alpha_u, lobe.trans_alpha_v, bp.eta);
    sh.st = to_world(lobe.t, hit.t, hit.b, hit.n);
    sh.sb = to_world(lobe.b, hit.t, hit.b, hit.n);
    sh.sn = to_world(lobe.n, hit.t, hit.b, hit.n);
    const Vec3 d = k::kv3_sub(a.position, k::kv3(xc, yc, top));
    sh.offset = k::kv3_scale(to_world(d, hit.t, hit.b, hit.n), 1.0f / S);
    return sh;
  }

  // Near field (or a multi-scale footprint below a cell, near_field_at): one
  // ray, CAPM or (no parallax) the height query at (x, y).
  k::KnitLineHit h;
  if (params_.capm) {
    const k::KnitCapm st = march(hit, ray_dir, frame);
    sh.steps = st.steps;
    if (st.state != KNIT_CAPM_HIT) {
      sh.point.p_delta = 1;
      return sh;
    }
    h = st.hit;
  } else {
    const Vec3 o = k::kv3(x, y, sh.from_back ? -top - 0.01f : top + 0.01f);
    h = k::knit_line_query(surface_.geom(), surface_.codes(), surface_.colors(), o,
                           k::kv3(0, 0, sh.from_back ? 1.0f : -1.0f), 0, 2 * top + 0.02f, KNIT_QUERY_FIRST);
    sh.steps = 1;
    if (!h.hit) {
      sh.point.p_delta = 1;
      return sh;
    }
    // Without parallax the hit is where the ray met the mesh.
    h.p = k::kv3(x, y, h.p.z);
  }
  sh.in_shell = params_.capm;  // without parallax there is no shell to march in
  shade_yarn(hit, h, frame, sh);
  return sh;
}

void KnitMaterial::shade_yarn(const BaseHit& hit, const k::KnitLineHit& h, const FrameProvider* frame,
                              KnitShade& sh) const {
  const float S = hit.pattern_per_world;
  const float x = params_.uv_scale * hit.u, y = params_.uv_scale * hit.v;
  const float top = surface_.shell_top();
  sh.p_yarn = h.p;
  sh.pass_through = false;
  // The layer count compounds the attenuation for the yarns under the hit
  // that transmitted light also crosses. With self-shadowing those yarns are
  // in the path (they block it, as explicit tubes do): one layer, no count.
  sh.point.layers = sh.in_shell && params_.self_shadowing
                        ? 1
                        : std::max(1, k::knit_vertical_layers(surface_.geom(), surface_.codes(), surface_.colors(),
                                                             h.p.x, h.p.y));
  set_colors(sh, h.colour);
  // Base frame at the yarn hit.
  Vec3 ft = hit.t, fb = hit.b, fn = hit.n;
  if (frame) {
    int64_t hint = hit.frame_hint;  // the yarn hit lies near the base hit
    frame->frame_near(h.p.x, h.p.y, hint, ft, fb, fn);
  } else if (hit.kx != 0 || hit.ky != 0) {
    curved_frame(hit.t, hit.b, hit.n, hit.kx / S, hit.ky / S, h.p.x - x, h.p.y - y, ft, fb, fn);
  }
  // Yarn frame (pattern-local): tangent along the yarn, normal of the tube.
  const Vec3 N = k::kv3_normalize(h.n);
  Vec3 T = k::kv3_sub(h.tangent, k::kv3_scale(N, k::kv3_dot(h.tangent, N)));
  T = k::kv3_len(T) > 1e-6f ? k::kv3_normalize(T) : k::kv3_normalize(k::kv3_cross(k::kv3(0, 1, 0), N));
  Vec3 lt = T, ln = N, lb = k::kv3_cross(N, T);
  if (params_.ply_detail) {
    // Azimuth around the yarn from the fabric normal's projection; the ply's
    // length coordinate from t (ply_arc).
    Vec3 ref = k::kv3_sub(k::kv3(0, 0, 1), k::kv3_scale(h.tangent, h.tangent.z));
    if (k::kv3_len(ref) < 1e-4f) ref = k::kv3(1, 0, 0);
    ref = k::kv3_normalize(ref);
    const Vec3 tt = k::kv3_normalize(h.tangent);
    const float phi = std::atan2(k::kv3_dot(N, k::kv3_cross(tt, ref)), k::kv3_dot(N, ref));
    // (As Cycles renders it: the procedural profile the shader evaluates,
    // not the table.)
    const k::KPlyShade ps = params_.bsdf_model == KnitBsdfModel::Cycles
                                ? k::ply_shade_procedural(ply_.kernel_params(), phi, ply_arc(h.t, h.row))
                                : ply_.lookup(phi, ply_arc(h.t, h.row));
    sh.point.shadow = ps.shadow;
    lt = to_world(ps.t, T, lb, N);
    ln = to_world(ps.n, T, lb, N);
    lb = to_world(ps.b, T, lb, N);
  }
  sh.st = to_world(lt, ft, fb, fn);
  sh.sb = to_world(lb, ft, fb, fn);
  sh.sn = to_world(ln, ft, fb, fn);
  const Vec3 d = k::kv3_sub(h.p, k::kv3(x, y, top));
  sh.offset = k::kv3_scale(to_world(d, hit.t, hit.b, hit.n), 1.0f / S);
}

float KnitMaterial::transmittance(const BaseHit& hit, Vec3 ray_dir, const FrameProvider* frame,
                                  std::array<float, 2> shift) const {
  return transmittance(hit, route_of(hit), ray_dir, frame, shift);
}

float KnitMaterial::transmittance(const BaseHit& hit, const HitRoute& r, Vec3 ray_dir, const FrameProvider* frame,
                                  std::array<float, 2> shift) const {
  // Only whether the ray meets yarn (or how often, over a footprint): no
  // shading frame, layer count or ply profile.
  const Vec3 &fx = r.fx, &fy = r.fy;
  const std::optional<FootprintTable::SubBox>& box = r.box;
  const Route rt = Route(r.route);
  if (rt != Route::NearField) {
    const float S = hit.pattern_per_world;
    const Vec3 c = footprint_centre(hit);
    const float x = c.x, y = c.y;
    const Vec3 wi = k::kv3_neg(k::kv3_to_local(ray_dir, hit.t, hit.b, hit.n));
    if (rt == Route::SubCells) return table_->p_delta_sub(surface_, *box, wi);
    const k::KFootprint f =
        k::knit_footprint(surface_.geom(), x, y, fx, fy, footprint_points_for(fx, fy), shift[0], shift[1]);
    if (rt == Route::Cells) return table_->p_delta(surface_, f, wi);
    // (the curvature only for the marched footprint: a frame lookup)
    const Vec3 kap = frame ? frame->curvature(x, y) : k::kv3(hit.kx / S, hit.ky / S, 0);
    return k::knit_footprint_p_delta(surface_.geom(), surface_.codes(), surface_.colors(), f, wi, kap.x, kap.y,
                                     curved_segment(kap.x, kap.y), params_.capm_options.max_steps);
  }
  if (!params_.capm) return shade(hit, r, ray_dir, frame, shift).pass_through ? 1.0f : 0.0f;
  // Hit or miss only (a corrected hit stays a hit: knit_capm_correct keeps
  // the first one when the corrected segment misses).
  return march(hit, ray_dir, frame, true).state == KNIT_CAPM_HIT ? 0.0f : 1.0f;
}

bool KnitMaterial::use_table_bsdf(const BaseHit& hit, Vec3 wi, const float* slot_hits, float u, KnitShade& sh,
                                  const float* colour_w) const {
  // The caller's number past the pass through the gaps: uniform again.
  const float p = sh.point.p_delta;
  const float u_mix = u >= 0 && p < 1 ? std::clamp((u - p) / (1 - p), 0.0f, 0.99999994f) : -1.0f;
  sh.mix = table_bsdf_->mix(slot_hits, wi, (sh.kd_r.r + sh.kd_r.g + sh.kd_r.b) / 3,
                            (sh.kd_t.r + sh.kd_t.g + sh.kd_t.b) / 3, u_mix, colour_w);
  if (sh.mix.n == 0) return false;  // (no class with hits to weigh)
  sh.table_bsdf = table_bsdf_.get();
  sh.st = hit.t;  // the base's frame: fabric x, y and front normal
  sh.sb = hit.b;
  sh.sn = hit.n;
  return true;
}

KnitShade KnitMaterial::point_shade(const BaseHit& hit, const k::KnitLineHit& h, bool from_back) const {
  KnitShade sh = unshaded();
  sh.from_back = from_back;
  sh.in_shell = params_.capm;
  shade_yarn(hit, h, nullptr, sh);
  return sh;
}

k::KYarnBsdf KnitMaterial::kernel_bsdf(const KnitShade& sh) const {
  const YarnBsdfParams& bp = params_.bsdf;
  const k::KAttenuation att = k::bsdf_att_make(bp.optical_depth, std::min(sh.point.layers, 4));
  return k::yarn_bsdf_make(sh.spec_r, sh.spec_t, k::kv3(sh.kd_r.r, sh.kd_r.g, sh.kd_r.b),
                           k::kv3(sh.kd_t.r, sh.kd_t.g, sh.kd_t.b), bp.body_energy, bp.body_reflect,
                           sh.point.shadow, att);
}

}  // namespace knit
