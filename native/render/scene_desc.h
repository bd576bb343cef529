// The parsed, validated scene description (docs/scene-format.md). Plain data:
// everything here has been range-checked at the boundary, and every element
// remembers its JSON path so later stages (mesh loading, scene building) can
// still name the field at fault.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "knit/shading.h"

#include "render/errors.h"
#include "render/transform.h"
#include "render/vec.h"

namespace knit::render {

struct FilmDesc {
  int width = 640;
  int height = 360;
  int spp = 16;
  uint64_t seed = 0;
  float exposure = 0;  // stops, applied to both EXR and PNG output
};

struct CameraDesc {
  Vec3 position{0, 1, 5};
  Vec3 look_at{0, 0, 0};
  Vec3 up{0, 1, 0};
  float fov = 40;  // vertical field of view, degrees, in (0, 180)
};

enum class Strategy { Mis, Nee, Bsdf };

struct IntegratorDesc {
  int max_depth = 8;  // scattering events per path (1 = direct light only)
  int rr_depth = 3;   // Russian roulette starts after this many bounces
  Strategy strategy = Strategy::Mis;
  // Render knit materials as explicit yarn tubes (the ground truth) instead
  // of with the knit model (also `knitshade render --explicit-yarns`).
  bool explicit_yarns = false;
};

enum class LightType { Quad, Point, Directional, EnvironmentMap, EnvironmentUniform };

struct LightDesc {
  LightType type = LightType::Point;
  std::string path;  // JSON path, e.g. "lights[2]"
  // quad
  Vec3 corner, edge_u, edge_v;
  Rgb emission;  // radiance
  bool two_sided = false;
  // point
  Vec3 position;
  Rgb intensity;  // W/sr
  // directional
  Vec3 to_light;   // unit direction from the scene toward the light
  Rgb irradiance;  // on a surface facing the light
  // environment
  std::string file;  // resolved path of the lat-long image
  Rgb color;         // uniform environment radiance
  float strength = 1;
  float rotation = 0;  // degrees about +y
};

enum class MaterialType { Diffuse, Dielectric, Thin, Knit };

struct DiffuseDesc {
  Rgb albedo{0.8f};
};

constexpr double kMinDielectricRoughness = 0.01;

struct DielectricDesc {
  float eta = 1.5f;
  float roughness = 0;  // 0: smooth; else in [kMinDielectricRoughness, 1], GGX alpha = roughness^2
  Rgb tint{1.0f};       // applied to refraction
};

// A straight-through sheet: passes light unchanged in direction with
// `transmittance`, reflects diffusely with `albedo` (albedo + transmittance <= 1).
struct ThinDesc {
  Rgb transmittance{0.5f};
  Rgb albedo{0.0f};
};

// Where CAPM takes the base mesh's frame from (docs/scene-format.md#knit).
enum class FootprintCentre {
  Pixel,   // "pixel": the camera sample's pixel's centre
  Sample,  // "sample": the sample's own hit
};

enum class KnitFrames {
  Exact,      // MeshFrame: exact lookups on the mesh (flat meshes need none)
  Curvature,  // the hit's frame turned with the mesh's curvature at the hit (no lookups)
  Baked,      // MeshFrame over a frame image written by `knitshade bake-frames`
};

// The knit material: the knit model (knit::KnitMaterial, built and validated
// at parse time) plus what the renderer needs to put it on meshes.
struct KnitDesc {
  std::shared_ptr<const knit::KnitMaterial> model;
  std::string pattern_source;  // the resolved pattern file, or "<inline>"
  // Inline patterns only (as written in the scene): row-major codes and colours.
  int rows = 0, cols = 0;
  std::vector<int32_t> codes;
  std::vector<int32_t> colors;
  KnitFrames frames = KnitFrames::Exact;
  std::string frames_file;     // KnitFrames::Baked: the resolved frame image
  int explicit_samples = 64;   // explicit-yarn mode: polyline points per stitch (docs/scene-format.md)
  // (and at least 4). 512 points a stitch over the half cylinder close-up's
  // whole mesh: 2.4 GB resident (docs/renderer.md, "Tube density").
  static constexpr int kMaxExplicitSamples = 1024;
  float footprint_scale = 1;   // multi-scale footprint, in pixels (whatever the spp)
  // Where a camera sample's multi-scale footprint is centred: at its pixel's
  // centre, so that every sample of a pixel aggregates the same box (the
  // pixel is averaged once), or at the sample's own hit (the pixel is
  // averaged twice: by each box, then by the spread of the boxes).
  FootprintCentre footprint_centre = FootprintCentre::Pixel;
  // bsdf_model "cycles": the Cycles whose closure rules it follows, 5 (5.0
  // and later) or 4 (before 5.0: Blender 4.x, the standalone Cycles 4.2),
  // which differ in the GGX closure's side test (yarn_cycles_as_cycles4).
  int cycles_version = 5;

  // The colour a diffuse preview uses: the first yarn colour.
  Rgb base_color() const;
};

struct MaterialDesc {
  std::string name;
  std::string path;  // "materials.<name>"
  MaterialType type = MaterialType::Diffuse;
  DiffuseDesc diffuse;
  DielectricDesc dielectric;
  ThinDesc thin;
  KnitDesc knit;
};

struct ObjectDesc {
  std::string name;
  std::string path;       // "objects[i]"
  std::string mesh_file;  // resolved path
  Transform transform;
  int material = -1;      // index into SceneDesc::materials
};

struct SceneDesc {
  std::string file;  // as named by the user (used in messages)
  std::string dir;   // directory relative paths are resolved against
  FilmDesc film;
  CameraDesc camera;
  IntegratorDesc integrator;
  std::vector<LightDesc> lights;
  std::vector<MaterialDesc> materials;
  std::vector<ObjectDesc> objects;
  Warnings warnings;
  // The file's text (parse_scene; null for a scene made in code), so that an
  // error found building the scene names the field's line and column too
  // (JsonPositions, which reads it only then).
  std::shared_ptr<const std::string> text;

  bool has_knit() const {
    for (const auto& m : materials)
      if (m.type == MaterialType::Knit) return true;
    return false;
  }
};

// Reads and validates a scene file. Throws SceneError. explicit_yarns: the
// scene will be rendered with explicit yarns (as `integrator.explicit_yarns`
// in the file also says), so multi-scale knit materials need no class table
// and do not build one.
SceneDesc load_scene_file(const std::string& path, bool explicit_yarns = false);
// Same, from text (`file` names it in messages, `dir` resolves relative paths).
SceneDesc parse_scene(const std::string& text, const std::string& file, const std::string& dir,
                      bool explicit_yarns = false);

}  // namespace knit::render
