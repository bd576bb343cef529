#include "render/material_knit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "render/errors.h"

namespace knit::render {

KnitMeshTables knit_mesh_tables(const TriangleMesh& mesh, float uv_scale) {
  KnitMeshTables t;
  const size_t n = mesh.num_triangles();
  t.triangles.resize(n);
  std::vector<char> ok(n, 0);
  double s_sum = 0, total_area = 0;
  size_t s_count = 0;
  for (size_t i = 0; i < n; ++i) {
    UvDerivatives d;
    if (!uv_derivatives(mesh, i, d)) continue;
    const float lu = length(d.dpdu), lv = length(d.dpdv);
    KnitTriangle& tri = t.triangles[i];
    tri.pattern_per_world = uv_scale / std::sqrt(lu * lv);
    tri.kx = d.curvature_u();
    tri.ky = d.curvature_v();
    if (!std::isfinite(tri.pattern_per_world) || !(tri.pattern_per_world > 0)) continue;
    if (!std::isfinite(tri.kx)) tri.kx = 0;
    if (!std::isfinite(tri.ky)) tri.ky = 0;
    ok[i] = 1;
    s_sum += tri.pattern_per_world;
    ++s_count;
    const Vec2 a = mesh.uvs[mesh.indices[3 * i]], b = mesh.uvs[mesh.indices[3 * i + 1]],
               c = mesh.uvs[mesh.indices[3 * i + 2]];
    const double area = 0.5 * std::fabs(double(b.x - a.x) * (c.y - a.y) - double(b.y - a.y) * (c.x - a.x));
    total_area += area;
    const float ratio = std::max(lu / lv, lv / lu);
    if (ratio > 1.1f) {
      ++t.stretched;
      t.stretched_area += area;
    }
    t.worst_ratio = std::max(t.worst_ratio, ratio);
  }
  // Triangles without UV area get the mean scale (a ray can still hit them).
  const float mean_s = s_count ? float(s_sum / double(s_count)) : uv_scale;
  for (size_t i = 0; i < n; ++i)
    if (!ok[i]) t.triangles[i] = KnitTriangle{mean_s, 0, 0};
  if (total_area > 0) t.stretched_area /= total_area;
  t.with_uv_area = s_count;
  t.flat = true;
  for (const Vec3& nv : mesh.normals)
    if (length(nv - mesh.normals[0]) > 1e-4f) {
      t.flat = false;
      break;
    }
  if (t.flat)
    for (KnitTriangle& tri : t.triangles) tri.kx = tri.ky = 0;
  return t;
}

KnitModelMaterial::KnitModelMaterial(const KnitDesc& desc, std::shared_ptr<const TriangleMesh> mesh,
                                     const std::string& scene_file, const std::string& material_path,
                                     const std::string& object_path, const std::string& where, Warnings& warnings)
    : model_(desc.model), mesh_(std::move(mesh)) {
  const float uv_scale = model_->params().uv_scale;
  tables_ = knit_mesh_tables(*mesh_, uv_scale);
  if (tables_.with_uv_area == 0)
    throw SceneError(scene_file, object_path + ".mesh",
                     mesh_->file + ": no triangle has a non-zero UV area and a size in the scene that single "
                                   "precision resolves (after the object's transform), which the knit material needs");
  // Pattern space is single precision (knit::kMaxPatternCoord).
  for (size_t i = 0; i < mesh_->uvs.size(); ++i) {
    const Vec2 uv = mesh_->uvs[i];
    const double x = double(uv.x) * uv_scale, y = double(uv.y) * uv_scale;
    if (!(std::fabs(x) <= knit::kMaxPatternCoord && std::fabs(y) <= knit::kMaxPatternCoord))
      throw SceneError(scene_file, object_path + ".mesh",
                       mesh_->file + ": vertex " + std::to_string(i) + " has UV (" + fmt_num(uv.x) + ", " +
                           fmt_num(uv.y) + "), which " + material_path + " (uv_scale " + fmt_num(uv_scale) +
                           ") maps to pattern coordinates beyond +-" + fmt_num(knit::kMaxPatternCoord) +
                           ", where single-precision pattern space no longer resolves the yarns: lower "
                           "uv_scale or bring the UVs nearer 0");
  }
  if (model_->params().mode == knit::KnitMode::MultiScale) {
    knit::KnitMaterialParams p = model_->params();
    p.mode = knit::KnitMode::NearField;
    point_model_ = std::make_shared<const knit::KnitMaterial>(model_->surface().pattern(), p);
  }
  min_footprint_ = 1e-4f * model_->surface().cell_width();
  footprint_scale_ = desc.footprint_scale;
  centre_at_pixel_ = desc.footprint_centre == FootprintCentre::Pixel;
  cycles_ = model_->params().bsdf_model == knit::KnitBsdfModel::Cycles;
  cycles4_ = cycles_ && desc.cycles_version == 4;
  // A stretch worth a warning: over 1% of the UV area, or by 1.5 or more
  // anywhere. (A puffed cushion's corners, 0.1% of its UV area stretched by
  // at most 17%, do not show; a warning there only teaches users to ignore
  // warnings.)
  if (tables_.stretched > 0 && (tables_.stretched_area >= 0.01 || tables_.worst_ratio >= 1.5f)) {
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "%zu of %zu triangles (%.1f%% of the UV area) have |dP/du| and |dP/dv| differing by more than "
                  "10%% (worst ratio %.2f)",
                  tables_.stretched, tables_.triangles.size(), 100.0 * tables_.stretched_area, tables_.worst_ratio);
    warnings.add(where + ": " + mesh_->file + ": " + buf + ": the stitches of " + material_path +
                 " are stretched there");
  }
  if (desc.frames == KnitFrames::Baked) {
    try {
      frame_ = MeshFrame::from_baked(desc.frames_file, uv_scale);
    } catch (const std::exception& e) {
      throw SceneError(scene_file, material_path + ".frames", e.what());
    }
  } else if (desc.frames == KnitFrames::Exact && !tables_.flat) {
    frame_ = std::make_unique<MeshFrame>(mesh_, uv_scale);
  }
}

