// Scene -> Cycles 4.2 standalone XML (see cycles_export.h and
// docs/renderer.md, "Export to Cycles").
//
// What the app's reader takes, in brief: <film>, <integrator> and <camera>
// set their nodes' sockets from attributes named as the sockets (snake case,
// e.g. max_bounce); <transform matrix="16 numbers, column by column"> sets
// the transform of what it holds; <state shader="NAME"
// interpolation="smooth"> chooses the shader and smoothing of the meshes
// and lights inside; <mesh P verts nverts [N] [UV] [tangent]> is one
// polygon mesh with per-vertex P and N and per-corner UV and tangent;
// <light> is a Cycles light (socket attributes, position and axes in tfm);
// <shader name> and <background> hold a graph of nodes (element name = node
// type, attribute name = socket) joined by <connect from="node socket"
// to="node socket">, an <osl_shader src="FILE.osl"> being a script node
// whose sockets are the shader's parameters.
#include "render/cycles_export.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <set>
#include <stdexcept>

#include "knit/osl_source.h"
#include "knit/ply_profile.h"
#include "render/integrator.h"
#include "render/json_strict.h"
#include "render/material_knit.h"
#include "render/mesh.h"

namespace knit::render {
namespace {

namespace fs = std::filesystem;

constexpr double kPiD = 3.14159265358979323846;

// ---- text ------------------------------------------------------------------

// Numbers as single-precision floats (what Cycles stores), in the fewest
// significant digits that the reader's atof turns back into the same float
// (at most 9): 0.6, not 0.600000024.
std::string num(double value) {
  const float v = static_cast<float>(value);
  if (v == 0) return "0";
  char buf[32];
  for (int digits = 6; digits <= 9; ++digits) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, double(v));
    if (std::strtof(buf, nullptr) == v) break;
  }
  return buf;
}

template <class C>
std::string rgb(const C& c) {
  return num(c.r) + " " + num(c.g) + " " + num(c.b);
}

std::string vec3(double x, double y, double z) { return num(x) + " " + num(y) + " " + num(z); }

std::string escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char ch : s) {
    switch (ch) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += ch;
    }
  }
  return out;
}

// An XML comment may not hold "--" (nor end in "-").
std::string comment_text(std::string s) {
  size_t at;
  while ((at = s.find("--")) != std::string::npos) s.replace(at, 2, "- -");
  if (!s.empty() && s.back() == '-') s += ' ';
  return s;
}

using Attrs = std::vector<std::pair<std::string, std::string>>;

struct Xml {
  std::string out;
  int depth = 0;

  void indent() { out.append(size_t(2 * depth), ' '); }
  void attrs(const Attrs& a) {
    for (const auto& [k, v] : a) out += " " + k + "=\"" + escape(v) + "\"";
  }
  void empty(const std::string& tag, const Attrs& a) {
    indent();
    out += "<" + tag;
    attrs(a);
    out += "/>\n";
  }
  void open(const std::string& tag, const Attrs& a = {}) {
    indent();
    out += "<" + tag;
    attrs(a);
    out += ">\n";
    ++depth;
  }
  void close(const std::string& tag) {
    --depth;
    indent();
    out += "</" + tag + ">\n";
  }
  void comment(const std::string& text) {
    indent();
    out += "<!-- " + comment_text(text) + " -->\n";
  }
  void connect(const std::string& from, const std::string& to) { empty("connect", {{"from", from}, {"to", to}}); }
};

// ---- geometry --------------------------------------------------------------

