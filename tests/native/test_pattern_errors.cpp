// knit::Pattern errors: every message, with the source, line and column it
// names, from parse, from_file, from_rows and the array constructor; the
// 4096 and input-size limits.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "knit/pattern.h"
#include "pattern_testing.h"

using knit::Pattern;
using knit_test::ParseFails;
using knit_test::ThrowsPatternError;

namespace {

const char* kUnknown = " (expected 0-3 or K, P, F, B)";

TEST(PatternErrors, RaggedRows) {
  EXPECT_TRUE(
      ParseFails("K P\nK P K\n", 2, 5, "row has 3 cells, expected 2 like the first row (line 1)"));
  EXPECT_TRUE(ParseFails("# c\n\nKPK\nKPK\nKP\n", 5, 3,
                         "row has 2 cells, expected 3 like the first row (line 3)"));
  EXPECT_TRUE(
      ParseFails("K,P\nKPP\n", 2, 3, "row has 3 cells, expected 2 like the first row (line 1)"));
}

TEST(PatternErrors, UnknownCodeSeparated) {
  EXPECT_TRUE(ParseFails("K P\nK X\n", 2, 3, std::string("unknown stitch code 'X'") + kUnknown));
  EXPECT_TRUE(ParseFails("0 4", 1, 3, std::string("unknown stitch code '4'") + kUnknown));
  EXPECT_TRUE(ParseFails("K PP K", 1, 3, std::string("unknown stitch code 'PP'") + kUnknown));
  EXPECT_TRUE(ParseFails("K, é", 1, 4, std::string("unknown stitch code 'é'") + kUnknown));
  EXPECT_TRUE(
      ParseFails("colors : x", 1, 1, std::string("unknown stitch code 'colors'") + kUnknown));
}

TEST(PatternErrors, UnknownCodeCompact) {
  EXPECT_TRUE(ParseFails("KKXK", 1, 3, std::string("unknown stitch code 'X'") + kUnknown));
  EXPECT_TRUE(ParseFails("KKKK\nKK4K", 2, 3, std::string("unknown stitch code '4'") + kUnknown));
  EXPECT_TRUE(ParseFails("Kä", 1, 2, std::string("unknown stitch code 'ä'") + kUnknown));
  EXPECT_TRUE(ParseFails("colors", 1, 1, std::string("unknown stitch code 'c'") + kUnknown));
}

TEST(PatternErrors, LongTokenIsQuotedShortened) {
  EXPECT_TRUE(ParseFails("K " + std::string(100, 'x'), 1, 3,
                         "unknown stitch code '" + std::string(24, 'x') + "...'" + kUnknown));
}

TEST(PatternErrors, EmptyCells) {
  EXPECT_TRUE(ParseFails("K,,P", 1, 3, "empty cell (two commas in a row)"));
  EXPECT_TRUE(ParseFails("K, ,P", 1, 4, "empty cell (two commas in a row)"));
  EXPECT_TRUE(ParseFails("KP\n ,K", 2, 2, "empty cell (a comma with no cell before it)"));
  EXPECT_TRUE(ParseFails(",", 1, 1, "empty cell (a comma with no cell before it)"));
  EXPECT_TRUE(ParseFails("K,P,,", 1, 5, "empty cell (two commas in a row)"));
}

TEST(PatternErrors, EmptyPattern) {
  const std::string msg = "empty pattern (no stitch rows)";
  EXPECT_TRUE(ParseFails("", 0, 0, msg));
  EXPECT_TRUE(ParseFails("\n\n   \n", 0, 0, msg));
  EXPECT_TRUE(ParseFails("# only a comment\n# K P\n", 0, 0, msg));
  EXPECT_TRUE(ParseFails("\xEF\xBB\xBF", 0, 0, msg));
}

TEST(PatternErrors, ColourMatrixRowCount) {
  EXPECT_TRUE(ParseFails("KP\nPK\ncolors:\n0 1\n", 3, 1,
                         "colour matrix has 1 rows, expected 2 like the pattern"));
  EXPECT_TRUE(ParseFails("KP\n\n  colors:\n", 3, 1,
                         "colour matrix has 0 rows, expected 1 like the pattern"));
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 1\n  1 0\n", 4, 3,
                         "colour matrix has more rows than the pattern (1)"));
  // A stitch row after the colour matrix is read as a colour row.
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 1\nK P\n", 4, 1,
                         "colour matrix has more rows than the pattern (1)"));
}

