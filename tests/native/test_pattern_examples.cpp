// Every file in examples/patterns parses, has a comment header, has the
// expected shape, and shows the structure its name promises.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "knit/pattern.h"

using knit::Pattern;

namespace {

struct Expect {
  int rows, cols, num_colors;
  bool has_colors;
};

const std::map<std::string, Expect>& expected() {
  static const std::map<std::string, Expect> m = {
      {"stockinette", {4, 4, 1, false}},
      {"reverse_stockinette", {4, 4, 1, false}},
      {"garter", {4, 4, 1, false}},
      {"rib_1x1", {4, 4, 1, false}},
      {"rib_2x2", {4, 8, 1, false}},
      {"seed", {4, 4, 1, false}},
      {"moss", {4, 4, 1, false}},
      {"basketweave", {8, 8, 1, false}},
      {"pyramid", {16, 16, 1, false}},
      {"diamond_blocks_2colour", {48, 48, 2, true}},
      {"linen_stitch", {4, 4, 1, false}},
      {"heel_stitch", {4, 4, 1, false}},
      {"stripes_two_colour", {4, 4, 2, true}},
  };
  return m;
}

std::filesystem::path dir() { return std::filesystem::path(KNIT_SOURCE_DIR) / "examples/patterns"; }

Pattern load(const std::string& name) {
  return Pattern::from_file((dir() / (name + ".knit")).string());
}

TEST(PatternExamples, EveryFileParsesWithExpectedShape) {
  std::set<std::string> seen;
  for (const auto& entry : std::filesystem::directory_iterator(dir())) {
    if (entry.path().extension() != ".knit") continue;
    std::string name = entry.path().stem().string();
    seen.insert(name);
    auto it = expected().find(name);
    ASSERT_NE(it, expected().end()) << "no expectation for " << entry.path();
    Pattern p = Pattern::from_file(entry.path().string());
    EXPECT_EQ(p.rows(), it->second.rows) << name;
    EXPECT_EQ(p.cols(), it->second.cols) << name;
    EXPECT_EQ(p.has_colors(), it->second.has_colors) << name;
    EXPECT_EQ(p.num_colors(), it->second.num_colors) << name;
    EXPECT_EQ(Pattern::parse(p.to_text()), p) << name;
    std::ifstream in(entry.path());
    std::string first;
    std::getline(in, first);
    EXPECT_EQ(first.rfind("# ", 0), 0u) << name << " lacks a comment header";
  }
  EXPECT_EQ(seen.size(), expected().size()) << "an expected example file is missing";
}

// code(r, c) == f(r, c) for every cell.
template <class F>
void expect_cells(const std::string& name, F f) {
  Pattern p = load(name);
  for (int r = 0; r < p.rows(); ++r)
    for (int c = 0; c < p.cols(); ++c)
      EXPECT_EQ(p.code(r, c), f(r, c)) << name << " " << r << "," << c;
}

TEST(PatternExamples, StructureMatchesTheName) {
  expect_cells("stockinette", [](int, int) { return 0; });
  expect_cells("reverse_stockinette", [](int, int) { return 1; });
  expect_cells("garter", [](int r, int) { return r % 2; });
  expect_cells("rib_1x1", [](int, int c) { return c % 2; });
  expect_cells("rib_2x2", [](int, int c) { return (c / 2) % 2; });
  expect_cells("seed", [](int r, int c) { return (r + c) % 2; });
  expect_cells("moss", [](int r, int c) { return (r / 2 + c) % 2; });
  expect_cells("basketweave", [](int r, int c) { return (r / 4 + c / 4) % 2; });
  expect_cells("linen_stitch", [](int r, int c) { return r % 2 ? 0 : ((c + r / 2) % 2 ? 2 : 0); });
  expect_cells("heel_stitch", [](int r, int c) { return r % 2 ? 0 : (c % 2 ? 0 : 3); });
}

TEST(PatternExamples, PyramidWidensDownwards) {
  Pattern p = load("pyramid");
  int prev = 0;
  for (int r = 0; r < p.rows(); ++r) {
    int purls = 0;
    for (int c = 0; c < p.cols(); ++c) purls += p.code(r, c) == 1;
    EXPECT_GE(purls, prev) << "row " << r;
    EXPECT_EQ(p.code(r, 7), 1) << "apex column, row " << r;
    EXPECT_EQ(p.code(r, 0), r >= 14 ? 1 : 0) << "row " << r;
    prev = purls;
  }
  EXPECT_EQ(prev, 16);
}

TEST(PatternExamples, ColourExamplesUseBothColours) {
  Pattern stripes = load("stripes_two_colour");
  for (int r = 0; r < 4; ++r) EXPECT_EQ(stripes.color(r, 0), r / 2) << "row " << r;
  Pattern blocks = load("diamond_blocks_2colour");
  int ones = 0;
  for (int r = 0; r < 48; ++r)
    for (int c = 0; c < 48; ++c) ones += blocks.color(r, c);
  EXPECT_GT(ones, 48 * 48 / 5);
  EXPECT_LT(ones, 48 * 48 * 4 / 5);
  // Built from 4x4 blocks: every cell has the colour of its block's corner.
  for (int r = 0; r < 48; ++r)
    for (int c = 0; c < 48; ++c) ASSERT_EQ(blocks.color(r, c), blocks.color(r / 4 * 4, c / 4 * 4));
  EXPECT_FALSE(blocks.uses(knit::Stitch::Purl));
}

}  // namespace