KnitModelMaterial::~KnitModelMaterial() = default;

size_t KnitModelMaterial::binding_bytes() const {
  return tables_.triangles.size() * sizeof(KnitTriangle) + (frame_ ? frame_->memory_bytes() : 0);
}

knit::BaseHit KnitModelMaterial::base_hit(const SurfaceInteraction& si, float diff_scale, Vec2 pixel_offset) const {
  knit::BaseHit h;
  h.u = si.uv.x;
  h.v = si.uv.y;
  h.t = to_kvec(si.shading.t);
  h.b = to_kvec(si.shading.b);
  h.n = to_kvec(si.shading.n);
  const size_t prim = std::min<size_t>(si.prim_id, tables_.triangles.size() - 1);
  const KnitTriangle& tri = tables_.triangles[prim];
  h.pattern_per_world = tri.pattern_per_world;
  h.kx = tri.kx;
  h.ky = tri.ky;
  h.frame_hint = static_cast<int64_t>(prim);  // frame_ is this mesh's: its lookups start in the triangle hit
  if (si.footprint.valid && diff_scale > 0) {
    const float k = footprint_scale_ / diff_scale;
    h.dudx = si.footprint.dudx * k;
    h.dvdx = si.footprint.dvdx * k;
    h.dudy = si.footprint.dudy * k;
    h.dvdy = si.footprint.dvdy * k;
    if (centre_at_pixel_) {
      // The sample lies pixel_offset from its pixel's centre: the footprint's
      // centre goes that far back (a footprint below a pixel part of the way,
      // so that the boxes of the pixel's samples still reach its edges and
      // always hold their own sample).
      const float c = std::min(footprint_scale_, 1.0f) / diff_scale;
      h.box_du = -c * (pixel_offset.x * si.footprint.dudx + pixel_offset.y * si.footprint.dudy);
      h.box_dv = -c * (pixel_offset.x * si.footprint.dvdx + pixel_offset.y * si.footprint.dvdy);
    }
  }
  return h;
}