TEST(PatternErrors, ColourMatrixColumnCount) {
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 1 1\n", 3, 5,
                         "colour row has 3 cells, expected 2 like the pattern"));
  EXPECT_TRUE(ParseFails("KPK\nPKP\ncolors:\n0 1 0\n01\n", 5, 3,
                         "colour row has 2 cells, expected 3 like the pattern"));
}

TEST(PatternErrors, ColourIndexOutOfRange) {
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 256", 3, 3, "colour index '256' out of range 0..255"));
  EXPECT_TRUE(ParseFails("KP\ncolors:\n-1,0", 3, 1, "colour index '-1' out of range 0..255"));
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 99999999999999999999999", 3, 3,
                         "colour index '99999999999999999999999' out of range 0..255"));
}

TEST(PatternErrors, ColourIndexNotAnInteger) {
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 a", 3, 3, "colour index 'a' is not an integer"));
  EXPECT_TRUE(ParseFails("KP\ncolors:\n1.5 0", 3, 1, "colour index '1.5' is not an integer"));
  EXPECT_TRUE(ParseFails("KP\ncolors:\n0 +", 3, 3, "colour index '+' is not an integer"));
  EXPECT_TRUE(ParseFails("KPK\ncolors:\n0k1", 3, 2, "colour index 'k' is not an integer"));
  EXPECT_TRUE(ParseFails("K\ncolors:\nK", 3, 1, "colour index 'K' is not an integer"));
}

TEST(PatternErrors, ColourSectionPlacement) {
  EXPECT_TRUE(ParseFails("# no rows yet\n  colors:\n0\n", 2, 3,
                         "colour section without a pattern (no stitch rows before it)"));
  EXPECT_TRUE(ParseFails("K\ncolors:\n0\nColours:\n0\n", 4, 1,
                         "second colour section (the first is at line 2)"));
  EXPECT_TRUE(
      ParseFails("K\ncolors: 0\n", 2, 8,
                 "unexpected text after 'colors:' (the colour matrix starts on the next line)"));
  EXPECT_TRUE(
      ParseFails("K\nCOLOURS:0\n", 2, 9,
                 "unexpected text after 'COLOURS:' (the colour matrix starts on the next line)"));
}

TEST(PatternErrors, NotText) {
  EXPECT_TRUE(ParseFails(std::string("K\0P", 3), 1, 2, "input is not text (NUL byte)"));
  EXPECT_TRUE(ParseFails("KP\n# \xFF", 2, 3, "input is not text (invalid UTF-8 byte 0xFF)"));
  EXPECT_TRUE(ParseFails("K\x01", 1, 2, "input is not text (control byte 0x01)"));
  EXPECT_TRUE(ParseFails("K\x7F", 1, 2, "input is not text (control byte 0x7F)"));
  EXPECT_TRUE(
      ParseFails("KP\xC3", 1, 3, "input is not text (invalid UTF-8 byte 0xC3)"));  // truncated
  EXPECT_TRUE(
      ParseFails("\xC0\xAF", 1, 1, "input is not text (invalid UTF-8 byte 0xC0)"));  // overlong
  EXPECT_TRUE(ParseFails("\xED\xA0\x80", 1, 1,
                         "input is not text (invalid UTF-8 byte 0xED)"));  // surrogate
  EXPECT_TRUE(ParseFails("\xF4\x90\x80\x80", 1, 1, "input is not text (invalid UTF-8 byte 0xF4)"));
  // Not-text is found before syntax errors on earlier lines.
  EXPECT_TRUE(ParseFails("X\n\n\x02", 3, 1, "input is not text (control byte 0x02)"));
}

TEST(PatternErrors, ColumnsCountCodePointsAndSkipTheByteOrderMark) {
  EXPECT_TRUE(ParseFails("K # é ✓\x01", 1, 8, "input is not text (control byte 0x01)"));
  EXPECT_TRUE(
      ParseFails("\xEF\xBB\xBFK X", 1, 3, std::string("unknown stitch code 'X'") + kUnknown));
}