struct V3 {
  double x = 0, y = 0, z = 0;
};
V3 sub(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 crs(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 nrm(V3 a) {
  const double l = std::sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
  return {a.x / l, a.y / l, a.z / l};
}
V3 v3(Vec3 v) { return {v.x, v.y, v.z}; }

// The reader's <transform matrix>: 16 numbers that it reads as the rows of
// a 4 x 4 matrix and then transposes, i.e. the matrix column by column.
// `c0`..`c2` are the columns of the linear part, `t` the translation.
std::string column_major(V3 c0, V3 c1, V3 c2, V3 t) {
  return vec3(c0.x, c0.y, c0.z) + " 0  " + vec3(c1.x, c1.y, c1.z) + " 0  " + vec3(c2.x, c2.y, c2.z) + " 0  " +
         vec3(t.x, t.y, t.z) + " 1";
}

// A light's tfm socket: 12 numbers, the three rows of a 3 x 4 matrix
// (Cycles' Transform). Cycles reads the light's position from its last
// column, its axes from the first two and its direction as minus the third.
std::string light_tfm(V3 c0, V3 c1, V3 c2, V3 t) {
  return num(c0.x) + " " + num(c1.x) + " " + num(c2.x) + " " + num(t.x) + "  " + num(c0.y) + " " + num(c1.y) + " " +
         num(c2.y) + " " + num(t.y) + "  " + num(c0.z) + " " + num(c1.z) + " " + num(c2.z) + " " + num(t.z);
}

// Two unit vectors completing unit `w` to a right-handed frame.
void complete_frame(V3 w, V3& a, V3& b) {
  const V3 helper = std::fabs(w.x) < 0.9 ? V3{1, 0, 0} : V3{0, 1, 0};
  a = nrm(crs(helper, w));
  b = crs(w, a);
}

// ---- scene parts -----------------------------------------------------------

// XYZ Euler angles (Cycles' transform_euler: R = Rz(c) Ry(b) Rx(a)) of a
// rotation matrix r (row-major).
V3 euler_xyz(const double r[3][3]) {
  const double sb = std::clamp(-r[2][0], -1.0, 1.0);
  const double b = std::asin(sb);
  if (std::fabs(std::cos(b)) > 1e-9) return {std::atan2(r[2][1], r[2][2]), b, std::atan2(r[1][0], r[0][0])};
  return {0.0, b, std::atan2(-r[0][1], r[1][1])};  // gimbal lock: the x turn folded into z
}

// The environment texture's mapping rotation: the native lat-long lookup
// of a world direction d (docs/scene-format.md: y up, u = 0.5 towards -z,
// u = 0.75 towards +x, rotated by `rotation` degrees about +y) equals
// Cycles' equirectangular lookup (z up, u = 0.5 towards +x, u growing
// towards -y, the top row +z) of R d, with R = M Ry(-rotation), M taking
// +y to +z, -z to +x and +x to -y.
V3 environment_rotation(double rotation_deg) {
  const double a = rotation_deg * kPiD / 180.0, c = std::cos(a), s = std::sin(a);
  const double m[3][3] = {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}};
  const double ry[3][3] = {{c, 0, -s}, {0, 1, 0}, {s, 0, c}};  // Ry(-rotation)
  double r[3][3] = {};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k) r[i][j] += m[i][k] * ry[k][j];
  return euler_xyz(r);
}

// `target` as a path relative to the folder of `xml_file` (Cycles joins an
// environment texture's file name to that folder, even an absolute one).
std::string relative_to_xml(const std::string& target, const std::string& xml_file) {
  std::error_code ec;
  fs::path dir = fs::path(xml_file).parent_path();
  if (dir.empty()) dir = ".";
  const fs::path from = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  const fs::path to = fs::weakly_canonical(fs::absolute(target, ec), ec);
  fs::path rel = to.lexically_relative(from);
  if (rel.empty()) rel = to;
  return rel.generic_string();
}

