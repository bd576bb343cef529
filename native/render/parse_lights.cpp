// Scene file parser: the "lights" array (docs/scene-format.md#lights).
#include "render/scene_parse_internal.h"

namespace knit::render {

LightDesc parse_light(JsonNode node, const std::string& dir) {
  JsonObject o(node);
  LightDesc l;
  l.path = node.path();
  const std::string type = o.at("type").choice({"quad", "point", "directional", "environment"});
  const Range coord = Range::magnitude(kMaxCoord);
  const Range emit = Range::closed(0, kMaxEmission);
  if (type == "quad") {
    l.type = LightType::Quad;
    l.corner = o.vec3("corner", coord);
    l.edge_u = o.vec3("edge_u", coord);
    l.edge_v = o.vec3("edge_v", coord);
    l.emission = o.rgb("emission", emit);
    l.two_sided = o.boolean("two_sided", false);
    const Vec3 n = cross(l.edge_u, l.edge_v);
    if (!(length(n) > 1e-12f))
      o.at("edge_v").fail("edge_u and edge_v must be non-zero and not parallel (zero area)");
  } else if (type == "point") {
    l.type = LightType::Point;
    l.position = o.vec3("position", coord);
    l.intensity = o.rgb("intensity", emit);
  } else if (type == "directional") {
    l.type = LightType::Directional;
    l.to_light = o.at("to_light").direction();
    l.irradiance = o.rgb("irradiance", emit);
    if (auto ar = o.get("angular_radius")) {
      const float v = ar->number_f(Range::non_negative());
      if (v != 0)
        ar->fail("must be 0 (only delta directional lights are supported), got " + fmt_num(v));
    }
  } else {
    const bool has_file = o.has("file"), has_color = o.has("color");
    if (has_file == has_color)
      o.fail("an environment light needs exactly one of \"file\" (lat-long image) or \"color\"");
    if (has_file) {
      l.type = LightType::EnvironmentMap;
      l.file = resolve_input_file(o.at("file"), dir);
    } else {
      l.type = LightType::EnvironmentUniform;
      l.color = o.rgb("color", emit);
    }
    l.strength = o.number("strength", Range::closed(0, kMaxEmission), 1.0f);
    l.rotation = o.number("rotation", Range::magnitude(1e5), 0.0f);
  }
  o.finish();
  return l;
}

}  // namespace knit::render
