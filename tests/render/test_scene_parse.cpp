// Scene file parsing and validation: every error class, each message naming
// the file and the JSON path of the field at fault.
#include <gtest/gtest.h>

#include <algorithm>
#include <regex>

#include <nlohmann/json.hpp>

#include "render/scene.h"
#include "render/scene_desc.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

using nlohmann::json;

// The message of the SceneError `fn` throws, with the line and column that
// follow the scene file's name taken out ("scene.json:12:7: film.width: ..."
// -> "scene.json: film.width: ..."): the tests below check the words, and
// SceneParse.ErrorsNameTheLineAndColumnOfTheField checks the positions.
template <class Fn>
std::string scene_error_of(Fn&& fn) {
  return std::regex_replace(test::scene_error_of(fn), std::regex("scene\\.json:[0-9]+:[0-9]+: "), "scene.json: ");
}

json base_scene() {
  return json::parse(R"({
    "film": {"width": 8, "height": 6, "spp": 2, "seed": 3},
    "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"type": "point", "position": [0, 4, 0], "intensity": [10, 10, 10]}],
    "materials": {
      "red": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]},
      "wool": {"type": "knit", "pattern": ["KKPP", "PPKK"], "uv_scale": 10,
               "yarn_colors": [[0.8, 0.2, 0.2]]}
    },
    "objects": [{"mesh": "MESH", "material": "red"}]
  })");
}

std::string with_mesh(json j, const std::string& mesh) {
  for (auto& o : j["objects"]) o["mesh"] = mesh;
  return j.dump(2);
}

SceneDesc parse(const json& j) { return parse_scene(with_mesh(j, test::mesh("quad.obj")), "scene.json", "."); }

std::string error_of(const json& j) {
  return scene_error_of([&] { parse(j); });
}

// (the message as it is, positions included)
std::string error_of_text(const std::string& text) {
  return test::scene_error_of([&] { parse_scene(text, "scene.json", "."); });
}

TEST(SceneParse, ValidSceneParses) {
  const SceneDesc d = parse(base_scene());
  EXPECT_EQ(d.film.width, 8);
  EXPECT_EQ(d.film.height, 6);
  EXPECT_EQ(d.film.spp, 2);
  EXPECT_EQ(d.film.seed, 3u);
  ASSERT_EQ(d.materials.size(), 2u);
  ASSERT_EQ(d.objects.size(), 1u);
  EXPECT_EQ(d.materials[static_cast<size_t>(d.objects[0].material)].name, "red");
  const MaterialDesc& wool = d.materials[1];
  ASSERT_EQ(wool.type, MaterialType::Knit);
  EXPECT_EQ(wool.knit.rows, 2);
  EXPECT_EQ(wool.knit.cols, 4);
  EXPECT_EQ(wool.knit.codes, (std::vector<int32_t>{0, 0, 1, 1, 1, 1, 0, 0}));
  EXPECT_FLOAT_EQ(wool.knit.model->params().uv_scale, 10.0f);
}