// A mesh element: P (after the object's transform), verts, nverts (all 3),
// N (the renderer's vertex normals, for smooth shading), UV per corner when
// the mesh has UVs, and `corner_vectors` (one per triangle, given at its
// three corners) as the per-corner "tangent" attribute when not null.
void write_mesh(Xml& x, const TriangleMesh& m, bool with_uv, const std::vector<V3>* corner_vectors) {
  std::string p, n, verts, nverts, uv, tangent;
  p.reserve(m.positions.size() * 36);
  for (const Vec3& v : m.positions) p += vec3(v.x, v.y, v.z) + " ";
  for (const Vec3& v : m.normals) n += vec3(v.x, v.y, v.z) + " ";
  const size_t tris = m.num_triangles();
  for (size_t t = 0; t < tris; ++t) {
    verts += std::to_string(m.indices[3 * t]) + " " + std::to_string(m.indices[3 * t + 1]) + " " +
             std::to_string(m.indices[3 * t + 2]) + " ";
    nverts += "3 ";
    if (with_uv)
      for (int c = 0; c < 3; ++c) {
        const Vec2 u = m.uvs[m.indices[3 * t + size_t(c)]];
        uv += num(u.x) + " " + num(u.y) + " ";
      }
    if (corner_vectors) {
      const V3 k = (*corner_vectors)[t];
      const std::string one = vec3(k.x, k.y, k.z) + " ";
      tangent += one + one + one;
    }
  }
  auto trim = [](std::string& s) {
    if (!s.empty()) s.pop_back();
  };
  trim(p), trim(n), trim(verts), trim(nverts), trim(uv), trim(tangent);
  Attrs a = {{"P", p}, {"verts", verts}, {"nverts", nverts}, {"N", n}};
  if (with_uv) a.emplace_back("UV", uv);
  if (corner_vectors) a.emplace_back("tangent", tangent);
  x.empty("mesh", a);
}

