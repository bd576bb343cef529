// The knit model on a base mesh (paper Sec. 4-6): knit::KnitMaterial
// (native/include/knit/shading.h) put on one mesh of the scene.
//
// The base mesh is the top of the yarn shell (paper Alg. 1): a ray that hits
// it from the front enters pattern space at (x, y, shell_top) with
// x = uv_scale u, y = uv_scale v; the yarns hang below the mesh. Pattern
// units per world unit, S = uv_scale / sqrt(|dP/du| |dP/dv|), are taken per
// triangle (a warning names meshes whose |dP/du| and |dP/dv| differ by more
// than 10%: stitches are stretched there).
//
// At a hit, resolve() fills knit::BaseHit (UV, the mesh's front-side frame,
// S, curvature, the UV footprint of the ray differentials) and runs
// KnitMaterial::shade with a per-sample footprint shift. A ray that meets
// no yarn passes on straight (a pass-through event); in multi-scale mode it
// also passes with probability p_delta. Otherwise the hit is shaded at the
// base hit point with the yarn BSDF in the yarn's frame. Shadow rays are
// attenuated by KnitMaterial::transmittance (near field 0 or 1, multi-scale
// p_delta). In multi-scale mode, hits without a ray footprint (shadow rays,
// rays after a diffuse bounce) use the near-field model: the aggregate over
// a point is that point's CAPM hit, so one march replaces N identical ones.
// With bsdf_model Cycles the hit is shaded as the OSL shader shades it in
// Cycles (docs/cycles.md): the smooth closures of bsdf_cycles.h, the
// transparent one as a pass-through, footprints from the ray's cone.
// docs/renderer.md#the-knit-model.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "knit/shading.h"
#include "render/material_yarn.h"
#include "render/mesh.h"
#include "render/mesh_frame.h"
#include "render/scene_desc.h"

namespace knit::render {

// Per-triangle pattern scale and curvature of a mesh under a knit material.
struct KnitTriangle {
  float pattern_per_world = 1;  // S = uv_scale / sqrt(|dP/du| |dP/dv|)
  float kx = 0, ky = 0;         // normal curvature along +u and +v, 1 / world units
};

struct KnitMeshTables {
  std::vector<KnitTriangle> triangles;
  bool flat = true;           // every vertex normal (nearly) the same
  size_t with_uv_area = 0;    // triangles with a usable UV map (the others get the mean scale)
  size_t stretched = 0;       // triangles whose |dP/du| / |dP/dv| is off 1 by more than 10%
  double stretched_area = 0;  // their share of the UV area
  float worst_ratio = 1;      // the largest max(ratio, 1 / ratio)
};

// Computes the tables for `mesh` (world space, with UVs) at `uv_scale`.
KnitMeshTables knit_mesh_tables(const TriangleMesh& mesh, float uv_scale);

class KnitModelMaterial final : public YarnShadedMaterial {
 public:
  // `where` names the object in warnings ("scene.json: objects[2] (name)");
  // errors name `object_path`. Throws SceneError for a mesh without any UV
  // area or an unreadable baked-frame file.
  KnitModelMaterial(const KnitDesc& desc, std::shared_ptr<const TriangleMesh> mesh, const std::string& scene_file,
                    const std::string& material_path, const std::string& object_path, const std::string& where,
                    Warnings& warnings);
  ~KnitModelMaterial() override;

  const char* kind() const override { return "knit"; }
  PassThrough resolve(SurfaceInteraction& si, const RayDifferential& ray, Sampler& sampler) const override;
  Rgb transmittance(const SurfaceInteraction& si, Vec3 w, Sampler& sampler) const override;
  Rgb self_transmittance(const SurfaceInteraction& si, Vec3 w) const override;
  bool bounce_table(SurfaceInteraction& si, Vec3 wi, float u) const override;
  bool bounce_inside(SurfaceInteraction& si, Vec3 wi) const override;

  const knit::KnitMaterial& model() const { return *model_; }
  // The BaseHit resolve() passes to the model; the UV footprint is scaled to
  // `footprint_scale` pixels (KnitDesc) from the ray's differentials, which
  // are `diff_scale` pixels apart, and centred at the pixel's centre (a
  // camera sample `pixel_offset` pixels from it; KnitDesc::footprint_centre).
  knit::BaseHit base_hit(const SurfaceInteraction& si, float diff_scale = 1.0f, Vec2 pixel_offset = {}) const;
  const knit::FrameProvider* frame_provider() const { return frame_.get(); }
  // bsdf_model Cycles, multi-scale: the footprint the OSL shader builds from
  // Cycles' ray differentials (knit::k::knit_footprint_isotropic), from the
  // ray's cone width at the hit (Cycles' compact dP) and the ray direction
  // `dir`, put into `hit`; false (hit unchanged) when the cone is unknown or
  // the material is not multi-scale.
  bool cycles_footprint(const SurfaceInteraction& si, Vec3 dir, knit::BaseHit& hit) const;
  // Renderer-side tables for this mesh (per-triangle data, the MeshFrame).
  size_t binding_bytes() const;

 private:
  // The model for hits without a footprint (shadow rays, rays after a
  // diffuse bounce): in multi-scale mode a near-field twin of model_ (every
  // footprint point would be the same CAPM ray: one march instead of N);
  // otherwise model_ itself.
  const knit::KnitMaterial& model_for(const knit::BaseHit& hit) const;
  // The near-field model (point_model_ or model_) and the base hit and shade
  // of a hit resolved inside the shell (si.yarn.in_shell), for marching on from it.
  const knit::KnitMaterial& near_model() const { return point_model_ ? *point_model_ : *model_; }
  knit::BaseHit shell_base_hit(const SurfaceInteraction& si) const;
  // Multi-scale, for a hit without differentials (past a diffuse bounce):
  // the footprint of the ray's cone (RayDifferential::cone_width) put into
  // `hit`, when it covers a stitch cell or more in both directions (the
  // class table's domain). False otherwise (the hit is then a point).
  bool cone_footprint(const SurfaceInteraction& si, Vec3 dir, knit::BaseHit& hit) const;
  // bsdf_model Cycles: the mixture of Cycles' closures for a shade seen from
  // wo (world, unit) in the frame apply_shade gives it; false when the
  // shade's frame is unusable.
  static bool cycles_mixture(const knit::KnitShade& sh, const knit::KnitMaterial& model, Vec3 wo,
                             knit::k::KYarnCycles& out);
  static knit::KnitShade shell_shade(const SurfaceInteraction& si);
  // Sets si's shading frame and yarn BSDF from a resolved shade.
  void apply_shade(SurfaceInteraction& si, const knit::KnitShade& sh, const knit::KnitMaterial& model) const;
  float min_footprint_ = 0;  // pattern units: smaller footprints count as none
  float footprint_scale_ = 1;  // pixels
  bool centre_at_pixel_ = true;  // KnitDesc::footprint_centre
  bool cycles_ = false;          // bsdf_model Cycles
  bool cycles4_ = false;         // and cycles_version 4 (yarn_cycles_as_cycles4)

  std::shared_ptr<const knit::KnitMaterial> model_;
  std::shared_ptr<const knit::KnitMaterial> point_model_;
  std::shared_ptr<const TriangleMesh> mesh_;
  KnitMeshTables tables_;
  std::unique_ptr<MeshFrame> frame_;  // null: flat mesh, or the curvature mode
};

}  // namespace knit::render
