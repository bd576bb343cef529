// Writing the rendered image: EXR (linear float) or PNG (display-referred,
// 8-bit, through the OpenColorIO display transform), chosen by extension.
#pragma once

#include <string>

#include "render/display.h"
#include "render/image.h"

namespace knit::render {

enum class OutputFormat { Exr, Png };

// The format for `path`'s extension (case-insensitive .exr or .png); throws
// std::runtime_error otherwise. Call before rendering to fail early.
OutputFormat output_format_for(const std::string& path);

// Multiplies by 2^exposure and writes. PNG values are display-encoded, then
// clamped to [0, 1] and rounded to 8 bits (the only place values are clamped).
void write_output(const std::string& path, const RgbImage& linear, float exposure, const DisplaySettings& display);

}  // namespace knit::render
