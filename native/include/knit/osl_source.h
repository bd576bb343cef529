// The knit shader for Cycles (OSL), self-contained, for one pattern.
//
// The template is osl/knit_fabric.osl with the shared kernel inlined (built
// by addon/knitshade_blender/core/shader.py and embedded at build time);
// osl_source puts the pattern in, as constant arrays, where the template
// includes knit_pattern.h. The add-on's generator does the same in Python:
// both give the same bytes for the same pattern (tests/addon_core).
// docs/shader.md describes the shader.
#pragma once

#include <string>

#include "knit/pattern.h"

namespace knit {

// Rows and columns a shader's pattern may have, and the yarn colours its
// palette holds (colour indices 0 .. kOslPaletteSize - 1).
constexpr int kOslMaxSide = 256;
constexpr int kOslPaletteSize = 8;

// The template text (the shader with the pattern header's include left in).
const std::string& osl_template();

// The shader text for `pattern`. Throws std::invalid_argument naming the
// limit when the pattern has more than kOslMaxSide rows or columns, or a
// colour index the palette does not hold.
std::string osl_source(const Pattern& pattern);

}  // namespace knit