// A knit material's script-node parameters (osl/knit_fabric.osl), from the
// material as the library validated it; SceneError for what the shader
// cannot be given.
Attrs knit_parameters(const MaterialDesc& md, const std::string& file, Warnings& warnings) {
  const knit::KnitMaterialParams& p = md.knit.model->params();
  const knit::YarnBsdfParams& b = p.bsdf;
  const int colours = b.num_colors();
  if (colours > knit::kOslPaletteSize)
    throw SceneError(file, md.path + ".yarn_colors",
                     std::to_string(colours) + " yarn colours; the Cycles shader's palette holds " +
                         std::to_string(knit::kOslPaletteSize) + " (colour indices 0 to " +
                         std::to_string(knit::kOslPaletteSize - 1) + ")");
  // The shader's transmission colours are the palette times one tint.
  float tint[3] = {-1, -1, -1};
  for (int i = 0; i < colours; ++i) {
    const float rc[3] = {b.reflect_colors[size_t(i)].r, b.reflect_colors[size_t(i)].g, b.reflect_colors[size_t(i)].b};
    const float tc[3] = {b.transmit_colors[size_t(i)].r, b.transmit_colors[size_t(i)].g,
                         b.transmit_colors[size_t(i)].b};
    for (int ch = 0; ch < 3; ++ch) {
      if (rc[ch] == 0) {
        if (tc[ch] == 0) continue;
        throw SceneError(file, md.path + ".transmit_colors[" + std::to_string(i) + "]",
                         "transmission colour (" + num(tc[0]) + ", " + num(tc[1]) + ", " + num(tc[2]) +
                             ") over a yarn colour with a zero channel: the Cycles shader takes the yarn colours "
                             "times one tint");
      }
      const float t = tc[ch] / rc[ch];
      if (tint[ch] < 0) {
        tint[ch] = t;
      } else if (std::fabs(t - tint[ch]) > 1e-5f * std::max(1.0f, tint[ch])) {
        throw SceneError(file, md.path + ".transmit_colors[" + std::to_string(i) + "]",
                         "transmission colour (" + num(tc[0]) + ", " + num(tc[1]) + ", " + num(tc[2]) +
                             ") is not the yarn colour times the tint the colours before it give (" +
                             num(tint[0] < 0 ? 1 : tint[0]) + ", " + num(tint[1] < 0 ? 1 : tint[1]) +
                             ", " + num(tint[2] < 0 ? 1 : tint[2]) +
                             "): the Cycles shader takes the yarn colours times one tint");
      }
    }
  }
  for (float& t : tint)
    if (t < 0) t = 1;
  if (p.ply_detail) {
    const float packed = knit::PlyParams::packed_radius(p.ply.ply_count);
    if (std::fabs(p.ply.ply_radius - packed) > 1e-6f * std::max(1.0f, packed))
      throw SceneError(file, md.path + ".ply.ply_radius",
                       "ply_radius " + num(p.ply.ply_radius) +
                           ": the Cycles shader takes the packed radius of its ply_count (" +
                           std::to_string(p.ply.ply_count) + " plies: " + num(packed) + ")");
  }
  const knit::CapmOptions defaults;
  if (p.capm_options.max_segment != defaults.max_segment)
    warnings.add(file + ": " + md.path + ".capm_options.max_segment = " + num(p.capm_options.max_segment) +
                 " is not exported: the Cycles shader marches segments of at most " +
                 num(defaults.max_segment) + " pattern units");
  if (p.capm_options.max_bend != defaults.max_bend)
    warnings.add(file + ": " + md.path + ".capm_options.max_bend = " + num(p.capm_options.max_bend) +
                 " is not exported: the Cycles shader bends segments by at most " + num(defaults.max_bend) +
                 " radians");
  if (md.knit.footprint_scale != 1.0f && p.mode == knit::KnitMode::MultiScale)
    warnings.add(file + ": " + md.path + ".footprint_scale = " + num(md.knit.footprint_scale) +
                 " is not exported: the Cycles shader's footprint is Cycles' ray cone");

  const double deg = 180.0 / kPiD;
  Attrs a = {{"UVScale", num(p.uv_scale)}, {"A", num(p.stitch.a)}, {"H", num(p.stitch.h)},
             {"D", num(p.stitch.d)},       {"R", num(p.stitch.r)}};
  for (int i = 0; i < colours; ++i) a.emplace_back("Yarn" + std::to_string(i), rgb(b.reflect_colors[size_t(i)]));
  a.emplace_back("TransmitTint", vec3(tint[0], tint[1], tint[2]));
  a.emplace_back("Roughness", num(b.roughness_x));
  a.emplace_back("RoughnessAcross", num(b.roughness_y));
  a.emplace_back("TransRoughness", num(b.trans_roughness_x));
  a.emplace_back("TransRoughnessAcross", num(b.trans_roughness_y));
  a.emplace_back("IOR", num(b.eta));
  a.emplace_back("BodyEnergy", num(b.body_energy));
  a.emplace_back("BodyReflect", num(b.body_reflect));
  a.emplace_back("OpticalDepth", num(b.optical_depth));
  a.emplace_back("PlyDetail", p.ply_detail ? "1" : "0");
  a.emplace_back("PlyCount", std::to_string(p.ply.ply_count));
  a.emplace_back("PlyTwist", num(double(p.ply.ply_twist) * deg));
  a.emplace_back("FiberCount", std::to_string(p.ply.fiber_count));
  a.emplace_back("FiberTwist", num(double(p.ply.fiber_twist) * deg));
  a.emplace_back("Mode", p.mode == knit::KnitMode::MultiScale ? "1" : "0");
  a.emplace_back("FootprintPoints", std::to_string(p.footprint_points));
  a.emplace_back("CAPM", p.capm ? "1" : "0");
  a.emplace_back("CapmSteps", std::to_string(p.capm_options.max_steps));
  return a;
}

// The world-space mesh of an object, loaded once per file.
struct LoadedObject {
  std::shared_ptr<const TriangleMesh> mesh;
  KnitMeshTables tables;  // knit materials only
};

}  // namespace

std::string cycles_shader_file_name(const std::string& xml_file, const std::string& material) {
  std::string safe = material;
  for (char& ch : safe)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.' || ch == '-')) ch = '_';
  return fs::path(xml_file).stem().string() + "_" + safe + ".osl";
}

