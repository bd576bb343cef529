// Scene file parser: the "materials" map (docs/scene-format.md#materials).
#include "render/scene_parse_internal.h"

namespace knit::render {

MaterialDesc parse_material(JsonNode node, const std::string& name, const std::string& dir,
                            bool class_tables) {
  JsonObject o(node);
  MaterialDesc m;
  m.name = name;
  m.path = node.path();
  const std::string type = o.at("type").choice({"diffuse", "dielectric", "thin", "knit"});
  const Range unit = Range::closed(0, 1);
  if (type == "diffuse") {
    m.type = MaterialType::Diffuse;
    m.diffuse.albedo = o.rgb("albedo", unit);
  } else if (type == "dielectric") {
    m.type = MaterialType::Dielectric;
    m.dielectric.eta = o.number("eta", Range::left_open(0, 4), m.dielectric.eta);
    const std::optional<JsonNode> rough = o.get("roughness");
    const double roughness = rough ? rough->number(unit) : 0.0;
    m.dielectric.tint = o.rgb("tint", unit, Rgb(1.0f));
    // GGX alpha = roughness^2: below 1e-4 single precision cannot resolve the
    // lobe (its peak D = 1 / (pi alpha^2) and the half vector's rounding).
    if (roughness > 0 && roughness < kMinDielectricRoughness)
      rough->fail("must be 0 (smooth) or in [" + fmt_num(kMinDielectricRoughness) +
                  ", 1] (GGX alpha = roughness^2), got " + fmt_num(roughness));
    m.dielectric.roughness = float(roughness);
  } else if (type == "thin") {
    m.type = MaterialType::Thin;
    m.thin.transmittance = o.rgb("transmittance", unit);
    m.thin.albedo = o.rgb("albedo", unit, Rgb(0.0f));
    const Rgb sum = m.thin.transmittance + m.thin.albedo;
    if (sum.max() > 1.0f + 1e-6f)
      o.at("albedo").fail("albedo + transmittance must be <= 1 in every channel, got " +
                          fmt_num(sum.max()));
  } else {
    m.type = MaterialType::Knit;
    m.knit = parse_knit_material(o, dir, class_tables);
  }
  o.finish();
  return m;
}

}  // namespace knit::render
