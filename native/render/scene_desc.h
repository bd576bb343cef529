// The parsed, validated scene description (docs/scene-format.md). Plain data:
// everything here has been range-checked at the boundary, and every element
// remembers its JSON path so later stages (mesh loading, scene building) can
// still name the field at fault.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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

struct DielectricDesc {
  float eta = 1.5f;
  float roughness = 0;  // validated; rendered as 0 (smooth) until the rough lobes land
  Rgb tint{1.0f};       // applied to refraction
};

// A straight-through sheet: passes light unchanged in direction with
// `transmittance`, reflects diffusely with `albedo` (albedo + transmittance <= 1).
struct ThinDesc {
  Rgb transmittance{0.5f};
  Rgb albedo{0.0f};
};

enum class KnitMode { NearField, MultiScale };

struct KnitDesc {
  // Pattern: either a file (pattern_file set) or an inline matrix.
  std::string pattern_file;  // resolved path; empty for an inline pattern
  int rows = 0, cols = 0;    // inline patterns only
  std::vector<int32_t> codes;   // inline: row-major, 0 knit, 1 purl, 2 front, 3 back
  std::vector<int32_t> colors;  // inline: row-major colour indices, empty if none given
  // Stitch curve (paper Eq. 2) and tube radius, pattern-space units.
  float a = 1.5f, h = 4.0f, d = 1.0f, r = 0.75f;
  float uv_scale = 1.0f;         // pattern units per UV unit
  std::vector<Rgb> yarn_colors;  // one per colour index
  // Yarn appearance (near-field model, paper Sec. 3.2).
  float specular_roughness = 0.3f;
  float specular_eta = 1.46f;
  float body_energy = 0.8f;       // B
  float body_reflect = 0.5f;      // r: reflected share of the body energy
  int ply_count = 3;
  float ply_twist = 30;           // degrees
  float ply_shadowing = 0.5f;     // [0, 1]
  float fiber_twist = 15;         // degrees
  float fiber_shadowing = 0.3f;   // [0, 1]
  KnitMode mode = KnitMode::MultiScale;
  bool capm = true;
  int footprint_samples = 16;

  // The colour a diffuse preview uses: yarn_colors[0].
  Rgb base_color() const { return yarn_colors.empty() ? Rgb(0.5f) : yarn_colors[0]; }
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

  bool has_knit() const {
    for (const auto& m : materials)
      if (m.type == MaterialType::Knit) return true;
    return false;
  }
};

// Reads and validates a scene file. Throws SceneError.
SceneDesc load_scene_file(const std::string& path);
// Same, from text (`file` names it in messages, `dir` resolves relative paths).
SceneDesc parse_scene(const std::string& text, const std::string& file, const std::string& dir);

}  // namespace knit::render