CyclesExport export_cycles(const SceneDesc& desc, const CyclesExportOptions& options, Warnings& warnings) try {
  const std::string& file = desc.file;
  CyclesExport ex;
  ex.width = desc.film.width;
  ex.height = desc.film.height;
  ex.samples = desc.film.spp;
  if (desc.integrator.explicit_yarns)
    warnings.add(file + ": integrator.explicit_yarns is not exported: Cycles renders the knit materials with the "
                 "knit shader");

  // Objects first: their meshes, their checks, which materials they use.
  std::map<std::string, std::shared_ptr<const TriangleMesh>> cache;
  std::vector<LoadedObject> objects;
  std::vector<char> used(desc.materials.size(), 0), curved(desc.materials.size(), 0);
  for (const ObjectDesc& o : desc.objects) {
    std::shared_ptr<const TriangleMesh> base;
    auto it = cache.find(o.mesh_file);
    if (it != cache.end()) {
      base = it->second;
    } else {
      try {
        base = std::make_shared<const TriangleMesh>(load_mesh(o.mesh_file, &warnings));
      } catch (const std::exception& e) {
        throw SceneError(file, o.path + ".mesh", e.what());
      }
      cache.emplace(o.mesh_file, base);
    }
    const MaterialDesc& md = desc.materials[size_t(o.material)];
    used[size_t(o.material)] = 1;
    LoadedObject lo;
    lo.mesh = o.transform.is_identity() ? base : std::make_shared<const TriangleMesh>(transform_mesh(*base, o.transform));
    if (md.type == MaterialType::Knit) {
      // As the renderer checks a knit mesh (scene_build.cpp, material_knit.cpp).
      if (!base->has_uvs())
        throw SceneError(file, o.path + ".mesh",
                         o.mesh_file + " has no UV coordinates, which the knit material '" + md.name + "' needs");
      const float uv_scale = md.knit.model->params().uv_scale;
      lo.tables = knit_mesh_tables(*lo.mesh, uv_scale);
      if (lo.tables.with_uv_area == 0)
        throw SceneError(file, o.path + ".mesh",
                         lo.mesh->file + ": no triangle has a non-zero UV area and a size in the scene that single "
                                         "precision resolves (after the object's transform), which the knit "
                                         "material needs");
      for (size_t i = 0; i < lo.mesh->uvs.size(); ++i) {
        const Vec2 uv = lo.mesh->uvs[i];
        if (!(std::fabs(double(uv.x) * uv_scale) <= knit::kMaxPatternCoord &&
              std::fabs(double(uv.y) * uv_scale) <= knit::kMaxPatternCoord))
          throw SceneError(file, o.path + ".mesh",
                           lo.mesh->file + ": vertex " + std::to_string(i) + " has UV (" + fmt_num(uv.x) + ", " +
                               fmt_num(uv.y) + "), which " + md.path + " (uv_scale " + fmt_num(uv_scale) +
                               ") maps to pattern coordinates beyond +-" + fmt_num(knit::kMaxPatternCoord) +
                               ", where single-precision pattern space no longer resolves the yarns: lower "
                               "uv_scale or bring the UVs nearer 0");
      }
      if (!lo.tables.flat) {
        if (options.curvature) {
          curved[size_t(o.material)] = 1;
        } else {
          warnings.add(file + ": " + o.path + (o.name.empty() ? "" : " (" + o.name + ")") +
                       ": curved mesh under knit material '" + md.name +
                       "': its Curvature input is left unlinked, so the shader marches it as flat");
        }
      }
    }
    objects.push_back(std::move(lo));
  }

  Xml x;
  x.out = "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n";
  x.comment("Exported by knitshade export-cycles from " + file +
            " for the standalone Cycles 4.2 app with the OSL shading system. The app takes the image size and "
            "the sample count from its command line, not from this file: " + std::to_string(ex.width) + " x " +
            std::to_string(ex.height) + " pixels, " + std::to_string(ex.samples) + " samples.");
  x.open("cycles");

  // Film and integrator.
  x.empty("film", {{"exposure", num(std::exp2(double(desc.film.exposure)))},
                   {"filter_type", "box"},
                   {"filter_width", "1"}});
  const int depth = desc.integrator.max_depth;
  x.empty("integrator", {{"max_bounce", std::to_string(depth)},
                         {"max_diffuse_bounce", std::to_string(depth)},
                         {"max_glossy_bounce", std::to_string(depth)},
                         {"max_transmission_bounce", std::to_string(depth)},
                         {"transparent_max_bounce", std::to_string(PathIntegrator::kMaxPassThrough)},
                         {"min_bounce", std::to_string(desc.integrator.rr_depth)},
                         {"caustics_reflective", "true"},
                         {"caustics_refractive", "true"},
                         {"filter_glossy", "0"},
                         {"sample_clamp_direct", "0"},
                         {"sample_clamp_indirect", "0"},
                         {"light_sampling_threshold", "0"},
                         {"use_adaptive_sampling", "false"},
                         {"aa_samples", std::to_string(desc.film.spp)},
                         {"seed", std::to_string(desc.film.seed % 2147483648ull)}});

  // Camera: Cycles' camera looks along its +z with +y up in the image and +x
  // to the right; its field of view spans the image's shorter side.
  {
    const CameraDesc& c = desc.camera;
    const V3 pos = v3(c.position);
    const V3 fwd = nrm(sub(v3(c.look_at), pos));
    const V3 right = nrm(crs(fwd, v3(c.up)));
    const V3 up = crs(right, fwd);
    const double tan_half = std::tan(double(c.fov) * kPiD / 360.0);
    const double fov = desc.film.width >= desc.film.height
                           ? double(c.fov) * kPiD / 180.0
                           : 2.0 * std::atan(tan_half * double(desc.film.width) / double(desc.film.height));
    x.comment("camera: vertical field of view " + num(c.fov) + " degrees");
    x.open("transform", {{"matrix", column_major(right, up, fwd, pos)}});
    x.empty("camera", {{"width", std::to_string(desc.film.width)},
                       {"height", std::to_string(desc.film.height)},
                       {"fov", num(fov)},
                       {"farclip", "1e10"}});
    x.close("transform");
  }

  // Lights.
  for (size_t li = 0; li < desc.lights.size(); ++li) {
    const LightDesc& l = desc.lights[li];
    switch (l.type) {
      case LightType::EnvironmentUniform:
      case LightType::EnvironmentMap: {
        x.comment(l.path + ": environment");
        x.open("background");
        if (l.type == LightType::EnvironmentMap) {
          const V3 r = environment_rotation(l.rotation);
          x.empty("environment_texture", {{"name", "env"},
                                          {"filename", relative_to_xml(l.file, options.xml_file)},
                                          {"colorspace", "__builtin_raw"},
                                          {"projection", "equirectangular"},
                                          {"interpolation", "linear"},
                                          {"tex_mapping.type", "vector"},
                                          {"tex_mapping.rotation", vec3(r.x, r.y, r.z)}});
          x.empty("background", {{"name", "bg"}, {"color", "1 1 1"}, {"strength", num(l.strength)}});
          x.connect("env color", "bg color");
        } else {
          x.empty("background", {{"name", "bg"}, {"color", rgb(l.color)}, {"strength", num(l.strength)}});
        }
        x.connect("bg background", "output surface");
        x.close("background");
        // Importance sampling of the environment (Cycles turns it off for a
        // uniform one by itself).
        x.open("state", {{"shader", "default_background"}});
        x.empty("light", {{"name", l.path}, {"light_type", "background"}, {"use_mis", "true"}});
        x.close("state");
        break;
      }
      case LightType::Quad: {
        // An emissive mesh: the same radiance, seen by the camera, blocking
        // light, reached by BSDF rays (Cycles' area lights are rectangles).
        x.comment(l.path + ": quad light, an emissive mesh of radiance " + rgb(l.emission) +
                  (l.two_sided ? ", two-sided" : ", one-sided"));
        x.open("shader", {{"name", l.path}, {"emission_sampling_method", l.two_sided ? "front_back" : "front"}});
        x.empty("emission", {{"name", "emission"}, {"color", rgb(l.emission)}, {"strength", "1"}});
        if (!l.two_sided) {
          // Strength 1 - backfacing: black from behind.
          x.empty("geometry", {{"name", "geometry"}});
          x.empty("math", {{"name", "front"}, {"math_type", "subtract"}, {"value1", "1"}});
          x.connect("geometry backfacing", "front value2");
          x.connect("front value", "emission strength");
        }
        x.connect("emission emission", "output surface");
        x.close("shader");
        const V3 c0 = v3(l.corner), eu = v3(l.edge_u), ev = v3(l.edge_v);
        const V3 c1 = {c0.x + eu.x, c0.y + eu.y, c0.z + eu.z};
        const V3 c2 = {c1.x + ev.x, c1.y + ev.y, c1.z + ev.z};
        const V3 c3 = {c0.x + ev.x, c0.y + ev.y, c0.z + ev.z};
        x.open("state", {{"shader", l.path}, {"interpolation", "flat"}});
        x.empty("mesh", {{"P", vec3(c0.x, c0.y, c0.z) + " " + vec3(c1.x, c1.y, c1.z) + " " + vec3(c2.x, c2.y, c2.z) +
                                   " " + vec3(c3.x, c3.y, c3.z)},
                         {"verts", "0 1 2 0 2 3"},
                         {"nverts", "3 3"}});
        x.close("state");
        break;
      }
      case LightType::Point:
      case LightType::Directional: {
        // A unit emission shader; the light's strength carries the value.
        x.open("shader", {{"name", l.path}});
        x.empty("emission", {{"name", "emission"}, {"color", "1 1 1"}, {"strength", "1"}});
        x.connect("emission emission", "output surface");
        x.close("shader");
        x.open("state", {{"shader", l.path}});
        if (l.type == LightType::Point) {
          // Cycles' point light of size 0 has intensity strength / (4 pi).
          x.comment(l.path + ": point light of intensity " + rgb(l.intensity) + " W/sr: strength 4 pi I");
          const double s = 4.0 * kPiD;
          x.empty("light", {{"name", l.path},
                            {"light_type", "point"},
                            {"strength", vec3(s * l.intensity.r, s * l.intensity.g, s * l.intensity.b)},
                            {"size", "0"},
                            {"tfm", light_tfm({1, 0, 0}, {0, 1, 0}, {0, 0, 1}, v3(l.position))}});
        } else {
          // Cycles' sun of angle 0: irradiance = strength; it shines along
          // minus the tfm's third column, which is to_light then.
          x.comment(l.path + ": directional light of irradiance " + rgb(l.irradiance));
          const V3 w = nrm(v3(l.to_light));
          V3 a, b;
          complete_frame(w, a, b);
          x.empty("light", {{"name", l.path},
                            {"light_type", "distant"},
                            {"strength", rgb(l.irradiance)},
                            {"angle", "0"},
                            {"tfm", light_tfm(a, b, w, {0, 0, 0})}});
        }
        x.close("state");
        break;
      }
    }
  }

  // Materials used by objects.
  std::set<std::string> shader_files;
  for (size_t mi = 0; mi < desc.materials.size(); ++mi) {
    if (!used[mi]) continue;
    const MaterialDesc& md = desc.materials[mi];
    if (md.type == MaterialType::Knit)
      // The fabric emits nothing: never sample its triangles as lights
      // (Cycles decides from a scan of the shader's bytecode for
      // "emission" otherwise; an earlier shader's error colour was one).
      // Bump map correction off, as the add-on sets it: left on, Cycles
      // bends the microfacet closure's normal and softens diffuse light at
      // the yarn normals, which the native "as Cycles renders it" option
      // does not model (the swatch of tests/cycles/render_standalone.py
      // renders 10% brighter under a sun with it on).
      x.open("shader", {{"name", md.path}, {"emission_sampling_method", "none"},
                        {"use_bump_map_correction", "false"}});
    else
      x.open("shader", {{"name", md.path}});
    switch (md.type) {
      case MaterialType::Diffuse:
        x.empty("diffuse_bsdf", {{"name", "bsdf"}, {"color", rgb(md.diffuse.albedo)}});
        x.connect("bsdf BSDF", "output surface");
        break;
      case MaterialType::Dielectric: {
        const DielectricDesc& d = md.dielectric;
        if (d.eta == 1.0f) {
          // No interface: the light goes straight on, tinted.
          x.empty("transparent_bsdf", {{"name", "bsdf"}, {"color", rgb(d.tint)}});
        } else {
          // Principled, all transmission: reflection untinted, refraction
          // tinted by sqrt(base colour) per crossing, exact Fresnel, single-
          // scattering GGX with alpha = roughness^2 (0: smooth).
          const Rgb base = d.tint * d.tint;
          x.empty("principled_bsdf", {{"name", "bsdf"},
                                      {"distribution", "ggx"},
                                      {"base_color", rgb(base)},
                                      {"transmission_weight", "1"},
                                      {"metallic", "0"},
                                      {"roughness", num(d.roughness)},
                                      {"ior", num(d.eta)},
                                      {"specular_ior_level", "0.5"}});
        }
        x.connect("bsdf BSDF", "output surface");
        break;
      }
      case MaterialType::Thin:
        x.empty("transparent_bsdf", {{"name", "through"}, {"color", rgb(md.thin.transmittance)}});
        x.empty("diffuse_bsdf", {{"name", "bsdf"}, {"color", rgb(md.thin.albedo)}});
        x.empty("add_closure", {{"name", "sum"}});
        x.connect("through BSDF", "sum closure1");
        x.connect("bsdf BSDF", "sum closure2");
        x.connect("sum closure", "output surface");
        break;
      case MaterialType::Knit: {
        Attrs params = knit_parameters(md, file, warnings);
        CyclesShaderFile sf;
        sf.material = md.name;
        sf.file_name = cycles_shader_file_name(options.xml_file, md.name);
        if (!shader_files.insert(sf.file_name).second) {
          // Two names made the same by the file-name rule: number the later.
          const std::string stem = sf.file_name.substr(0, sf.file_name.size() - 4);
          for (int k = 2; !shader_files.insert(sf.file_name = stem + "_" + std::to_string(k) + ".osl").second; ++k) {
          }
        }
        try {
          sf.text = knit::osl_source(md.knit.model->surface().pattern());
        } catch (const std::invalid_argument& e) {
          throw SceneError(file, md.path + ".pattern", e.what());
        }
        x.empty("texture_coordinate", {{"name", "texcoord"}});
        if (curved[mi]) x.empty("attribute", {{"name", "curvature"}, {"attribute", "tangent"}});
        Attrs a = {{"name", "knit"}, {"src", sf.file_name}};
        a.insert(a.end(), params.begin(), params.end());
        x.empty("osl_shader", a);
        x.connect("texcoord UV", "knit UV");
        if (curved[mi]) x.connect("curvature Vector", "knit Curvature");
        x.connect("knit BSDF", "output surface");
        ex.shaders.push_back(std::move(sf));
        break;
      }
    }
    x.close("shader");
  }

  // Objects.
  for (size_t oi = 0; oi < desc.objects.size(); ++oi) {
    const ObjectDesc& o = desc.objects[oi];
    const LoadedObject& lo = objects[oi];
    const MaterialDesc& md = desc.materials[size_t(o.material)];
    std::vector<V3> kvec;
    const bool carry = md.type == MaterialType::Knit && options.curvature && !lo.tables.flat;
    if (carry) {
      kvec.reserve(lo.tables.triangles.size());
      for (const KnitTriangle& t : lo.tables.triangles) kvec.push_back({t.kx, t.ky, 0});
    }
    x.comment(o.path + (o.name.empty() ? "" : " (" + o.name + ")") + ": " + fs::path(o.mesh_file).filename().string() +
              ", " + std::to_string(lo.mesh->num_triangles()) + " triangles, material " + md.name +
              (carry ? "; the tangent attribute holds its curvature (kx, ky, 0) per triangle" : ""));
    x.open("state", {{"shader", md.path}, {"interpolation", "smooth"}});
    write_mesh(x, *lo.mesh, lo.mesh->has_uvs(), carry ? &kvec : nullptr);
    x.close("state");
    ++ex.meshes;
  }
  for (const LightDesc& l : desc.lights)
    if (l.type == LightType::Quad) ++ex.meshes;

  x.close("cycles");
  ex.xml = std::move(x.out);
  return ex;
} catch (const SceneError& e) {
  if (!desc.text) throw;
  throw JsonPositions(*desc.text).locate(e, desc.file);
}

}  // namespace knit::render
