// libFuzzer harness for the pattern text format: any input either parses to a
// pattern whose canonical text reads back equal, or throws a PatternError
// with a sane position. Anything else (crash, other exception, mismatch)
// aborts. Built as `fuzz_pattern` (clang, KNIT_FUZZ=ON) and as the corpus
// replay test with any compiler (replay_main.cpp).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

#include "knit/pattern.h"

namespace {

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_pattern: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void check_pattern(const knit::Pattern& p) {
  if (p.rows() < 1 || p.rows() > knit::Pattern::kMaxRows || p.cols() < 1 ||
      p.cols() > knit::Pattern::kMaxCols) {
    fail("shape out of limits", p.to_text());
  }
  const size_t cells = static_cast<size_t>(p.rows()) * static_cast<size_t>(p.cols());
  if (p.codes().size() != cells || p.colors_or_zero().size() != cells) {
    fail("array size differs from rows*cols", p.to_text());
  }
  for (int32_t c : p.codes())
    if (c < 0 || c > 3) fail("code out of range", p.to_text());
  for (int32_t c : p.colors_or_zero())
    if (c < 0 || c >= knit::Pattern::kMaxColors) fail("colour out of range", p.to_text());
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::string_view text(reinterpret_cast<const char*>(data), size);
  knit::Pattern p;
  try {
    p = knit::Pattern::parse(text, "<fuzz>");
  } catch (const knit::PatternError& e) {
    size_t lines = 1;
    for (char c : text) lines += c == '\n';
    bool positioned = e.line() > 0;
    if (e.source() != "<fuzz>" || e.line() < 0 || static_cast<size_t>(e.line()) > lines ||
        e.column() < 0 || static_cast<size_t>(e.column()) > size + 1 ||
        positioned != (e.column() > 0) || e.message().empty()) {
      fail("error position out of range", e.what());
    }
    return 0;
  }
  check_pattern(p);
  const std::string canonical = p.to_text();
  knit::Pattern q;
  try {
    q = knit::Pattern::parse(canonical, "<canonical>");
  } catch (const knit::PatternError& e) {
    fail("canonical text does not parse", std::string(e.what()) + "\n" + canonical);
  }
  if (q != p) fail("parse(to_text()) differs from the pattern", canonical);
  if (q.to_text() != canonical) fail("canonical text is not a fixed point", canonical);
  return 0;
}