const knit::KnitMaterial& KnitModelMaterial::model_for(const knit::BaseHit& h) const {
  if (!point_model_) return *model_;
  const float us = model_->params().uv_scale;
  const float extent = us * (std::fabs(h.dudx) + std::fabs(h.dvdx) + std::fabs(h.dudy) + std::fabs(h.dvdy));
  return extent > min_footprint_ ? *model_ : *point_model_;
}

// The footprint's sample shift: drawn when the model reads it, else the
// draw is skipped (a multi-scale footprint read whole from the class table,
// the near field), so that the sampler's later draws stay the same.
static Vec2 footprint_shift(const knit::KnitMaterial& model, const knit::KnitMaterial::HitRoute& route,
                            Sampler& sampler) {
  if (model.uses_shift(route)) return sampler.get2d();
  sampler.skip();
  return {0.5f, 0.5f};
}

PassThrough KnitModelMaterial::resolve(SurfaceInteraction& si, const RayDifferential& ray, Sampler& sampler) const {
  PassThrough pt;
  knit::BaseHit hit = base_hit(si, ray.diff_scale, {ray.pixel_dx, ray.pixel_dy});
  if (cycles_) cycles_footprint(si, ray.d, hit);
  const knit::KnitMaterial& model = cone_footprint(si, ray.d, hit) ? *model_ : model_for(hit);
  // (once for the shift and the shading; with the pixel's memo where the
  // footprint is the pixel's)
  const knit::KnitMaterial::HitRoute route = model.route_of(hit, centre_at_pixel_ ? ray.footprint_memo : nullptr);
  const Vec2 shift = footprint_shift(model, route, sampler);
  // With the tabulated BSDF, one number serves the pass through the gaps
  // and, past it, the pick of the mix's view nodes (KnitMaterial::shade).
  const float u = model.table_bsdf() ? sampler.get1d() : -1.0f;
  const knit::KnitShade sh = model.shade(hit, route, to_kvec(ray.d), frame_.get(), {shift.x, shift.y}, u);
  pt.from_table = sh.from_table;
  pt.from_sub_cells = sh.from_sub_cells;
  pt.quarter_cell = sh.quarter_cell;
  pt.aggregated = sh.aggregated;
  pt.table_would_serve = model.table_would_serve(hit);
  if (sh.pass_through) {
    pt.pass = true;  // no yarn along this ray: it goes on straight
    return pt;
  }
  if (sh.point.p_delta > 0 && (u >= 0 ? u : sampler.get1d()) < sh.point.p_delta) {
    pt.pass = true;  // multi-scale: through a gap, with probability p_delta
    return pt;
  }
  apply_shade(si, sh, model);
  if (!si.yarn.active) {
    pt.pass = true;  // never seen; keeps a broken frame from producing NaNs
    return pt;
  }
  if (cycles_) {
    // Cycles' closures: the transparent() one (through, a delta) goes on as
    // a pass-through with the probability the mixture would pick it, the
    // others shade the hit (YarnShadedMaterial, the smooth lobes alone).
    si.yarn.cycles = true;
    si.yarn.cyc = knit::k::yarn_cycles_with_base(knit::k::yarn_cycles_make(si.yarn.bsdf,
                                                                           to_kvec(si.shading.to_local(-ray.d))),
                                                 to_kvec(si.shading.to_local(si.yarn.base.n)));
    if (cycles4_) si.yarn.cyc = knit::k::yarn_cycles_as_cycles4(si.yarn.cyc);
    const float p3 = si.yarn.cyc.p3;
    if (p3 > 0) {
      if (sampler.get1d() < p3) {
        pt.pass = true;
        pt.weight = Rgb(si.yarn.cyc.w.through / p3);
        return pt;
      }
      pt.weight = Rgb(1.0f / (1.0f - p3));
    }
  }
  return pt;
}

