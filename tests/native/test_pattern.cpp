// knit::Pattern: every accepted syntax, the value API, canonical text and
// round trips (random property test included). Errors: test_pattern_errors.cpp.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

#include "knit/pattern.h"
#include "pattern_testing.h"

using knit::Pattern;
using knit::Stitch;

namespace {

std::vector<int32_t> v(std::initializer_list<int32_t> x) { return x; }

TEST(PatternSyntax, DefaultIsOneKnitCell) {
  Pattern p;
  EXPECT_EQ(p.rows(), 1);
  EXPECT_EQ(p.cols(), 1);
  EXPECT_EQ(p.stitch(0, 0), Stitch::Knit);
  EXPECT_EQ(p.codes(), v({0}));
  EXPECT_EQ(p.colors_or_zero(), v({0}));
  EXPECT_FALSE(p.has_colors());
  EXPECT_EQ(p.num_colors(), 1);
}

TEST(PatternSyntax, DigitsSeparatedBySpaces) {
  Pattern p = Pattern::parse("0 1 2 3\n3 2 1 0\n");
  EXPECT_EQ(p.rows(), 2);
  EXPECT_EQ(p.cols(), 4);
  EXPECT_EQ(p.codes(), v({0, 1, 2, 3, 3, 2, 1, 0}));
}

TEST(PatternSyntax, LettersAnyCaseMeanTheSameCodes) {
  Pattern upper = Pattern::parse("K P F B");
  Pattern lower = Pattern::parse("k p f b");
  Pattern digits = Pattern::parse("0 1 2 3");
  EXPECT_EQ(upper.codes(), v({0, 1, 2, 3}));
  EXPECT_EQ(upper, lower);
  EXPECT_EQ(upper, digits);
  EXPECT_EQ(upper.stitch(0, 0), Stitch::Knit);
  EXPECT_EQ(upper.stitch(0, 1), Stitch::Purl);
  EXPECT_EQ(upper.stitch(0, 2), Stitch::Front);
  EXPECT_EQ(upper.stitch(0, 3), Stitch::Back);
}

TEST(PatternSyntax, CommasTabsAndMixedSeparators) {
  Pattern want = Pattern::parse("K P K P");
  EXPECT_EQ(Pattern::parse("K,P,K,P"), want);
  EXPECT_EQ(Pattern::parse("K, P ,K\t,\tP"), want);
  EXPECT_EQ(Pattern::parse("K\tP\tK\tP"), want);
  EXPECT_EQ(Pattern::parse("0,1 k\tp"), want);
  EXPECT_EQ(Pattern::parse("  K P K P  "), want);
  EXPECT_EQ(Pattern::parse("K, P, K, P,"), want);  // one trailing comma is allowed
}

TEST(PatternSyntax, CompactRowsOneCharacterPerCell) {
  Pattern p = Pattern::parse("KKPP\n0011\nfbFB\n");
  EXPECT_EQ(p.rows(), 3);
  EXPECT_EQ(p.cols(), 4);
  EXPECT_EQ(p.codes(), v({0, 0, 1, 1, 0, 0, 1, 1, 2, 3, 2, 3}));
}

TEST(PatternSyntax, CompactAndSeparatedLinesMix) {
  EXPECT_EQ(Pattern::parse("KP\nK,P\n  PK  # indented compact\n"),
            Pattern::from_rows({{0, 1}, {0, 1}, {1, 0}}));
}

TEST(PatternSyntax, CommentsBlankLinesAndLineEndings) {
  const char* text =
      "# a header comment\n"
      "\n"
      "K P   # trailing comment\n"
      "   \t \n"
      "#K P K\n"
      "P K#comment right after a cell\r\n"
      "\r\n";
  Pattern p = Pattern::parse(text);
  EXPECT_EQ(p, Pattern::from_rows({{0, 1}, {1, 0}}));
}

TEST(PatternSyntax, NoFinalNewlineAndCrLf) {
  EXPECT_EQ(Pattern::parse("K P\r\nP K"), Pattern::from_rows({{0, 1}, {1, 0}}));
}

TEST(PatternSyntax, ByteOrderMarkIsSkipped) {
  EXPECT_EQ(Pattern::parse("\xEF\xBB\xBFKP\nPK\n"), Pattern::from_rows({{0, 1}, {1, 0}}));
}

TEST(PatternSyntax, Utf8InCommentsIsFine) {
  EXPECT_EQ(Pattern::parse("# 2×2 rib — ✓\nKKPP # naïve\n"), Pattern::from_rows({{0, 0, 1, 1}}));
}

TEST(PatternSyntax, ColorsSection) {
  Pattern p = Pattern::parse("K P\nP K\ncolors:\n0 1\n2, 255\n");
  EXPECT_TRUE(p.has_colors());
  EXPECT_EQ(p.num_colors(), 256);
  EXPECT_EQ(p.color(0, 1), 1);
  EXPECT_EQ(p.color(1, 0), 2);
  EXPECT_EQ(p.color(1, 1), 255);
  EXPECT_EQ(p.colors_or_zero(), v({0, 1, 2, 255}));
}

TEST(PatternSyntax, ColorsHeaderSpellingsAndCase) {
  Pattern want = Pattern::from_rows({{0, 1}}, {{1, 0}});
  EXPECT_EQ(Pattern::parse("KP\ncolors:\n1 0"), want);
  EXPECT_EQ(Pattern::parse("KP\nCOLORS:\n1 0"), want);
  EXPECT_EQ(Pattern::parse("KP\ncolours:\n1 0"), want);
  EXPECT_EQ(Pattern::parse("KP\n  Colours:  # British\n1 0"), want);
}

TEST(PatternSyntax, CompactColourRowsAndLeadingZerosAndSigns) {
  Pattern want = Pattern::from_rows({{0, 1, 0}}, {{1, 0, 9}});
  EXPECT_EQ(Pattern::parse("KPK\ncolors:\n109\n"), want);
  EXPECT_EQ(Pattern::parse("KPK\ncolors:\n01, 000, +9\n"), want);
  EXPECT_EQ(Pattern::parse("KPK\ncolors:\n1 -0 9\n"), want);
}

TEST(PatternSyntax, OneColumnColourRowIsOneIndex) {
  // With one column a colour row without separators is a single index, so
  // the canonical text of a colour >= 10 reads back.
  Pattern p = Pattern::parse("K\nP\ncolors:\n12\n7\n");
  EXPECT_EQ(p.colors_or_zero(), v({12, 7}));
  EXPECT_EQ(Pattern::parse(p.to_text()), p);
}

TEST(PatternSyntax, ColourMatrixWithCommentsAndBlankLines) {
  Pattern p = Pattern::parse("KP\nPK\n\ncolors: # two colours\n# row 1\n1 0\n\n0 1 # row 2\n");
  EXPECT_EQ(p.colors_or_zero(), v({1, 0, 0, 1}));
}

TEST(PatternSyntax, NoColorsMeansZerosAndOneColour) {
  Pattern p = Pattern::parse("KP\nPK");
  EXPECT_FALSE(p.has_colors());
  EXPECT_EQ(p.num_colors(), 1);
  EXPECT_EQ(p.color(1, 1), 0);
  EXPECT_EQ(p.colors_or_zero(), v({0, 0, 0, 0}));
}

TEST(PatternValue, UsesAndNumColors) {
  Pattern p = Pattern::parse("K K\nP K\ncolors:\n0 3\n3 0");
  EXPECT_TRUE(p.uses(Stitch::Knit));
  EXPECT_TRUE(p.uses(Stitch::Purl));
  EXPECT_FALSE(p.uses(Stitch::Front));
  EXPECT_FALSE(p.uses(Stitch::Back));
  EXPECT_EQ(p.num_colors(), 4);
}

TEST(PatternValue, CellAccessIsBoundsChecked) {
  Pattern p = Pattern::parse("K P F\nB K P");
  EXPECT_EQ(p.code(1, 0), 3);
  EXPECT_EQ(p.code(0, 2), 2);
  EXPECT_THROW(p.stitch(2, 0), std::out_of_range);
  EXPECT_THROW(p.stitch(0, 3), std::out_of_range);
  EXPECT_THROW(p.stitch(-1, 0), std::out_of_range);
  EXPECT_THROW(p.color(0, -1), std::out_of_range);
  EXPECT_THROW(p.color(0, 3), std::out_of_range);
}

TEST(PatternValue, EqualityComparesShapeCodesAndColours) {
  Pattern a = Pattern::from_rows({{0, 1}});
  EXPECT_EQ(a, Pattern::from_rows({{0, 1}}));
  EXPECT_NE(a, Pattern::from_rows({{0}, {1}}));  // same codes, other shape
  EXPECT_NE(a, Pattern::from_rows({{1, 0}}));
  EXPECT_NE(a, Pattern::from_rows({{0, 1}}, {{0, 0}}));  // an explicit colour matrix counts
  EXPECT_NE(Pattern::from_rows({{0, 1}}, {{0, 1}}), Pattern::from_rows({{0, 1}}, {{0, 2}}));
}

TEST(PatternValue, ConstructorFromArrays) {
  Pattern p(2, 3, {0, 1, 2, 3, 2, 1}, {0, 0, 1, 1, 2, 2});
  EXPECT_EQ(p.rows(), 2);
  EXPECT_EQ(p.cols(), 3);
  EXPECT_EQ(p.code(1, 0), 3);
  EXPECT_EQ(p.color(1, 2), 2);
  EXPECT_EQ(p, Pattern::from_rows({{0, 1, 2}, {3, 2, 1}}, {{0, 0, 1}, {1, 2, 2}}));
}

TEST(PatternText, CanonicalForm) {
  EXPECT_EQ(Pattern::parse("0123\n3210").to_text(), "K P F B\nB F P K\n");
  EXPECT_EQ(Pattern::parse("kp\npk\ncolours:\n1,0\n0,12").to_text(),
            "K P\nP K\ncolors:\n1 0\n0 12\n");
  EXPECT_EQ(Pattern().to_text(), "K\n");
}

TEST(PatternText, RoundTripOfEverySyntax) {
  const char* inputs[] = {
      "K",          "0 1\n2 3",         "KKPP\nPPKK",      "k,p,f,b",
      "K\nP\nF\nB", "KP\ncolors:\n0 1", "K\ncolors:\n200", "FB\nBF\ncolours:\n3,4\n5 6",
  };
  for (const char* in : inputs) {
    Pattern p = Pattern::parse(in);
    std::string text = p.to_text();
    EXPECT_EQ(Pattern::parse(text), p) << in;
    EXPECT_EQ(Pattern::parse(text).to_text(), text) << in;  // canonical text is a fixed point
  }
}

TEST(PatternText, RandomRoundTripProperty) {
  std::mt19937 rng(1234);
  for (int iter = 0; iter < 400; ++iter) {
    int rows = std::uniform_int_distribution<int>(1, 40)(rng);
    int cols = std::uniform_int_distribution<int>(1, 40)(rng);
    bool colored = iter % 2 == 1;
    int max_color = std::uniform_int_distribution<int>(0, 255)(rng);
    std::vector<std::vector<int>> codes(rows, std::vector<int>(cols));
    std::vector<std::vector<int>> colors;
    for (auto& row : codes)
      for (int& x : row) x = std::uniform_int_distribution<int>(0, 3)(rng);
    if (colored) {
      colors.assign(rows, std::vector<int>(cols));
      for (auto& row : colors)
        for (int& x : row) x = std::uniform_int_distribution<int>(0, max_color)(rng);
    }
    Pattern p = Pattern::from_rows(codes, colors);
    Pattern q = Pattern::parse(p.to_text(), "<random>");
    ASSERT_EQ(q, p) << "iteration " << iter << "\n" << p.to_text();
    for (int r = 0; r < rows; ++r) {
      for (int c = 0; c < cols; ++c) {
        ASSERT_EQ(q.code(r, c), codes[r][c]);
        ASSERT_EQ(q.color(r, c), colored ? colors[r][c] : 0);
      }
    }
  }
}

TEST(PatternText, RandomSyntaxVariantsParseToTheSamePattern) {
  // Writes the same random pattern with random separators, letter case,
  // digits or letters, comments and blank lines; all must parse equal.
  std::mt19937 rng(99);
  const char* seps[] = {" ", ",", ", ", "\t", " ,\t", "  "};
  for (int iter = 0; iter < 200; ++iter) {
    int rows = std::uniform_int_distribution<int>(1, 12)(rng);
    int cols = std::uniform_int_distribution<int>(1, 12)(rng);
    std::vector<std::vector<int>> codes(rows, std::vector<int>(cols));
    for (auto& row : codes)
      for (int& x : row) x = std::uniform_int_distribution<int>(0, 3)(rng);
    std::string text;
    for (const auto& row : codes) {
      bool compact = rng() % 2 == 0;
      const char* sep = seps[rng() % 6];
      if (rng() % 3 == 0) text += "# comment K P ,\n\n";
      for (int c = 0; c < cols; ++c) {
        if (c && !compact) text += sep;
        int style = static_cast<int>(rng() % 3);
        text += style == 0 ? "0123"[row[c]] : style == 1 ? "KPFB"[row[c]] : "kpfb"[row[c]];
      }
      text += rng() % 2 ? "\n" : "  # end\r\n";
    }
    ASSERT_EQ(Pattern::parse(text), Pattern::from_rows(codes)) << text;
  }
}

TEST(PatternLimits, MaxSizePatternParses) {
  // 4096 columns in one row (compact) and 4096 rows of one column.
  Pattern wide = Pattern::parse(std::string(4096, 'P'));
  EXPECT_EQ(wide.cols(), 4096);
  EXPECT_EQ(wide.code(0, 4095), 1);
  std::string tall_text;
  for (int i = 0; i < 4096; ++i) tall_text += "B\n";
  Pattern tall = Pattern::parse(tall_text);
  EXPECT_EQ(tall.rows(), 4096);
  EXPECT_EQ(tall.code(4095, 0), 3);
}

TEST(PatternLimits, FullSize4096By4096WithColorsParsesAndRoundTrips) {
  std::string row(4096, 'K');
  std::string crow(4096, '1');
  std::string text;
  for (int i = 0; i < 4096; ++i) text += row + "\n";
  text += "colors:\n";
  for (int i = 0; i < 4096; ++i) text += crow + "\n";
  Pattern p = Pattern::parse(text);
  EXPECT_EQ(p.rows(), 4096);
  EXPECT_EQ(p.cols(), 4096);
  EXPECT_EQ(p.color(4095, 4095), 1);
  EXPECT_EQ(p.num_colors(), 2);
  // The largest canonical text: three-digit colours everywhere (~96 MiB)
  // still fits under the input limit.
  Pattern big(4096, 4096, std::vector<int32_t>(size_t(4096) * 4096, 3),
              std::vector<int32_t>(size_t(4096) * 4096, 255));
  std::string big_text = big.to_text();
  EXPECT_GT(big_text.size(), size_t(96) << 20);
  EXPECT_EQ(Pattern::parse(big_text), big);
}

}  // namespace