TEST(SceneParse, SyntaxErrorGivesLineAndColumn) {
  const std::string msg = error_of_text("{\n  \"film\": {\"width\": 8,\n  }\n}");
  EXPECT_NE(msg.find("scene.json:3:3:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("syntax error"), std::string::npos) << msg;
}

TEST(SceneParse, NumberOverflowIsLocated) {
  const std::string msg = error_of_text("{\n \"film\": {\"width\": 1e999}}");
  EXPECT_NE(msg.find("scene.json:2:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("overflow"), std::string::npos) << msg;
}

TEST(SceneParse, NanLiteralIsASyntaxError) {
  const std::string msg = error_of_text("{\"film\": {\"width\": NaN}}");
  EXPECT_NE(msg.find("scene.json:1:"), std::string::npos) << msg;
}

TEST(SceneParse, DuplicateKeyNamesTheObject) {
  // (at the second key)
  const std::string msg = error_of_text(R"({"film": {"width": 8, "width": 9}})");
  EXPECT_NE(msg.find("scene.json:1:23: film: duplicate key 'width'"), std::string::npos) << msg;
  const std::string top = error_of_text("{\"film\": {},\n \"film\": {}}");
  EXPECT_NE(top.find("scene.json:2:2: (top level): duplicate key 'film'"), std::string::npos) << top;
  // the text ending at the second key (found by fuzz_scene, 2026-12-04)
  const std::string end = error_of_text("{\n \"n\": 1,\n \"n\"");
  EXPECT_NE(end.find("scene.json:3:2: (top level): duplicate key 'n'"), std::string::npos) << end;
}

// The line and column of `needle`'s first occurrence at or after `from` in
// `text`, counted here (1-based, in bytes), as "scene.json:L:C: ".
std::string position_of(const std::string& text, const std::string& needle, size_t from = 0) {
  const size_t at = text.find(needle, from);
  EXPECT_NE(at, std::string::npos) << needle;
  if (at == std::string::npos) return "?";
  const size_t line_start = text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1;
  const long line = 1 + std::count(text.begin(), text.begin() + long(at), '\n');
  return "scene.json:" + std::to_string(line) + ":" + std::to_string(at - line_start + 1) + ": ";
}

TEST(SceneParse, ErrorsNameTheLineAndColumnOfTheField) {
  // Each error names the field's line and column: a member at its key, an
  // array element at its value, a missing key at the object that lacks it,
  // and an error found while building the scene (a mesh without UVs) at the
  // object's field.
  const std::string dir = test::test_dir();
  test::write_file(dir, "no_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string good = R"({
  "film": {"width": 8, "height": 6, "spp": 2},
  "camera": {"position": [0, 1, 5], "look_at": [0, 0, 0], "fov": 40},
  "lights": [
    {"type": "point", "position": [0, 4, 0], "intensity": [10, 10, 10]},
    {"type": "point", "position": [0, 4, 0],
     "intensity": [10, 10, 10]}
  ],
  "materials": {
    "we\u0069rd \"name\"": {"type": "diffuse", "albedo": [0.8, 0.1, 0.1]},
    "wool": {"type": "knit", "pattern": ["KP"], "uv_scale": 10,
             "yarn_colors": [[0.8, 0.2, 0.2]]}
  },
  "objects": [{"mesh": "QUAD", "material": "wool"},
              {"mesh": "no_uv.obj", "material": "wool"}]
})";
  const auto err = [&](const std::string& text) {
    return test::scene_error_of([&] { parse_scene(text, "scene.json", dir); });
  };
  const auto changed = [&](const std::string& from, const std::string& to) {
    std::string t = good;
    t.replace(t.find("QUAD"), 4, test::mesh("quad.obj"));
    const size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return at == std::string::npos ? t : t.replace(at, from.size(), to);
  };
  // a value out of range: at its key
  std::string t = changed("\"fov\": 40", "\"fov\": 400");
  EXPECT_NE(err(t).find(position_of(t, "\"fov\"") + "camera.fov: must be in (0, 180), got 400"), std::string::npos)
      << err(t);
  // an unknown key of the second element of an array, on a line of its own
  t = changed("\"intensity\": [10, 10, 10]}\n  ]", "\"intensity\": [10, 10, 10],\n     \"intensty\": 1}\n  ]");
  EXPECT_NE(err(t).find(position_of(t, "\"intensty\"") + "lights[1].intensty: unknown key"), std::string::npos)
      << err(t);
  // an element of an array of arrays: at its value
  t = changed("[[0.8, 0.2, 0.2]]", "[[0.8, 2, 0.2]]");
  EXPECT_NE(err(t).find(position_of(t, "2, 0.2]]") + "materials.wool.yarn_colors[0][1]: must be in [0, 1], got 2"),
            std::string::npos)
      << err(t);
  // a missing key: at the object without it
  t = changed("\"width\": 8, ", "");
  EXPECT_NE(err(t).find(position_of(t, "\"film\"") + "film: missing required key 'width'"), std::string::npos)
      << err(t);
  // a key with escapes, decoded as the reader decodes it
  t = changed("\"albedo\": [0.8, 0.1, 0.1]", "\"albedo\": [0.8, 0.1, -0.1]");
  EXPECT_NE(err(t).find(position_of(t, "-0.1") + "materials.weird \"name\".albedo[2]: must be in [0, 1], got -0.1"),
            std::string::npos)
      << err(t);
  // the top level: its members at their keys, the whole at its first value
  t = changed("  \"film\"", "  \"extra\": true,\n  \"film\"");
  EXPECT_NE(err(t).find(position_of(t, "\"extra\"") + "extra: unknown key"), std::string::npos) << err(t);
  t = "\n\n  " + changed("  \"camera\": {\"position\": [0, 1, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n", "");
  EXPECT_NE(err(t).find("scene.json:3:3: (top level): missing required key 'camera'"), std::string::npos) << err(t);
  // after a byte-order mark, which the parser skips (the column counts its bytes)
  t = "\xEF\xBB\xBF" + changed("\"width\": 8", "\"width\": 0");
  EXPECT_NE(err(t).find(position_of(t, "\"width\"") + "film.width: must be in [1, 16384], got 0"), std::string::npos)
      << err(t);

  // Found while building the scene: at the object's "mesh".
  t = changed("", "");
  const SceneDesc d = parse_scene(t, "scene.json", dir);
  Warnings w;
  const std::string built = test::scene_error_of([&] { Scene s(d, BuildOptions{}, w); });
  EXPECT_NE(built.find(position_of(t, "\"mesh\": \"no_uv.obj\"") + "objects[1].mesh: " + dir +
                       "/no_uv.obj has no UV coordinates"),
            std::string::npos)
      << built;
}

TEST(SceneParse, UnknownKeysAreErrors) {
  json j = base_scene();
  j["film"]["widht"] = 8;
  EXPECT_NE(error_of(j).find("scene.json: film.widht: unknown key 'widht'"), std::string::npos) << error_of(j);
  j = base_scene();
  j["materials"]["wool"]["colour"] = 1;
  EXPECT_NE(error_of(j).find("scene.json: materials.wool.colour: unknown key"), std::string::npos);
  j = base_scene();
  j["lights"][0]["color"] = {1, 1, 1};
  EXPECT_NE(error_of(j).find("scene.json: lights[0].color: unknown key"), std::string::npos);
  j = base_scene();
  j["extra"] = true;
  EXPECT_NE(error_of(j).find("scene.json: extra: unknown key"), std::string::npos);
}

TEST(SceneParse, MissingRequiredKeys) {
  json j = base_scene();
  j.erase("camera");
  EXPECT_NE(error_of(j).find("scene.json: (top level): missing required key 'camera'"), std::string::npos)
      << error_of(j);
  j = base_scene();
  j["film"].erase("width");
  EXPECT_NE(error_of(j).find("scene.json: film: missing required key 'width'"), std::string::npos);
  j = base_scene();
  j["materials"]["wool"].erase("uv_scale");
  EXPECT_NE(error_of(j).find("scene.json: materials.wool: missing required key 'uv_scale'"), std::string::npos);
}

TEST(SceneParse, WrongTypes) {
  json j = base_scene();
  j["film"]["width"] = "eight";
  EXPECT_NE(error_of(j).find("scene.json: film.width: must be an integer, got string"), std::string::npos);
  j = base_scene();
  j["film"]["spp"] = 1.5;
  EXPECT_NE(error_of(j).find("scene.json: film.spp: must be an integer, got 1.5"), std::string::npos);
  j = base_scene();
  j["camera"]["position"] = {0, 1};
  EXPECT_NE(error_of(j).find("scene.json: camera.position: must have 3 elements, got 2"), std::string::npos);
  j = base_scene();
  j["camera"]["position"][1] = nullptr;
  EXPECT_NE(error_of(j).find("scene.json: camera.position[1]: must be a number, got null"), std::string::npos);
}

TEST(SceneParse, FilmAndCameraRanges) {
  json j = base_scene();
  j["film"]["width"] = 0;
  EXPECT_NE(error_of(j).find("film.width: must be in [1, 16384], got 0"), std::string::npos) << error_of(j);
  j = base_scene();
  j["camera"]["fov"] = 180;
  EXPECT_NE(error_of(j).find("scene.json: camera.fov: must be in (0, 180), got 180"), std::string::npos);
  j = base_scene();
  j["camera"]["look_at"] = {0, 1, 5};
  EXPECT_NE(error_of(j).find("camera.look_at: must differ from camera.position"), std::string::npos);
  j = base_scene();
  j["camera"]["position"] = {0, 0, 5};
  j["camera"]["up"] = {0, 0, -2};
  EXPECT_NE(error_of(j).find("camera.up: up must not be parallel"), std::string::npos) << error_of(j);
  j = base_scene();
  j["camera"]["up"] = {0, 0, 0};
  EXPECT_NE(error_of(j).find("camera.up: must be a non-zero direction"), std::string::npos);
  j = base_scene();
  j["camera"]["position"][0] = 1e300;  // finite in double, not in float
  EXPECT_NE(error_of(j).find("camera.position[0]: must be in [-1000000, 1000000], got 1e+300"), std::string::npos)
      << error_of(j);
  j = base_scene();
  j["integrator"] = {{"strategy", "path"}};
  EXPECT_NE(error_of(j).find("integrator.strategy: must be one of \"mis\", \"nee\", \"bsdf\", got \"path\""),
            std::string::npos);
}

TEST(SceneParse, MaterialRanges) {
  json j = base_scene();
  j["materials"]["red"]["albedo"][0] = 1.5;
  EXPECT_NE(error_of(j).find("scene.json: materials.red.albedo[0]: must be in [0, 1], got 1.5"), std::string::npos);
  j = base_scene();
  j["materials"]["glass"] = {{"type", "dielectric"}, {"eta", 0}};
  EXPECT_NE(error_of(j).find("materials.glass.eta: must be in (0, 4], got 0"), std::string::npos) << error_of(j);
  j = base_scene();
  j["materials"]["sheet"] = {{"type", "thin"}, {"transmittance", {0.6, 0.6, 0.6}}, {"albedo", {0.5, 0.5, 0.5}}};
  EXPECT_NE(error_of(j).find("materials.sheet.albedo: albedo + transmittance must be <= 1"), std::string::npos);
  j = base_scene();
  j["materials"]["x"] = {{"type", "metal"}};
  EXPECT_NE(error_of(j).find("materials.x.type: must be one of"), std::string::npos);
}

// A rough dielectric is parsed without a warning (the rough lobes are
// rendered); a roughness too small for single precision to resolve is an
// error, not a silent smooth interface.
TEST(SceneParse, RoughDielectricRoughnessRange) {
  json j = base_scene();
  j["materials"]["glass"] = {{"type", "dielectric"}, {"eta", 1.5}, {"roughness", 0.2}};
  const SceneDesc d = parse(j);
  EXPECT_TRUE(d.warnings.messages.empty());
  j["materials"]["glass"]["roughness"] = 0.005;
  EXPECT_NE(error_of(j).find("scene.json: materials.glass.roughness: must be 0 (smooth) or in [0.01, 1] (GGX alpha = "
                             "roughness^2), got 0.005"),
            std::string::npos)
      << error_of(j);
  j["materials"]["glass"]["roughness"] = 1.5;
  EXPECT_NE(error_of(j).find("materials.glass.roughness: must be in [0, 1], got 1.5"), std::string::npos)
      << error_of(j);
}

TEST(SceneParse, KnitParameterRanges) {
  auto knit_error = [](const char* key, json value) {
    json j = base_scene();
    j["materials"]["wool"][key] = value;
    return error_of(j);
  };
  EXPECT_NE(knit_error("a", -1).find("scene.json: materials.wool.a: must be > 0, got -1"), std::string::npos)
      << knit_error("a", -1);
  EXPECT_NE(knit_error("h", 0).find("materials.wool.h: must be > 0, got 0"), std::string::npos);
  EXPECT_NE(knit_error("d", 0).find("materials.wool.d: must be != 0, got 0"), std::string::npos);
  EXPECT_NE(knit_error("r", -0.5).find("materials.wool.r: must be > 0, got -0.5"), std::string::npos);
  EXPECT_NE(knit_error("r", 5000).find("materials.wool.r: must be at most 1000"), std::string::npos);
  EXPECT_NE(knit_error("uv_scale", 0).find("materials.wool.uv_scale: must be > 0, got 0"), std::string::npos);
  EXPECT_NE(knit_error("yarn_colors", json::array({{0.5, 1.2, 0.5}})).find("materials.wool.yarn_colors[0][1]: must be in [0, 1], got 1.2"),
            std::string::npos);
  EXPECT_NE(knit_error("yarn_colors", json::array()).find("materials.wool.yarn_colors: must have 1 to 256 elements, got 0"),
            std::string::npos);
  EXPECT_NE(knit_error("mode", "far").find("materials.wool.mode: must be one of \"near_field\", \"multi_scale\""),
            std::string::npos);
  EXPECT_NE(knit_error("footprint_centre", "middle").find("materials.wool.footprint_centre: must be one of \"pixel\", \"sample\""),
            std::string::npos)
      << knit_error("footprint_centre", "middle");
  EXPECT_NE(knit_error("capm", 1).find("materials.wool.capm: must be true or false, got number"), std::string::npos);
  EXPECT_NE(knit_error("self_shadowing", "yes").find("materials.wool.self_shadowing: must be true or false"),
            std::string::npos);
  EXPECT_NE(knit_error("footprint_points", 0).find("materials.wool.footprint_points: must be in [1, 64], got 0"),
            std::string::npos);
  EXPECT_NE(knit_error("table_min_cells", 0.2).find("materials.wool.table_min_cells: must be in [0.25, 1], got 0.2"),
            std::string::npos)
      << knit_error("table_min_cells", 0.2);
  EXPECT_NE(knit_error("table_min_cells", "half").find("materials.wool.table_min_cells"), std::string::npos);
  EXPECT_NE(knit_error("bsdf", {{"roughness_x", 0}}).find("materials.wool.bsdf.roughness_x: must be in (0, 1], got 0"),
            std::string::npos);
  EXPECT_NE(knit_error("bsdf", {{"eta", 0.5}}).find("materials.wool.bsdf.eta: must be in [1, 3], got 0.5"),
            std::string::npos);
  EXPECT_NE(knit_error("bsdf", {{"body_energy", -0.1}}).find("materials.wool.bsdf.body_energy: must be in [0, 1], got -0.1"),
            std::string::npos);
  EXPECT_NE(knit_error("bsdf", {{"roughness", 0.3}}).find("materials.wool.bsdf.roughness: unknown key"), std::string::npos);
  EXPECT_NE(knit_error("ply", {{"ply_count", 3}, {"ply_twist", 90}}).find("materials.wool.ply.ply_twist: must be in [-80.2, 80.2], got 90"),
            std::string::npos);
  EXPECT_NE(knit_error("ply", {{"ply_count", 0}}).find("materials.wool.ply.ply_count: must be in [1, 16], got 0"),
            std::string::npos);
  EXPECT_NE(knit_error("ply", {{"shade", 1}}).find("materials.wool.ply.shade: unknown key"), std::string::npos);
  EXPECT_NE(knit_error("transmit_colors", json::array({{0.5, 0.5, 0.5}, {0.1, 0.1, 0.1}})).find(
                "materials.wool.transmit_colors: must have 1 elements, got 2"),
            std::string::npos);
  EXPECT_NE(knit_error("explicit_samples", 2).find("materials.wool.explicit_samples: must be in [4, 1024], got 2"),
            std::string::npos);
  EXPECT_NE(knit_error("explicit_samples", 1025).find("materials.wool.explicit_samples: must be in [4, 1024], got 1025"),
            std::string::npos);
  EXPECT_NE(knit_error("frames", "nope.exr").find("materials.wool.frames: file not found"), std::string::npos);
  // The library's own checks, reported against the field: r beyond the curve's clearance.
  const std::string clearance = knit_error("r", 0.9);
  EXPECT_NE(clearance.find("scene.json: materials.wool.r: stitch parameter r = 0.9 makes yarn tubes pass through each other"),
            std::string::npos)
      << clearance;
}

TEST(SceneParse, KnitMaterialMapsOntoTheModel) {
  json j = base_scene();
  j["materials"]["wool"] = json::parse(R"({"type": "knit", "pattern": ["KP"], "uv_scale": 20, "a": 1.4, "h": 3.5,
      "d": -0.8, "r": 0.5, "yarn_colors": [[0.5, 0.4, 0.3]], "transmit_colors": [[0.2, 0.3, 0.4]],
      "bsdf": {"roughness_x": 0.2, "roughness_y": 0.5, "trans_roughness_x": 0.35, "trans_roughness_y": 0.65,
               "eta": 1.4, "body_energy": 0.9, "body_reflect": 0.3, "optical_depth": 2},
      "ply": {"ply_count": 2, "ply_twist": 45, "fiber_count": 20, "fiber_twist": -10},
      "mode": "multi_scale", "capm": false, "footprint_points": 8, "frames": "curvature", "explicit_samples": 12,
      "footprint_table": false, "table_min_cells": 0.75, "table_bsdf": false, "table_fold": false, "self_shadowing": false,
      "near_field_below_cell": false, "footprint_scale": 0.5, "footprint_centre": "sample"})");
  const SceneDesc d = parse(j);
  const KnitDesc& k = d.materials[1].knit;
  ASSERT_TRUE(k.model);
  const knit::KnitMaterialParams& p = k.model->params();
  EXPECT_FLOAT_EQ(p.stitch.a, 1.4f);
  EXPECT_FLOAT_EQ(p.stitch.h, 3.5f);
  EXPECT_FLOAT_EQ(p.stitch.d, -0.8f);
  EXPECT_FLOAT_EQ(p.stitch.r, 0.5f);
  EXPECT_FLOAT_EQ(p.uv_scale, 20.0f);
  EXPECT_FLOAT_EQ(p.bsdf.reflect_colors[0].g, 0.4f);
  EXPECT_FLOAT_EQ(p.bsdf.transmit_colors[0].b, 0.4f);
  EXPECT_FLOAT_EQ(p.bsdf.roughness_x, 0.2f);
  EXPECT_FLOAT_EQ(p.bsdf.roughness_y, 0.5f);
  EXPECT_FLOAT_EQ(p.bsdf.trans_roughness_x, 0.35f);
  EXPECT_FLOAT_EQ(p.bsdf.trans_roughness_y, 0.65f);
  EXPECT_FLOAT_EQ(p.bsdf.eta, 1.4f);
  EXPECT_FLOAT_EQ(p.bsdf.body_energy, 0.9f);
  EXPECT_FLOAT_EQ(p.bsdf.body_reflect, 0.3f);
  EXPECT_FLOAT_EQ(p.bsdf.optical_depth, 2.0f);
  EXPECT_EQ(p.ply.ply_count, 2);
  EXPECT_FLOAT_EQ(p.ply.ply_radius, knit::PlyParams::packed_radius(2));
  EXPECT_NEAR(p.ply.ply_twist, 0.785398f, 1e-5f);
  EXPECT_EQ(p.ply.fiber_count, 20);
  EXPECT_NEAR(p.ply.fiber_twist, -0.174533f, 1e-5f);
  EXPECT_FLOAT_EQ(p.ply.yarn_radius, 0.5f);
  EXPECT_EQ(p.mode, knit::KnitMode::MultiScale);
  EXPECT_FALSE(p.capm);
  EXPECT_EQ(p.footprint_points, 8);
  EXPECT_FALSE(p.footprint_table);
  EXPECT_FLOAT_EQ(p.table_min_cells, 0.75f);
  EXPECT_FALSE(p.table_bsdf);
  EXPECT_FALSE(p.table_fold);
  EXPECT_FALSE(p.self_shadowing);
  EXPECT_FALSE(p.near_field_below_cell);
  EXPECT_EQ(k.frames, KnitFrames::Curvature);
  EXPECT_EQ(k.explicit_samples, 12);
  EXPECT_FLOAT_EQ(k.footprint_scale, 0.5f);
  EXPECT_EQ(k.footprint_centre, FootprintCentre::Sample);
  EXPECT_EQ(k.model->surface().pattern().cols(), 2);
}

// "bsdf_model": "cycles" renders as the OSL shader does in Cycles
// (docs/cycles.md): the model's Cycles option, the shader's frames and
// footprints by default, and an error for what Cycles cannot do.
TEST(SceneParse, KnitBsdfModel) {
  json j = base_scene();
  const SceneDesc exact = parse(j);
  EXPECT_EQ(exact.materials[1].knit.model->params().bsdf_model, knit::KnitBsdfModel::Exact);
  EXPECT_EQ(exact.materials[1].knit.frames, KnitFrames::Exact);
  EXPECT_EQ(exact.materials[1].knit.footprint_centre, FootprintCentre::Pixel);
  j["materials"]["wool"]["bsdf_model"] = "cycles";
  j["materials"]["wool"]["mode"] = "multi_scale";
  const SceneDesc d = parse(j);
  const KnitDesc& k = d.materials[1].knit;
  const knit::KnitMaterialParams& p = k.model->params();
  EXPECT_EQ(p.bsdf_model, knit::KnitBsdfModel::Cycles);
  EXPECT_FALSE(p.self_shadowing);
  EXPECT_FALSE(p.footprint_table);
  EXPECT_FALSE(p.table_bsdf);
  EXPECT_FALSE(p.near_field_below_cell);
  EXPECT_EQ(k.model->footprint_table(), nullptr);
  EXPECT_EQ(k.frames, KnitFrames::Curvature);
  EXPECT_EQ(k.footprint_centre, FootprintCentre::Sample);
  // Still overridable, and false is what cycles renders anyway.
  j["materials"]["wool"]["frames"] = "exact";
  j["materials"]["wool"]["footprint_centre"] = "pixel";
  j["materials"]["wool"]["self_shadowing"] = false;
  const SceneDesc o = parse(j);
  EXPECT_EQ(o.materials[1].knit.frames, KnitFrames::Exact);
  EXPECT_EQ(o.materials[1].knit.footprint_centre, FootprintCentre::Pixel);
  for (const char* key : {"self_shadowing", "footprint_table", "table_bsdf", "near_field_below_cell"}) {
    json b = j;
    b["materials"]["wool"][key] = true;
    const std::string e = error_of(b);
    EXPECT_NE(e.find(std::string("scene.json: materials.wool.") + key +
                     ": true is not what bsdf_model \"cycles\" renders ("),
              std::string::npos)
        << e;
  }
  // The Cycles whose rules it follows: 5 unless told 4; nothing else, and
  // only with bsdf_model "cycles".
  EXPECT_EQ(k.cycles_version, 5);
  j["materials"]["wool"]["cycles_version"] = 4;
  EXPECT_EQ(parse(j).materials[1].knit.cycles_version, 4);
  for (int v : {3, 6}) {
    json b = j;
    b["materials"]["wool"]["cycles_version"] = v;
    const std::string e = error_of(b);
    EXPECT_NE(e.find("scene.json: materials.wool.cycles_version"), std::string::npos) << e;
  }
  {
    json b = j;
    b["materials"]["wool"].erase("bsdf_model");
    const std::string e = error_of(b);
    EXPECT_NE(e.find("materials.wool.cycles_version: only bsdf_model \"cycles\" follows a Cycles version"),
              std::string::npos)
        << e;
  }
  j["materials"]["wool"].erase("cycles_version");
  j["materials"]["wool"]["bsdf_model"] = "osl";
  EXPECT_NE(error_of(j).find("materials.wool.bsdf_model: must be one of \"exact\", \"cycles\""), std::string::npos)
      << error_of(j);
}

TEST(SceneParse, KnitPatternFileErrorsNameTheFileLineAndColumn) {
  const std::string dir = test::test_dir();
  test::write_file(dir, "bad.knit", "KKPP\nKPXP\n");
  test::write_file(dir, "two.knit", "KP\nPK\ncolors:\n0 1\n1 0\n");
  json j = base_scene();
  j["materials"]["wool"]["pattern"] = "bad.knit";
  std::string msg = scene_error_of([&] { parse_scene(with_mesh(j, test::mesh("quad.obj")), "scene.json", dir); });
  EXPECT_NE(msg.find("scene.json: materials.wool.pattern: " + dir + "/bad.knit:2:3:"), std::string::npos) << msg;
  j["materials"]["wool"]["pattern"] = "two.knit";
  msg = scene_error_of([&] { parse_scene(with_mesh(j, test::mesh("quad.obj")), "scene.json", dir); });
  EXPECT_NE(msg.find("scene.json: materials.wool.yarn_colors: the pattern file uses colour index 1 but only 1 yarn colours are given"),
            std::string::npos)
      << msg;
}

TEST(SceneParse, KnitPatterns) {
  auto pattern_error = [](json pattern, json colors = nullptr) {
    json j = base_scene();
    j["materials"]["wool"]["pattern"] = pattern;
    if (!colors.is_null()) j["materials"]["wool"]["colors"] = colors;
    return error_of(j);
  };
  EXPECT_NE(pattern_error({"KKPP", "KKP"}).find("materials.wool.pattern[1]: has 3 cells but row 0 has 4"),
            std::string::npos);
  EXPECT_NE(pattern_error({"KXPP"}).find("materials.wool.pattern[0]: invalid stitch 'X' at character 2"),
            std::string::npos);
  EXPECT_NE(pattern_error(json::array({json::array({0, 4})})).find("materials.wool.pattern[0][1]: must be in [0, 3], got 4"),
            std::string::npos);
  EXPECT_NE(pattern_error(json::array()).find("materials.wool.pattern: must have 1 to 4096 elements, got 0"),
            std::string::npos);
  EXPECT_NE(pattern_error({"KP"}, json::array({json::array({0, 1, 0})})).find("materials.wool.colors[0]: must have 2 elements, got 3"),
            std::string::npos);
  EXPECT_NE(pattern_error({"KP"}, json::array({json::array({0, 1})})).find(
                "materials.wool.yarn_colors: the colors matrix uses colour index 1 but only 1 yarn colours are given"),
            std::string::npos);
  EXPECT_NE(pattern_error("no-such-pattern.txt").find("materials.wool.pattern: file not found"), std::string::npos);
  EXPECT_NE(pattern_error(42).find("materials.wool.pattern: must be a pattern file path or an array of rows"),
            std::string::npos);

  // Letters, digits, mixed separators and integer rows all read the same.
  json j = base_scene();
  j["materials"]["wool"]["pattern"] = {"k p, f b", "0123"};
  j["materials"]["wool"]["colors"] = json::array({json::array({0, 1, 1, 0}), json::array({1, 1, 0, 0})});
  j["materials"]["wool"]["yarn_colors"] = json::array({{0.1, 0.2, 0.3}, {0.9, 0.8, 0.7}});
  const SceneDesc d = parse(j);
  EXPECT_EQ(d.materials[1].knit.codes, (std::vector<int32_t>{0, 1, 2, 3, 0, 1, 2, 3}));
  EXPECT_EQ(d.materials[1].knit.colors, (std::vector<int32_t>{0, 1, 1, 0, 1, 1, 0, 0}));
}

TEST(SceneParse, ObjectsAndTransforms) {
  json j = base_scene();
  j["objects"][0]["material"] = "blue";
  EXPECT_NE(error_of(j).find("scene.json: objects[0].material: unknown material 'blue' (defined: red, wool)"),
            std::string::npos)
      << error_of(j);
  j = base_scene();
  j["objects"][0]["transform"] = {{"scale", 0}};
  EXPECT_NE(error_of(j).find("objects[0].transform.scale: must be in [-1000000, 1000000] and != 0, got 0"),
            std::string::npos)
      << error_of(j);
  j = base_scene();
  j["objects"][0]["transform"] = {{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1}}};
  EXPECT_NE(error_of(j).find("objects[0].transform.matrix: must be affine"), std::string::npos);
  j = base_scene();
  j["objects"][0]["transform"] = {{"matrix", {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 0, 0}, {0, 0, 0, 1}}}};
  EXPECT_NE(error_of(j).find("objects[0].transform.matrix: is singular"), std::string::npos);
  j = base_scene();
  j["objects"][0]["transform"] = {{"matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}}, {"translate", {1, 2, 3}}};
  EXPECT_NE(error_of(j).find("objects[0].transform.translate: cannot be combined with transform.matrix"),
            std::string::npos);

  // translate * rotate_z * rotate_y * rotate_x * scale
  j = base_scene();
  j["objects"][0]["transform"] = {{"translate", {1, 2, 3}}, {"rotate", {0, 90, 0}}, {"scale", 2}};
  const SceneDesc d = parse(j);
  const Vec3 p = d.objects[0].transform.point({1, 0, 0});
  EXPECT_NEAR(p.x, 1.0f, 1e-5f);
  EXPECT_NEAR(p.y, 2.0f, 1e-5f);
  EXPECT_NEAR(p.z, 1.0f, 1e-5f);  // (2, 0, 0) rotated +90 deg about y is (0, 0, -2)
}

TEST(SceneParse, MissingFilesAreNamed) {
  const std::string dir = test::test_dir();
  json j = base_scene();
  const std::string msg = scene_error_of([&] { parse_scene(with_mesh(j, "meshes/nope.obj"), "scene.json", dir); });
  EXPECT_NE(msg.find("scene.json: objects[0].mesh: file not found: " + dir + "/meshes/nope.obj"), std::string::npos)
      << msg;
  j["lights"] = json::array({{{"type", "environment"}, {"file", "sky.exr"}}});
  const std::string msg2 = scene_error_of([&] { parse_scene(with_mesh(j, test::mesh("quad.obj")), "scene.json", dir); });
  EXPECT_NE(msg2.find("scene.json: lights[0].file: file not found"), std::string::npos) << msg2;
  const std::string msg3 = scene_error_of([&] { load_scene_file(dir + "/missing.json"); });
  EXPECT_NE(msg3.find("missing.json: scene file not found"), std::string::npos) << msg3;
}

TEST(SceneParse, Lights) {
  auto light_error = [](json light) {
    json j = base_scene();
    j["lights"] = json::array({light});
    return error_of(j);
  };
  EXPECT_NE(light_error({{"type", "quad"}, {"corner", {0, 0, 0}}, {"edge_u", {1, 0, 0}}, {"edge_v", {2, 0, 0}},
                         {"emission", {1, 1, 1}}})
                .find("lights[0].edge_v: edge_u and edge_v must be non-zero and not parallel"),
            std::string::npos);
  EXPECT_NE(light_error({{"type", "directional"}, {"to_light", {0, 1, 0}}, {"irradiance", {1, 1, 1}}, {"angular_radius", 0.5}})
                .find("lights[0].angular_radius: must be 0"),
            std::string::npos);
  EXPECT_NE(light_error({{"type", "point"}, {"position", {0, 1, 0}}, {"intensity", {1, -1, 1}}})
                .find("lights[0].intensity[1]: must be in [0, 1e+09], got -1"),
            std::string::npos);
  EXPECT_NE(light_error({{"type", "environment"}}).find("lights[0]: an environment light needs exactly one of"),
            std::string::npos);
  json j = base_scene();
  j["lights"] = json::array({{{"type", "environment"}, {"color", {1, 1, 1}}}, {{"type", "environment"}, {"color", {1, 1, 1}}}});
  EXPECT_NE(error_of(j).find("scene.json: lights[1]: only one environment light is allowed"), std::string::npos);
  j = base_scene();
  j["lights"] = json::array();
  const SceneDesc d = parse(j);
  ASSERT_EQ(d.warnings.messages.size(), 1u);
  EXPECT_NE(d.warnings.messages[0].find("no lights"), std::string::npos);
}

// Errors found while building the scene (meshes, materials) also name the field.
TEST(SceneBuild, KnitNeedsUvs) {
  const std::string dir = test::test_dir();
  test::write_file(dir, "no_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  json j = base_scene();
  j["objects"][0]["material"] = "wool";
  const SceneDesc with_uv = parse_scene(with_mesh(j, test::mesh("quad.obj")), "scene.json", dir);
  Warnings w;
  EXPECT_NO_THROW(Scene(with_uv, BuildOptions{}, w));
  BuildOptions preview;
  preview.knit_preview_diffuse = true;
  EXPECT_NO_THROW(Scene(with_uv, preview, w));
  BuildOptions tubes;
  tubes.explicit_yarns = true;
  EXPECT_NO_THROW(Scene(with_uv, tubes, w));

  const SceneDesc no_uv = parse_scene(with_mesh(j, "no_uv.obj"), "scene.json", dir);
  for (const BuildOptions& o : {BuildOptions{}, preview, tubes}) {
    const std::string msg = scene_error_of([&] { Scene s(no_uv, o, w); });
    EXPECT_NE(msg.find("scene.json: objects[0].mesh: " + dir + "/no_uv.obj has no UV coordinates, which the knit material 'wool' needs"),
              std::string::npos)
        << msg;
  }
  // UVs without area (every vertex at the same UV) are an error too, for the model and the tubes.
  test::write_file(dir, "flat_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\n");
  const SceneDesc flat_uv = parse_scene(with_mesh(j, "flat_uv.obj"), "scene.json", dir);
  for (const BuildOptions& o : {BuildOptions{}, tubes}) {
    const std::string msg = scene_error_of([&] { Scene s(flat_uv, o, w); });
    EXPECT_NE(msg.find("scene.json: objects[0].mesh:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("no triangle has a non-zero UV area"), std::string::npos) << msg;
  }
  // Good UVs on a mesh scaled below what single precision resolves: its
  // triangles have no size in the scene, and the error says so.
  {
    json tiny = j;
    tiny["objects"][0]["transform"] = {{"scale", 1e-38}};
    const SceneDesc d = parse_scene(with_mesh(tiny, test::mesh("quad.obj")), "scene.json", dir);
    const std::string msg = scene_error_of([&] { Scene s(d, BuildOptions{}, w); });
    EXPECT_NE(msg.find("scene.json: objects[0].mesh:"), std::string::npos) << msg;
    EXPECT_NE(msg.find("a size in the scene that single precision resolves (after the object's transform)"),
              std::string::npos)
        << msg;
  }
  // UVs that the material maps beyond single-precision pattern space.
  test::write_file(dir, "far_uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1e9 1\nf 1/1 2/2 3/3\n");
  {
    const std::string msg =
        scene_error_of([&] { Scene s(parse_scene(with_mesh(j, "far_uv.obj"), "scene.json", dir), BuildOptions{}, w); });
    EXPECT_NE(msg.find("scene.json: objects[0].mesh: " + dir + "/far_uv.obj: vertex 2 has UV (1e+09, 1)"),
              std::string::npos)
        << msg;
    EXPECT_NE(msg.find("beyond +-32768"), std::string::npos) << msg;
  }
  // A diffuse material is fine without UVs.
  j["objects"][0]["material"] = "red";
  EXPECT_NO_THROW(Scene(parse_scene(with_mesh(j, "no_uv.obj"), "scene.json", dir), BuildOptions{}, w));
}

TEST(SceneBuild, ExplicitYarnsThatWouldNotFitNameTheObject) {
  json j = base_scene();
  j["objects"][0]["material"] = "wool";
  j["materials"]["wool"]["uv_scale"] = 1e5;  // 16000 x 22000 stitches on the unit quad
  const SceneDesc d = parse(j);
  Warnings w;
  BuildOptions tubes;
  tubes.explicit_yarns = true;
  const std::string msg = scene_error_of([&] { Scene s(d, tubes, w); });
  EXPECT_NE(msg.find("scene.json: objects[0].mesh: explicit yarns of materials.wool:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("curve points"), std::string::npos) << msg;
}

TEST(SceneBuild, BadMeshesNameFileAndIndex) {
  const std::string dir = test::test_dir();
  test::write_file(dir, "nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
  test::write_file(dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nf 1 2 3\nf 2 3 4\n");
  test::write_file(dir, "empty.obj", "v 0 0 0\nv 1 0 0\n");
  json j = base_scene();
  Warnings w;
  BuildOptions preview;
  preview.knit_preview_diffuse = true;
  auto build_error = [&](const std::string& mesh) {
    return scene_error_of([&] { Scene s(parse_scene(with_mesh(j, mesh), "scene.json", dir), preview, w); });
  };
  EXPECT_NE(build_error("nan.obj").find("scene.json: objects[0].mesh: " + dir + "/nan.obj: line 3: 'nan' in a 'v' line is not a number"),
            std::string::npos)
      << build_error("nan.obj");
  EXPECT_NE(build_error("flat.obj").find("flat.obj: all 2 triangles are degenerate (first: triangle 0)"), std::string::npos)
      << build_error("flat.obj");
  EXPECT_NE(build_error("empty.obj").find("scene.json: objects[0].mesh: " + dir + "/empty.obj:"), std::string::npos)
      << build_error("empty.obj");
}

}  // namespace
}  // namespace knit::render