void KnitModelMaterial::apply_shade(SurfaceInteraction& si, const knit::KnitShade& sh,
                                    const knit::KnitMaterial& model) const {
  // Shaded at the base hit point, in the yarn's frame.
  const Vec3 n = from_kvec(sh.sn);
  const float ln = length(n);
  si.yarn.active = false;
  if (!(ln > 0.5f) || !std::isfinite(ln)) return;
  const Frame base = si.yarn.in_shell ? si.yarn.base : si.shading;
  si.shading = Frame::from_normal_tangent(n / ln, from_kvec(sh.st));
  si.yarn.active = true;
  if (sh.table_bsdf) {
    // The tabulated BSDF reads only the body colours of the yarn BSDF.
    si.yarn.bsdf.kd_r = knit::k::kv3(sh.kd_r.r, sh.kd_r.g, sh.kd_r.b);
    si.yarn.bsdf.kd_t = knit::k::kv3(sh.kd_t.r, sh.kd_t.g, sh.kd_t.b);
  } else {
    si.yarn.bsdf = model.kernel_bsdf(sh);
  }
  si.yarn.table = sh.table_bsdf;
  if (sh.table_bsdf) si.yarn.mix = sh.mix;
  si.yarn.cycles = false;
  si.yarn.in_shell = sh.in_shell;
  si.yarn.from_back = sh.from_back;
  si.yarn.shell_p = sh.p_yarn;
  si.yarn.base = base;
}

bool KnitModelMaterial::cone_footprint(const SurfaceInteraction& si, Vec3 dir, knit::BaseHit& hit) const {
  if (!point_model_ || si.footprint.valid || !(si.cone_width > 0) || !model_->footprint_table()) return false;
  const float w = si.cone_width * footprint_scale_;
  // Across the ray's projection the footprint is w wide, along it w / cos.
  const Vec3 d = si.shading.to_local(dir);
  const float c = std::max(std::fabs(d.z), 0.125f);
  const float lt = std::sqrt(d.x * d.x + d.y * d.y);
  const float e1x = lt > 1e-6f ? d.x / lt : 1.0f, e1y = lt > 1e-6f ? d.y / lt : 0.0f;
  const float S = hit.pattern_per_world, us = model_->params().uv_scale;
  const float a = S * w / c, b = S * w;  // pattern units
  const float fxx = a * e1x, fxy = a * e1y, fyx = -b * e1y, fyy = b * e1x;
  // The class table's domain: whole cells, or its sub-cells.
  if (!model_->table_serves(us * hit.u, us * hit.v, knit::k::kv3(fxx, fxy, 0), knit::k::kv3(fyx, fyy, 0)))
    return false;
  hit.dudx = fxx / us;
  hit.dvdx = fxy / us;
  hit.dudy = fyx / us;
  hit.dvdy = fyy / us;
  return true;
}

bool KnitModelMaterial::cycles_footprint(const SurfaceInteraction& si, Vec3 dir, knit::BaseHit& hit) const {
  if (!point_model_ || !(si.cone_width > 0)) return false;
  // Cycles' UV differentials: two tangent vectors of the cone's width, UV
  // lengths w S / uv_scale on a mesh whose |dP/du| and |dP/dv| agree (S its
  // pattern units per world unit).
  const float us = model_->params().uv_scale;
  const float len = si.cone_width * footprint_scale_ * hit.pattern_per_world / us;
  const knit::k::KFootprintAxes f =
      knit::k::knit_footprint_isotropic(len, len, to_kvec(si.shading.to_local(dir)), us);
  hit.dudx = f.fx.x / us;
  hit.dvdx = f.fx.y / us;
  hit.dudy = f.fy.x / us;
  hit.dvdy = f.fy.y / us;
  return true;
}