TEST(PatternErrors, ErrorNamesTheSource) {
  EXPECT_TRUE(ThrowsPatternError([] { Pattern::parse("Q", "patterns/rib.knit"); },
                                 "patterns/rib.knit", 1, 1,
                                 std::string("unknown stitch code 'Q'") + kUnknown));
  EXPECT_TRUE(ThrowsPatternError([] { Pattern::parse("Q"); }, "<string>", 1, 1,
                                 std::string("unknown stitch code 'Q'") + kUnknown));
}

TEST(PatternLimits, RowLimit) {
  std::string ok;
  for (int i = 0; i < 4096; ++i) ok += "KP\n";
  EXPECT_EQ(Pattern::parse(ok).rows(), 4096);
  // Line 4098: the comment shifts lines against rows.
  EXPECT_TRUE(ParseFails("# header\n" + ok + "PK\n", 4098, 1, "more than 4096 rows (the limit)"));
}

TEST(PatternLimits, ColumnLimit) {
  EXPECT_EQ(Pattern::parse(std::string(4096, 'K')).cols(), 4096);
  EXPECT_TRUE(
      ParseFails(std::string(4097, 'K'), 1, 4097, "row has more than 4096 cells (the limit)"));
  std::string sep;
  for (int i = 0; i < 4097; ++i) sep += "P ";
  EXPECT_TRUE(ParseFails(sep, 1, 8193, "row has more than 4096 cells (the limit)"));
  EXPECT_EQ(Pattern::parse(sep.substr(0, 2 * 4096)).cols(), 4096);
  // A long line is rejected at cell 4097, however long it goes on.
  EXPECT_TRUE(
      ParseFails(std::string(1 << 20, 'F'), 1, 4097, "row has more than 4096 cells (the limit)"));
  EXPECT_TRUE(ParseFails(std::string(4096, 'K') + "\ncolors:\n" + std::string(4097, '1'), 3, 4097,
                         "row has more than 4096 cells (the limit)"));
}

TEST(PatternLimits, InputSizeLimit) {
  std::string big((size_t(128) << 20) + 1, ' ');
  EXPECT_TRUE(ParseFails(big, 0, 0, "input is 134217729 bytes, more than the 128 MiB limit"));
  big.pop_back();  // exactly the limit: read (and empty)
  EXPECT_TRUE(ParseFails(big, 0, 0, "empty pattern (no stitch rows)"));
}

