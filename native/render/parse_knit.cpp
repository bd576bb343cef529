// Scene file parser: the "knit" material (docs/scene-format.md#knit).
// Rendering it is phase 2; parsing and validation are complete now.
#include <algorithm>
#include <cmath>

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

KnitDesc parse_knit_material(JsonObject& o, const std::string& dir) {
  KnitDesc k;
  JsonNode pat = o.at("pattern");
  if (pat.is_string()) {
    k.pattern_file = resolve_input_file(pat, dir);
    if (o.has("colors"))
      o.at("colors").fail("cannot be given with a pattern file (put a \"colors:\" block in the file)");
  } else if (pat.is_array()) {
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
  } else {
    pat.fail("must be a pattern file path or an array of rows, got " + pat.type_name());
  }

  // Two checks per parameter so the messages read "must be > 0, got -1".
  auto param = [&](const char* key, const Range& sign, double max_abs, float def) {
    auto n = o.get(key);
    if (!n) return def;
    const float v = n->number_f(sign);
    if (std::fabs(v) > max_abs) n->fail("must be at most " + fmt_num(max_abs) + " in magnitude, got " + fmt_num(v));
    return v;
  };
  k.a = param("a", Range::positive(), 1e3, k.a);
  k.h = param("h", Range::positive(), 1e3, k.h);
  k.d = param("d", Range::not_zero(), 1e3, k.d);
  k.r = param("r", Range::positive(), 1e3, k.r);
  if (!o.has("uv_scale")) o.fail("missing required key 'uv_scale'");
  k.uv_scale = param("uv_scale", Range::positive(), 1e6, 0.0f);

  JsonNode yc = o.at("yarn_colors");
  for (const JsonNode& c : yc.elements(1, static_cast<size_t>(Pattern::kMaxColors)))
    k.yarn_colors.push_back(c.rgb(Range::closed(0, 1)));
  if (!k.colors.empty()) {
    const int used = 1 + *std::max_element(k.colors.begin(), k.colors.end());
    if (used > static_cast<int>(k.yarn_colors.size()))
      yc.fail("the colors matrix uses colour index " + std::to_string(used - 1) + " but only " +
              std::to_string(k.yarn_colors.size()) + " yarn colours are given");
  }

  if (auto s = o.get("specular")) {
    JsonObject so(*s);
    k.specular_roughness = so.number("roughness", Range::left_open(0, 1), k.specular_roughness);
    k.specular_eta = so.number("eta", Range::left_open(1, 3), k.specular_eta);
    so.finish();
  }
  if (auto b = o.get("body")) {
    JsonObject bo(*b);
    k.body_energy = bo.number("energy", Range::closed(0, 1), k.body_energy);
    k.body_reflect = bo.number("reflect", Range::closed(0, 1), k.body_reflect);
    bo.finish();
  }
  if (auto p = o.get("ply")) {
    JsonObject po(*p);
    k.ply_count = static_cast<int>(po.integer("count", 1, 16, k.ply_count));
    k.ply_twist = po.number("twist", Range::right_open(0, 90), k.ply_twist);
    k.ply_shadowing = po.number("shadowing", Range::closed(0, 1), k.ply_shadowing);
    po.finish();
  }
  if (auto f = o.get("fiber")) {
    JsonObject fo(*f);
    k.fiber_twist = fo.number("twist", Range::right_open(0, 90), k.fiber_twist);
    k.fiber_shadowing = fo.number("shadowing", Range::closed(0, 1), k.fiber_shadowing);
    fo.finish();
  }
  const std::string mode = o.choice("mode", {"near_field", "multi_scale"}, "multi_scale");
  k.mode = mode == "near_field" ? KnitMode::NearField : KnitMode::MultiScale;
  k.capm = o.boolean("capm", k.capm);
  k.footprint_samples = static_cast<int>(o.integer("footprint_samples", 1, 1024, k.footprint_samples));
  return k;
}

}  // namespace knit::render