bool KnitModelMaterial::cycles_mixture(const knit::KnitShade& sh, const knit::KnitMaterial& model, Vec3 wo,
                                       knit::k::KYarnCycles& out) {
  // The frame apply_shade gives the hit.
  const Vec3 n = from_kvec(sh.sn);
  const float ln = length(n);
  if (!(ln > 0.5f) || !std::isfinite(ln)) return false;
  const Frame f = Frame::from_normal_tangent(n / ln, from_kvec(sh.st));
  out = knit::k::yarn_cycles_make(model.kernel_bsdf(sh), to_kvec(f.to_local(wo)));
  return true;
}

knit::BaseHit KnitModelMaterial::shell_base_hit(const SurfaceInteraction& si) const {
  SurfaceInteraction base = si;
  base.shading = si.yarn.base;
  base.footprint.valid = false;
  return base_hit(base);
}

knit::KnitShade KnitModelMaterial::shell_shade(const SurfaceInteraction& si) {
  knit::KnitShade from;
  from.in_shell = si.yarn.in_shell;
  from.from_back = si.yarn.from_back;
  from.p_yarn = si.yarn.shell_p;
  return from;
}

Rgb KnitModelMaterial::self_transmittance(const SurfaceInteraction& si, Vec3 w) const {
  if (!si.yarn.in_shell) return Rgb(1.0f);
  return near_model().occluded_from(shell_base_hit(si), shell_shade(si), to_kvec(w), frame_.get()) ? Rgb()
                                                                                                   : Rgb(1.0f);
}

bool KnitModelMaterial::bounce_table(SurfaceInteraction& si, Vec3 wi, float u) const {
  // The yarn met inside the footprint is taken as yarn of the same classes
  // seen from -wi: the table's mix for that view (its view nodes picked
  // with u), at the same point.
  if (!si.yarn.table) return false;
  si.yarn.table->remix(si.yarn.mix, to_kvec(si.shading.to_local(-wi)), u);
  return si.yarn.mix.n > 0;
}

bool KnitModelMaterial::bounce_inside(SurfaceInteraction& si, Vec3 wi) const {
  if (!si.yarn.in_shell) return false;
  const knit::KnitMaterial& model = near_model();
  const knit::KnitShade sh = model.shade_from(shell_base_hit(si), shell_shade(si), to_kvec(wi), frame_.get());
  if (sh.pass_through) return false;
  apply_shade(si, sh, model);
  return si.yarn.active;
}

Rgb KnitModelMaterial::transmittance(const SurfaceInteraction& si, Vec3 w, Sampler& sampler) const {
  knit::BaseHit hit = base_hit(si);
  if (cycles_) {
    // What a shadow ray through the fabric gets in Cycles: the shader's
    // transparent() weight, p_delta + (1 - p_delta) through (1 in a gap), as
    // resolve() passes camera and bounce rays.
    cycles_footprint(si, w, hit);
    const knit::KnitMaterial& model = model_for(hit);
    const knit::KnitMaterial::HitRoute route = model.route_of(hit);
    const Vec2 shift = footprint_shift(model, route, sampler);
    const knit::KnitShade sh = model.shade(hit, route, to_kvec(w), frame_.get(), {shift.x, shift.y});
    if (sh.pass_through) return Rgb(1.0f);
    knit::k::KYarnCycles c;
    const float p = sh.point.p_delta;
    if (!cycles_mixture(sh, model, -w, c)) return Rgb(1.0f);  // (as resolve() passes it)
    return Rgb(p + (1 - p) * c.w.through);
  }
  const knit::KnitMaterial& model = cone_footprint(si, w, hit) ? *model_ : model_for(hit);
  const knit::KnitMaterial::HitRoute route = model.route_of(hit);
  const Vec2 shift = footprint_shift(model, route, sampler);
  return Rgb(model.transmittance(hit, route, to_kvec(w), frame_.get(), {shift.x, shift.y}));
}

}  // namespace knit::render
