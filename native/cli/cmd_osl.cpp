// `knitshade osl PATTERN -o FILE`: the self-contained Cycles shader for a
// pattern file (knit::osl_source).
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "knit/osl_source.h"
#include "knit/pattern.h"

namespace knit::cli {
namespace {

const char* kHelp = R"(usage: knitshade osl PATTERN [-o FILE]

Writes the knit shader for Cycles (OSL) with the pattern of PATTERN (a .knit
file, docs/patterns.md) compiled in: one self-contained text, the shared
kernel inlined, the same bytes for the same pattern. Every other setting is
a shader parameter (docs/shader.md). Without -o the text goes to standard
output. Patterns of up to 256 x 256 stitches and colour indices 0 to 7.

options:
  -o, --output FILE   where to write the shader (.osl)
)";

int run(const std::vector<std::string>& args) {
  std::string pattern_path, out;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kHelp);
      return 0;
    } else if (a == "-o" || a == "--output") {
      out = option_value(args, i);
      if (out.empty()) throw UsageError{a + ": empty file name"};
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else if (pattern_path.empty()) {
      pattern_path = a;
    } else {
      throw UsageError{"one pattern file only (got " + pattern_path + " and " + a + ")"};
    }
  }
  if (pattern_path.empty()) throw UsageError{"missing the pattern file"};
  const Pattern pattern = Pattern::from_file(pattern_path);
  std::string text;
  try {
    text = osl_source(pattern);
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(pattern_path + ": " + e.what());
  }
  if (out.empty()) {
    std::fwrite(text.data(), 1, text.size(), stdout);
    return 0;
  }
  std::ofstream f(out, std::ios::binary);
  if (f) f.write(text.data(), std::streamsize(text.size()));
  if (!f) throw std::runtime_error(out + ": cannot write the shader");
  std::fprintf(stderr, "knitshade osl: wrote %s (%d x %d stitches, %zu bytes)\n", out.c_str(), pattern.rows(),
               pattern.cols(), text.size());
  return 0;
}

const bool registered = register_command({"osl", "write the Cycles (OSL) knit shader for a pattern", &run});

}  // namespace
}  // namespace knit::cli
