// Internal to the scene parser (scene_parse.cpp, parse_lights.cpp,
// parse_materials.cpp, parse_knit.cpp).
#pragma once

#include <string>

#include "render/json_strict.h"
#include "render/scene_desc.h"

namespace knit::render {

// Largest coordinate magnitude accepted for positions and offsets.
constexpr double kMaxCoord = 1e6;
// Largest emission / intensity / irradiance component.
constexpr double kMaxEmission = 1e9;

// Resolves `rel` against `dir` and checks that it names a readable regular
// file; `node` locates the error ("objects[0].mesh: file not found: ...").
std::string resolve_input_file(const JsonNode& node, const std::string& dir);

LightDesc parse_light(JsonNode node, const std::string& dir);
// class_tables: false when the knit model will not shade (explicit yarns):
// multi-scale materials then skip building their class table.
MaterialDesc parse_material(JsonNode node, const std::string& name, const std::string& dir,
                            bool class_tables = true);
KnitDesc parse_knit_material(JsonObject& obj, const std::string& dir, bool class_tables = true);

}  // namespace knit::render