std::filesystem::path temp_dir() {
  auto dir = std::filesystem::path(KNIT_TEST_OUTPUT_DIR) / "pattern";
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(PatternFile, ReadsAFile) {
  auto path = temp_dir() / "ok.knit";
  std::ofstream(path) << "# 1x1 rib\nK P\nK P\n";
  Pattern p = Pattern::from_file(path.string());
  EXPECT_EQ(p, Pattern::from_rows({{0, 1}, {0, 1}}));
}

TEST(PatternFile, ErrorsNameThePath) {
  auto path = temp_dir() / "bad.knit";
  std::ofstream(path) << "K P\nK Z\n";
  std::string p = path.string();
  EXPECT_TRUE(ThrowsPatternError([&] { Pattern::from_file(p); }, p, 2, 3,
                                 std::string("unknown stitch code 'Z'") + kUnknown));
}

TEST(PatternFile, MissingFile) {
  std::string p = (temp_dir() / "does-not-exist.knit").string();
  EXPECT_TRUE(
      ThrowsPatternError([&] { Pattern::from_file(p); }, p, 0, 0,
                         "cannot open pattern file '" + p + "': No such file or directory"));
}

TEST(PatternFile, DirectoryIsNotAPatternFile) {
  std::string p = temp_dir().string();
  EXPECT_TRUE(ThrowsPatternError([&] { Pattern::from_file(p); }, p, 0, 0,
                                 "cannot read pattern file '" + p + "': Is a directory"));
}

TEST(PatternFile, OversizedFileIsRejected) {
  auto path = temp_dir() / "huge.knit";
  { std::ofstream(path) << "K\n"; }
  std::filesystem::resize_file(path, (std::uintmax_t(128) << 20) + 4096);  // sparse
  std::string p = path.string();
  EXPECT_TRUE(ThrowsPatternError([&] { Pattern::from_file(p); }, p, 0, 0,
                                 "pattern file '" + p + "' is larger than the 128 MiB limit"));
  std::filesystem::remove(path);
}

TEST(PatternFromRows, Errors) {
  const std::string s = "<rows>";
  EXPECT_TRUE(ThrowsPatternError([] { Pattern::from_rows({}); }, s, 0, 0,
                                 "empty pattern (no rows or an empty first row)"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{}, {0}});
      },
      s, 0, 0, "empty pattern (no rows or an empty first row)"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}, {0}});
      },
      s, 2, 2, "stitch row 2 has 1 cells, expected 2 like row 1"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}, {0, 1, 1}});
      },
      s, 2, 3, "stitch row 2 has 3 cells, expected 2 like row 1"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}, {1, 4}});
      },
      s, 2, 2, "unknown stitch code 4 (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)"));
  EXPECT_TRUE(
      ThrowsPatternError([] { Pattern::from_rows({{-1}}); }, s, 1, 1,
                         "unknown stitch code -1 (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0}, {1}}, {{0}});
      },
      s, 2, 1, "colour matrix has 1 rows, expected 2 like the pattern"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0}}, {{0}, {1}});
      },
      s, 2, 1, "colour matrix has 2 rows, expected 1 like the pattern"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}}, {{0}});
      },
      s, 1, 2, "colour row 1 has 1 cells, expected 2 like row 1"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}}, {{0, 256}});
      },
      s, 1, 2, "colour index 256 out of range 0..255"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern::from_rows({{0, 1}}, {{-3, 0}});
      },
      s, 1, 1, "colour index -3 out of range 0..255"));
}

TEST(PatternFromRows, Limits) {
  const std::string s = "<rows>";
  std::vector<std::vector<int>> tall(4096, std::vector<int>{1});
  EXPECT_EQ(Pattern::from_rows(tall).rows(), 4096);
  tall.push_back({1});
  EXPECT_TRUE(ThrowsPatternError([&] { Pattern::from_rows(tall); }, s, 4097, 1,
                                 "more than 4096 rows (the limit)"));
  std::vector<std::vector<int>> wide{std::vector<int>(4096, 2)};
  EXPECT_EQ(Pattern::from_rows(wide).cols(), 4096);
  wide[0].push_back(2);
  EXPECT_TRUE(ThrowsPatternError([&] { Pattern::from_rows(wide); }, s, 1, 4097,
                                 "more than 4096 columns (the limit)"));
}

TEST(PatternConstructor, Errors) {
  const std::string s = "<pattern>";
  EXPECT_TRUE(ThrowsPatternError([] { Pattern(0, 3, {}); }, s, 0, 0, "empty pattern (0x3)"));
  EXPECT_TRUE(ThrowsPatternError([] { Pattern(2, -1, {}); }, s, 0, 0, "empty pattern (2x-1)"));
  EXPECT_TRUE(ThrowsPatternError([] { Pattern(4097, 1, std::vector<int32_t>(4097, 0)); }, s, 0, 0,
                                 "pattern has 4097 rows, more than 4096 (the limit)"));
  EXPECT_TRUE(ThrowsPatternError([] { Pattern(1, 4097, std::vector<int32_t>(4097, 0)); }, s, 0, 0,
                                 "pattern has 4097 columns, more than 4096 (the limit)"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern(2, 2, {0, 1, 2});
      },
      s, 0, 0, "code array has 3 entries, expected 4 for a 2x2 pattern"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern(1, 2, {0, 1}, {0});
      },
      s, 0, 0, "colour array has 1 entries, expected 2 for a 1x2 pattern"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern(2, 2, {0, 1, 2, 9});
      },
      s, 2, 2, "unknown stitch code 9 (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)"));
  EXPECT_TRUE(ThrowsPatternError(
      [] {
        Pattern(1, 2, {0, 1}, {0, 300});
      },
      s, 1, 2, "colour index 300 out of range 0..255"));
}

}  // namespace
