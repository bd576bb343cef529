// Scene file parser: the top level, film, camera, integrator, objects and
// transforms. Lights, materials and the knit material have their own files.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "render/scene_parse_internal.h"

namespace knit::render {

namespace fs = std::filesystem;

std::string resolve_input_file(const JsonNode& node, const std::string& dir) {
  const std::string rel = node.string();
  if (rel.empty()) node.fail("must be a file path, got an empty string");
  fs::path p(rel);
  if (p.is_relative()) p = fs::path(dir) / p;
  std::error_code ec;
  const auto st = fs::status(p, ec);
  if (ec || !fs::exists(st)) node.fail("file not found: " + p.string());
  if (!fs::is_regular_file(st)) node.fail("not a regular file: " + p.string());
  std::ifstream probe(p, std::ios::binary);
  if (!probe) node.fail("cannot open file: " + p.string());
  return p.lexically_normal().string();
}

static FilmDesc parse_film(JsonObject o) {
  FilmDesc f;
  f.width = static_cast<int>(o.integer("width", 1, 16384));
  f.height = static_cast<int>(o.integer("height", 1, 16384));
  f.spp = static_cast<int>(o.integer("spp", 1, 1 << 20, f.spp));
  f.seed = static_cast<uint64_t>(o.integer("seed", 0, INT64_MAX, 0));
  f.exposure = o.number("exposure", Range::closed(-30, 30), 0.0f);
  o.finish();
  return f;
}

static CameraDesc parse_camera(JsonObject o) {
  CameraDesc c;
  o.choice("type", {"pinhole"}, "pinhole");
  c.position = o.vec3("position", Range::magnitude(kMaxCoord));
  c.look_at = o.vec3("look_at", Range::magnitude(kMaxCoord));
  auto up = o.get("up");
  if (up) c.up = up->direction();
  c.fov = o.number("fov", Range::open(0, 180), c.fov);
  const Vec3 view = c.look_at - c.position;
  if (!(length(view) > 1e-6f)) o.at("look_at").fail("must differ from camera.position");
  if (length(cross(normalize(view), c.up)) < 1e-4f)
    (up ? *up : o.node()).fail("up must not be parallel to the viewing direction");
  o.finish();
  return c;
}

static IntegratorDesc parse_integrator(JsonObject o) {
  IntegratorDesc d;
  d.max_depth = static_cast<int>(o.integer("max_depth", 1, 1024, d.max_depth));
  d.rr_depth = static_cast<int>(o.integer("rr_depth", 1, 1024, d.rr_depth));
  const std::string s = o.choice("strategy", {"mis", "nee", "bsdf"}, "mis");
  d.strategy = s == "nee" ? Strategy::Nee : (s == "bsdf" ? Strategy::Bsdf : Strategy::Mis);
  d.explicit_yarns = o.boolean("explicit_yarns", false);
  o.finish();
  return d;
}

static Transform parse_transform(JsonObject o) {
  if (o.has("matrix")) {
    JsonNode mn = o.at("matrix");
    std::array<double, 16> m{};
    auto rows = mn.elements();
    if (rows.size() == 4 && rows[0].is_array()) {
      for (size_t i = 0; i < 4; ++i) {
        auto cols = rows[i].elements(4, 4);
        for (size_t j = 0; j < 4; ++j) m[i * 4 + j] = cols[j].number(Range::magnitude(kMaxCoord));
      }
    } else {
      auto e = mn.elements(16, 16);
      for (size_t i = 0; i < 16; ++i) m[i] = e[i].number(Range::magnitude(kMaxCoord));
    }
    for (const char* k : {"translate", "rotate", "scale"})
      if (o.has(k)) o.at(k).fail("cannot be combined with transform.matrix");
    Transform t(m);
    if (!t.is_affine()) mn.fail("must be affine: the last row must be [0, 0, 0, 1]");
    if (!(std::fabs(t.determinant3()) > 1e-12)) mn.fail("is singular (determinant 0)");
    o.finish();
    return t;
  }
  Vec3 tr = o.vec3("translate", Range::magnitude(kMaxCoord), Vec3(0, 0, 0));
  Vec3 rot = o.vec3("rotate", Range::magnitude(1e5), Vec3(0, 0, 0));
  Vec3 sc(1, 1, 1);
  if (auto s = o.get("scale")) {
    Range r = Range::magnitude(kMaxCoord);
    r.nonzero = true;
    if (s->is_number()) {
      const float v = s->number_f(r);
      sc = {v, v, v};
    } else {
      sc = s->vec3(r);
    }
  }
  o.finish();
  // Scale first, then rotate about x, y, z (in that order), then translate.
  return Transform::translate(tr) * Transform::rotate_z(rot.z) * Transform::rotate_y(rot.y) *
         Transform::rotate_x(rot.x) * Transform::scale(sc);
}

static ObjectDesc parse_object(JsonNode node, size_t index, const std::string& dir,
                               const std::vector<MaterialDesc>& materials) {
  JsonObject o(node);
  ObjectDesc d;
  d.path = node.path();
  d.name = o.has("name") ? o.string("name") : "object" + std::to_string(index);
  d.mesh_file = resolve_input_file(o.at("mesh"), dir);
  JsonNode mat = o.at("material");
  const std::string mname = mat.string();
  for (size_t i = 0; i < materials.size(); ++i)
    if (materials[i].name == mname) d.material = static_cast<int>(i);
  if (d.material < 0) {
    std::string list;
    for (const auto& m : materials) list += (list.empty() ? "" : ", ") + m.name;
    mat.fail("unknown material '" + mname + "'" +
             (list.empty() ? std::string(" (no materials are defined)") : " (defined: " + list + ")"));
  }
  if (auto t = o.get("transform")) d.transform = parse_transform(JsonObject(*t));
  o.finish();
  return d;
}

static SceneDesc parse_scene_tree(const nlohmann::json& root, const std::string& file, const std::string& dir,
                                  bool explicit_yarns) {
  SceneDesc s;
  s.file = file;
  s.dir = dir;
  JsonObject top(JsonNode(root, "", file));
  if (auto v = top.get("version")) v->integer(1, 1);
  s.film = parse_film(JsonObject(top.at("film")));
  s.camera = parse_camera(JsonObject(top.at("camera")));
  if (auto n = top.get("integrator")) s.integrator = parse_integrator(JsonObject(*n));
  if (auto n = top.get("materials")) {
    JsonObject mats(*n);
    for (const std::string& name : mats.keys()) {
      if (name.empty()) n->fail("material names must not be empty");
      s.materials.push_back(
          parse_material(mats.at(name), name, dir, !(explicit_yarns || s.integrator.explicit_yarns)));
    }
    mats.finish();
  }
  if (auto n = top.get("lights")) {
    bool have_env = false;
    for (const JsonNode& l : n->elements()) {
      s.lights.push_back(parse_light(l, dir));
      const LightType t = s.lights.back().type;
      if (t == LightType::EnvironmentMap || t == LightType::EnvironmentUniform) {
        if (have_env) l.fail("only one environment light is allowed");
        have_env = true;
      }
    }
  }
  if (auto n = top.get("objects")) {
    auto elems = n->elements();
    for (size_t i = 0; i < elems.size(); ++i)
      s.objects.push_back(parse_object(elems[i], i, dir, s.materials));
  }
  top.finish();
  if (s.lights.empty()) s.warnings.add(file + ": the scene has no lights; the image will be black");
  return s;
}

SceneDesc parse_scene(const std::string& text, const std::string& file, const std::string& dir,
                      bool explicit_yarns) {
  const nlohmann::json root = parse_json_strict(text, file);
  try {
    SceneDesc s = parse_scene_tree(root, file, dir, explicit_yarns);
    s.text = std::make_shared<const std::string>(text);
    return s;
  } catch (const SceneError& e) {
    throw JsonPositions(text).locate(e, file);
  }
}

SceneDesc load_scene_file(const std::string& path, bool explicit_yarns) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw SceneError(path, "", "scene file not found");
  if (!fs::is_regular_file(path, ec)) throw SceneError(path, "", "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path, "", "cannot open scene file");
  std::ostringstream ss;
  ss << in.rdbuf();
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  return parse_scene(ss.str(), path, dir.string(), explicit_yarns);
}

}  // namespace knit::render
