// The shader text for a pattern: the embedded template with the pattern's
// block where the template includes knit_pattern.h. The block's bytes must
// equal core/shader.py's pattern_block (tests/addon_core checks it).
#include "knit/osl_source.h"

#include <algorithm>
#include <stdexcept>

namespace knit {
namespace {

const char* const kPatternLine = "#include \"knit_pattern.h\"";

void append_array(std::string& out, const std::vector<int32_t>& v, int rows, int cols) {
  for (int r = 0; r < rows; ++r) {
    out += "  ";
    for (int c = 0; c < cols; ++c) {
      if (c) out += ", ";
      out += std::to_string(v[size_t(r) * size_t(cols) + size_t(c)]);
    }
    out += r + 1 < rows ? ", \\\n" : " }";
  }
}

}  // namespace

std::string osl_source(const Pattern& pattern) {
  const int rows = pattern.rows(), cols = pattern.cols();
  if (rows > kOslMaxSide || cols > kOslMaxSide)
    throw std::invalid_argument("the pattern is " + std::to_string(rows) + " x " + std::to_string(cols) +
                                " stitches; the shader takes patterns of at most " + std::to_string(kOslMaxSide) +
                                " x " + std::to_string(kOslMaxSide));
  const std::vector<int32_t>& colours = pattern.colors_or_zero();
  const int top = colours.empty() ? 0 : *std::max_element(colours.begin(), colours.end());
  if (top >= kOslPaletteSize)
    throw std::invalid_argument("the pattern uses colour index " + std::to_string(top) +
                                "; the shader's palette has " + std::to_string(kOslPaletteSize) +
                                " yarn colours, indices 0 to " + std::to_string(kOslPaletteSize - 1));
  const bool floats = pattern.uses(Stitch::Front) || pattern.uses(Stitch::Back);
  std::string block = "/* Pattern: " + std::to_string(rows) + " x " + std::to_string(cols) +
                      " stitches, row 0 at the top. */\n";
  block += "#define KNIT_PATTERN_ROWS " + std::to_string(rows) + "\n";
  block += "#define KNIT_PATTERN_COLS " + std::to_string(cols) + "\n";
  block += "#define KNIT_PATTERN_CELLS " + std::to_string(rows * cols) + "\n";
  block += std::string("#define KNIT_PATTERN_HAS_FLOATS ") + (floats ? "1" : "0") + "\n";
  block += "#define KNIT_PATTERN_CODES { \\\n";
  append_array(block, pattern.codes(), rows, cols);
  block += "\n#define KNIT_PATTERN_COLOURS { \\\n";
  append_array(block, colours, rows, cols);
  const std::string& t = osl_template();
  const size_t at = t.find(kPatternLine);
  if (at == std::string::npos) throw std::logic_error("the embedded OSL template has no pattern line");
  return t.substr(0, at) + block + t.substr(at + std::string(kPatternLine).size());
}

}  // namespace knit
