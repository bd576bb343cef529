// Scene file parser: the "knit" material (docs/scene-format.md#knit). The
// knit model (knit::KnitMaterial) is built here, so every parameter is
// validated by the library at parse time; its messages are reported against
// the JSON field they concern.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <utility>

#include "knit/pattern.h"
#include "render/scene_parse_internal.h"

namespace knit::render {

// One stitch cell: 0-3 or K, P, F, B (any case); -1 if not a stitch.
static int stitch_code(char c) {
  switch (c) {
    case '0': case 'k': case 'K': return 0;
    case '1': case 'p': case 'P': return 1;
    case '2': case 'f': case 'F': return 2;
    case '3': case 'b': case 'B': return 3;
    default: return -1;
  }
}

static std::vector<int32_t> parse_pattern_row(const JsonNode& row) {
  std::vector<int32_t> cells;
  if (row.is_string()) {
    const std::string s = row.string();
    for (size_t i = 0; i < s.size(); ++i) {
      const char c = s[i];
      if (c == ' ' || c == '\t' || c == ',') continue;
      const int code = stitch_code(c);
      if (code < 0)
        row.fail(std::string("invalid stitch '") + c + "' at character " + std::to_string(i + 1) +
                 " (expected 0-3 or K, P, F, B)");
      cells.push_back(code);
    }
  } else if (row.is_array()) {
    for (const JsonNode& cell : row.elements()) {
      if (cell.is_string()) {
        const std::string s = cell.string();
        const int code = s.size() == 1 ? stitch_code(s[0]) : -1;
        if (code < 0) cell.fail("invalid stitch \"" + s + "\" (expected 0-3 or K, P, F, B)");
        cells.push_back(code);
      } else {
        cells.push_back(static_cast<int32_t>(cell.integer(0, 3)));
      }
    }
  } else {
    row.fail("a pattern row must be a string such as \"KKPP\" or an array of stitch codes, got " +
             row.type_name());
  }
  if (cells.empty()) row.fail("a pattern row must not be empty");
  if (cells.size() > static_cast<size_t>(Pattern::kMaxCols))
    row.fail("has " + std::to_string(cells.size()) + " cells, more than the maximum " +
             std::to_string(Pattern::kMaxCols));
  return cells;
}

namespace {

// The JSON field a knit-library validation message is about: "stitch
// parameter r ..." -> "r", "YarnBsdfParams.eta = ..." -> "bsdf.eta",
// "PlyParams.ply_count = ..." -> "ply.ply_count"; empty when unknown.
std::string field_of_library_error(const std::string& msg) {
  const std::string stitch = "stitch parameter ";
  if (msg.rfind(stitch, 0) == 0 && msg.size() > stitch.size()) return std::string(1, msg[stitch.size()]);
  auto name_after = [&](const std::string& prefix) {
    size_t e = prefix.size();
    while (e < msg.size() && (std::isalnum(static_cast<unsigned char>(msg[e])) || msg[e] == '_')) ++e;
    return msg.substr(prefix.size(), e - prefix.size());
  };
  if (msg.rfind("YarnBsdfParams.", 0) == 0) {
    const std::string f = name_after("YarnBsdfParams.");
    if (f == "reflect_colors") return "yarn_colors";
    if (f == "transmit_colors") return "transmit_colors";
    return "bsdf." + f;
  }
  if (msg.rfind("PlyParams.", 0) == 0) {
    const std::string f = name_after("PlyParams.");
    return f == "yarn_radius" ? "r" : "ply." + f;
  }
  if (msg.rfind("KnitMaterialParams.bsdf:", 0) == 0) return "yarn_colors";
  if (msg.rfind("KnitMaterialParams.", 0) == 0) {
    const std::string f = name_after("KnitMaterialParams.");
    if (f == "capm_options") return "capm_options";
    return f;
  }
  return "";
}

constexpr double kDegPerRad = 57.29577951308232;
// |ply_twist|, |fiber_twist| <= 1.4 rad (PlyParams::validate), in degrees.
constexpr double kMaxTwistDeg = 80.2;

}  // namespace

KnitDesc parse_knit_material(JsonObject& o, const std::string& dir, bool class_tables) {
  KnitDesc k;
  const std::string& file = o.node().file();
  JsonNode pat = o.at("pattern");
  Pattern pattern;
  if (pat.is_string()) {
    k.pattern_source = resolve_input_file(pat, dir);
    if (o.has("colors"))
      o.at("colors").fail("cannot be given with a pattern file (put a \"colors:\" block in the file)");
    try {
      pattern = Pattern::from_file(k.pattern_source);
    } catch (const std::exception& e) {
      pat.fail(e.what());  // "<pattern file>:<line>:<column>: <message>"
    }
  } else if (pat.is_array()) {
    k.pattern_source = "<inline>";
    auto rows = pat.elements(1, static_cast<size_t>(Pattern::kMaxRows));
    for (size_t i = 0; i < rows.size(); ++i) {
      std::vector<int32_t> cells = parse_pattern_row(rows[i]);
      if (i == 0) k.cols = static_cast<int>(cells.size());
      if (static_cast<int>(cells.size()) != k.cols)
        rows[i].fail("has " + std::to_string(cells.size()) + " cells but row 0 has " +
                     std::to_string(k.cols) + " (the pattern must be rectangular)");
      k.codes.insert(k.codes.end(), cells.begin(), cells.end());
    }
    k.rows = static_cast<int>(rows.size());
    if (auto cn = o.get("colors")) {
      auto crows = cn->elements(static_cast<size_t>(k.rows), static_cast<size_t>(k.rows));
      for (const JsonNode& cr : crows) {
        auto cells = cr.elements(static_cast<size_t>(k.cols), static_cast<size_t>(k.cols));
        for (const JsonNode& c : cells)
          k.colors.push_back(static_cast<int32_t>(c.integer(0, Pattern::kMaxColors - 1)));
      }
    }
    try {
      pattern = Pattern(k.rows, k.cols, k.codes, k.colors);
    } catch (const std::exception& e) {
      pat.fail(e.what());
    }
  } else {
    pat.fail("must be a pattern file path or an array of rows, got " + pat.type_name());
  }

  knit::KnitMaterialParams mp;
  // Two checks per parameter so the messages read "must be > 0, got -1".
  auto param = [&](JsonObject& obj, const char* key, const Range& sign, double max_abs, float def) {
    auto n = obj.get(key);
    if (!n) return def;
    const float v = n->number_f(sign);
    if (std::fabs(v) > max_abs) n->fail("must be at most " + fmt_num(max_abs) + " in magnitude, got " + fmt_num(v));
    return v;
  };
  mp.stitch.a = param(o, "a", Range::positive(), 1e3, mp.stitch.a);
  mp.stitch.h = param(o, "h", Range::positive(), 1e3, mp.stitch.h);
  mp.stitch.d = param(o, "d", Range::not_zero(), 1e3, mp.stitch.d);
  mp.stitch.r = param(o, "r", Range::positive(), 1e3, mp.stitch.r);
  if (!o.has("uv_scale")) o.fail("missing required key 'uv_scale'");
  mp.uv_scale = param(o, "uv_scale", Range::positive(), 1e6, 0.0f);

  // Yarn colours: YarnBsdfParams::reflect_colors (k_x^B) and transmit_colors (k_y^B).
  JsonNode yc = o.at("yarn_colors");
  std::vector<knit::Rgb> reflect, transmit;
  for (const JsonNode& c : yc.elements(1, static_cast<size_t>(Pattern::kMaxColors))) {
    const Rgb v = c.rgb(Range::closed(0, 1));
    reflect.push_back({v.r, v.g, v.b});
  }
  if (auto tc = o.get("transmit_colors")) {
    for (const JsonNode& c : tc->elements(reflect.size(), reflect.size())) {
      const Rgb v = c.rgb(Range::closed(0, 1));
      transmit.push_back({v.r, v.g, v.b});
    }
  } else {
    transmit = reflect;
  }
  if (pattern.num_colors() > static_cast<int>(reflect.size()))
    yc.fail(std::string(k.pattern_source == "<inline>" ? "the colors matrix" : "the pattern file") +
            " uses colour index " + std::to_string(pattern.num_colors() - 1) + " but only " +
            std::to_string(reflect.size()) + " yarn colours are given");
  mp.bsdf.reflect_colors = reflect;
  mp.bsdf.transmit_colors = transmit;

  // YarnBsdfParams, field for field.
  if (auto b = o.get("bsdf")) {
    JsonObject bo(*b);
    const Range unit_open = Range::left_open(0, 1), unit = Range::closed(0, 1);
    mp.bsdf.roughness_x = bo.number("roughness_x", unit_open, mp.bsdf.roughness_x);
    mp.bsdf.roughness_y = bo.number("roughness_y", unit_open, mp.bsdf.roughness_y);
    mp.bsdf.trans_roughness_x = bo.number("trans_roughness_x", unit_open, mp.bsdf.trans_roughness_x);
    mp.bsdf.trans_roughness_y = bo.number("trans_roughness_y", unit_open, mp.bsdf.trans_roughness_y);
    mp.bsdf.eta = bo.number("eta", Range::closed(1, 3), mp.bsdf.eta);
    mp.bsdf.body_energy = bo.number("body_energy", unit, mp.bsdf.body_energy);
    mp.bsdf.body_reflect = bo.number("body_reflect", unit, mp.bsdf.body_reflect);
    mp.bsdf.optical_depth = bo.number("optical_depth", Range::closed(0, 50), mp.bsdf.optical_depth);
    bo.finish();
  }
  // PlyParams, field for field (angles in degrees); yarn_radius is r.
  if (auto p = o.get("ply")) {
    JsonObject po(*p);
    mp.ply_detail = po.boolean("enabled", true);
    mp.ply.ply_count = static_cast<int>(po.integer("ply_count", 1, 16, mp.ply.ply_count));
    mp.ply.ply_radius = po.number("ply_radius", Range::open(0, 1), knit::PlyParams::packed_radius(mp.ply.ply_count));
    const Range twist = Range::magnitude(kMaxTwistDeg);
    if (po.has("ply_twist")) mp.ply.ply_twist = static_cast<float>(po.number("ply_twist", twist) / kDegPerRad);
    mp.ply.fiber_count = static_cast<int>(po.integer("fiber_count", 0, 10000, mp.ply.fiber_count));
    if (po.has("fiber_twist")) mp.ply.fiber_twist = static_cast<float>(po.number("fiber_twist", twist) / kDegPerRad);
    po.finish();
  }
  mp.ply.yarn_radius = mp.stitch.r;

  // "cycles": as the OSL shader renders it in Cycles (docs/cycles.md). What
  // Cycles cannot do is left out, so asking for it is an error naming the key.
  const bool cycles = o.choice("bsdf_model", {"exact", "cycles"}, "exact") == "cycles";
  mp.bsdf_model = cycles ? knit::KnitBsdfModel::Cycles : knit::KnitBsdfModel::Exact;
  if (cycles) {
    const std::pair<const char*, const char*> not_in_cycles[] = {
        {"footprint_table", "the shader has no class table"},
        {"table_bsdf", "the shader has no class table"},
        {"near_field_below_cell", "the shader aggregates every multi-scale footprint"},
        {"self_shadowing", "Cycles shades the yarn at the base hit, where light and bounces leave"}};
    for (const auto& [key, why] : not_in_cycles)
      if (auto n = o.get(key))
        if (n->boolean())
          n->fail(std::string("true is not what bsdf_model \"cycles\" renders (") + why +
                  "): leave it out or set it false");
  }
  if (auto v = o.get("cycles_version")) {
    if (!cycles) v->fail("only bsdf_model \"cycles\" follows a Cycles version: leave it out or set bsdf_model");
    k.cycles_version = static_cast<int>(o.integer("cycles_version", 4, 5, k.cycles_version));
  }
  const std::string mode = o.choice("mode", {"near_field", "multi_scale"}, "near_field");
  mp.mode = mode == "near_field" ? knit::KnitMode::NearField : knit::KnitMode::MultiScale;
  mp.capm = o.boolean("capm", mp.capm);
  mp.footprint_points = static_cast<int>(o.integer("footprint_points", 1, KNIT_MS_MAX_POINTS, mp.footprint_points));
  mp.footprint_table = o.boolean("footprint_table", mp.footprint_table);
  mp.table_min_cells = float(o.number("table_min_cells", Range::closed(FootprintTable::kMinSubBox, 1), mp.table_min_cells));
  mp.table_bsdf = o.boolean("table_bsdf", mp.table_bsdf);
  mp.table_fold = o.boolean("table_fold", mp.table_fold);
  // (read either way, so that the key is still checked)
  if (!class_tables) mp.footprint_table = false;
  mp.self_shadowing = o.boolean("self_shadowing", mp.self_shadowing);
  mp.near_field_below_cell = o.boolean("near_field_below_cell", mp.near_field_below_cell);
  if (auto c = o.get("capm_options")) {
    JsonObject co(*c);
    mp.capm_options.max_steps = static_cast<int>(co.integer("max_steps", 1, 4096, mp.capm_options.max_steps));
    mp.capm_options.max_segment =
        co.number("max_segment", Range::left_open(0, kMaxCapmSegment), mp.capm_options.max_segment);
    mp.capm_options.max_bend = co.number("max_bend", Range::left_open(0, 3.14159265f), mp.capm_options.max_bend);
    co.finish();
  }
  // (the shader's frames: the hit's, turned with the mesh's curvature)
  if (cycles) k.frames = KnitFrames::Curvature;
  if (auto f = o.get("frames")) {
    const std::string v = f->string();
    if (v == "exact") {
      k.frames = KnitFrames::Exact;
    } else if (v == "curvature") {
      k.frames = KnitFrames::Curvature;
    } else {
      k.frames = KnitFrames::Baked;
      k.frames_file = resolve_input_file(*f, dir);
    }
  }
  k.explicit_samples =
      static_cast<int>(o.integer("explicit_samples", 4, KnitDesc::kMaxExplicitSamples, k.explicit_samples));
  k.footprint_scale = o.number("footprint_scale", Range::left_open(0, 16), k.footprint_scale);
  // (a shader does not know where its sample lies in the pixel)
  k.footprint_centre = o.choice("footprint_centre", {"pixel", "sample"}, cycles ? "sample" : "pixel") == "pixel"
                           ? FootprintCentre::Pixel
                           : FootprintCentre::Sample;

  try {
    k.model = std::make_shared<const knit::KnitMaterial>(std::move(pattern), mp);
  } catch (const std::invalid_argument& e) {
    const std::string field = field_of_library_error(e.what());
    throw SceneError(file, field.empty() ? o.path() : json_child_path(o.path(), field), e.what());
  }
  return k;
}

Rgb KnitDesc::base_color() const {
  if (!model) return Rgb(0.5f);
  const knit::Rgb c = model->params().bsdf.reflect_colors[0];
  return {c.r, c.g, c.b};
}

}  // namespace knit::render
