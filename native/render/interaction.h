// What the integrator and the materials know about a ray-surface hit.
#pragma once

#include "knit/kernel.h"
#include "knit/table_bsdf.h"
#include "render/vec.h"

namespace knit::render {

// Yarn shading at a hit (the knit model's base hits and explicit yarn
// tubes): filled by the shape (curve data) and by Material::resolve (the
// kernel BSDF), read by the yarn materials' eval/pdf/sample.
struct YarnShading {
  bool active = false;      // bsdf is set: the hit is shaded with the yarn BSDF
  knit::k::KYarnBsdf bsdf{};
  // Explicit yarn tubes (CurveShape): colour index, the ply coordinate along the yarn
  // (pattern units) and azimuth around it (radians) at the hit.
  int color = 0;
  float arc = 0, phi = 0;
  // ... and the length of the tube segment hit (world units; 0 elsewhere),
  // for the render report's count of pixels that span few segments.
  float segment = 0;
  // The knit model's near field: the yarn point hit inside the shell
  // (pattern space) and the base mesh's frame there, for self-shadowing and
  // bounces inside the shell (KnitModelMaterial).
  bool in_shell = false;
  bool from_back = false;
  knit::k::kvec3 shell_p{};
  Frame base;
  // The knit model's class table with its tabulated BSDF: shaded with it
  // (in si.shading, the base's frame) instead of bsdf's lobes; bsdf holds
  // the body colours.
  const knit::TableBsdf* table = nullptr;
  knit::TableBsdf::Mix mix;
  // The knit model with bsdf_model Cycles: shaded with the smooth lobes of
  // Cycles' closures (bsdf_cycles.h), their weights fixed at this hit's
  // view direction; the transparent() lobe was the resolve's pass-through.
  bool cycles = false;
  knit::k::KYarnCycles cyc{};
};

// Screen-space footprint of a hit (ray differentials, Igehy 1999): how the
// hit point, the UVs and the shading normal change from one pixel to the
// next. Valid on camera paths until the first non-specular bounce.
struct Footprint {
  bool valid = false;
  Vec3 dpdx, dpdy;
  float dudx = 0, dvdx = 0, dudy = 0, dvdy = 0;
  Vec3 dndx, dndy;
};

struct SurfaceInteraction {
  Vec3 p;        // hit point (interpolated on the primitive, not o + t d)
  Vec3 ng;       // unit geometric normal, in the hemisphere of the shading normal
  Frame shading; // n: shading normal; t along +u, b along +v when the mesh has UVs
  Vec2 uv;       // texture coordinates (barycentrics when the mesh has none)
  bool has_uv = false;
  float t = 0;   // ray distance
  Footprint footprint;
  // Width of one pixel's footprint here from the ray's cone
  // (RayDifferential::cone_width; set by the integrator, 0 when unknown).
  float cone_width = 0;
  unsigned geom_id = 0, prim_id = 0;
  int material = -1;  // index into the scene's materials, -1 for lights
  int light = -1;     // index into the scene's lights when the surface emits
  YarnShading yarn;
};

}  // namespace knit::render
