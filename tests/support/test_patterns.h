// Patterns used by the geometry tests, built in code so each test states
// exactly what it covers (the shipped examples are tested separately).
#pragma once

#include <string>
#include <vector>

#include "knit/pattern.h"

namespace knit::test {

inline Pattern stockinette() { return Pattern::from_rows({{0}}); }
inline Pattern reverse_stockinette() { return Pattern::from_rows({{1}}); }
inline Pattern rib_1x1() { return Pattern::from_rows({{0, 1}}); }
inline Pattern seed() { return Pattern::from_rows({{0, 1}, {1, 0}}); }
inline Pattern garter() { return Pattern::from_rows({{0}, {1}}); }
inline Pattern slip_floats() { return Pattern::from_rows({{0, 2, 0, 3}, {0, 0, 0, 0}}); }

// A 16x16 knit/purl pyramid: purl triangles on a knit ground.
inline Pattern pyramid16() {
  std::vector<std::vector<int>> rows(16, std::vector<int>(16, 0));
  for (int r = 0; r < 16; ++r) {
    int half = (r + 1) / 2;  // widens downwards
    for (int c = 8 - half; c < 8 + half; ++c) rows[size_t(r)][size_t(c)] = 1;
  }
  return Pattern::from_rows(rows);
}

struct NamedPattern {
  std::string name;
  Pattern pattern;
};

#ifdef KNIT_SOURCE_DIR
// A shipped example pattern (examples/patterns/<name>.knit).
inline Pattern example(const std::string& name) {
  return Pattern::from_file(std::string(KNIT_SOURCE_DIR) + "/examples/patterns/" + name + ".knit");
}

// The ground-truth set: the shipped example files.
inline std::vector<NamedPattern> groundtruth_patterns() {
  return {{"stockinette", example("stockinette")},
          {"reverse_stockinette", example("reverse_stockinette")},
          {"rib_1x1", example("rib_1x1")},
          {"seed", example("seed")},
          {"pyramid16", example("pyramid")}};
}
#endif

}  // namespace knit::test
