// Knit patterns: a rectangular matrix of stitch codes with an optional matrix
// of colour indices of the same shape.
//
// Conventions (docs/patterns.md): row 0 is the top row as written in the file;
// codes follow the paper's Table 1: 0 knit (K), 1 purl (P), 2 front slip
// stitch (F, float in front), 3 back slip stitch (B, float behind).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace knit {

enum class Stitch : int32_t { Knit = 0, Purl = 1, Front = 2, Back = 3 };

// A parse or validation error that names where the input went wrong.
// what() reads "<source>:<line>:<column>: <message>" (line/column 1-based),
// or "<source>: <message>" when the error is not tied to a position (line
// and column 0).
class PatternError : public std::runtime_error {
 public:
  PatternError(std::string source, int line, int column, const std::string& message);
  const std::string& source() const { return source_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& message() const { return message_; }

 private:
  std::string source_;
  int line_;
  int column_;
  std::string message_;
};

class Pattern {
 public:
  static constexpr int kMaxRows = 4096;
  static constexpr int kMaxCols = 4096;
  static constexpr int kMaxColors = 256;
  // Largest text parse() and from_file() accept: room for the canonical text
  // of a kMaxRows x kMaxCols pattern with three-digit colours (~96 MiB).
  static constexpr std::size_t kMaxTextBytes = std::size_t(128) << 20;

  // A 1x1 knit pattern.
  Pattern();

  // Validates shape, codes (0..3) and colour indices (0..kMaxColors-1).
  // `colors` may be empty (every cell colour 0). Throws PatternError.
  Pattern(int rows, int cols, std::vector<int32_t> codes, std::vector<int32_t> colors = {});

  // Text format (docs/patterns.md): one pattern row per line; cells are digits
  // 0-3 or letters K P F B (any case), separated by whitespace or commas, or
  // written one character per cell with no separators. '#' starts a comment.
  // An optional colour matrix follows a line `colors:` (same shape, integer
  // indices). Throws PatternError naming `source`, line and column.
  static Pattern parse(std::string_view text, const std::string& source = "<string>");
  static Pattern from_file(const std::string& path);
  static Pattern from_rows(const std::vector<std::vector<int>>& codes,
                           const std::vector<std::vector<int>>& colors = {});

  int rows() const { return rows_; }
  int cols() const { return cols_; }
  Stitch stitch(int row, int col) const;  // bounds-checked, throws std::out_of_range
  int code(int row, int col) const { return static_cast<int>(stitch(row, col)); }
  int color(int row, int col) const;      // bounds-checked
  bool has_colors() const { return !colors_.empty(); }
  int num_colors() const;                 // 1 + largest colour index
  bool uses(Stitch s) const;              // any cell with this code

  // Canonical text form; parse(to_text()) == *this.
  std::string to_text() const;

  // Row-major, row 0 first, one int32 per cell: the arrays the kernel reads.
  const std::vector<int32_t>& codes() const { return codes_; }
  // Same layout; all zeros when the pattern has no colour matrix.
  const std::vector<int32_t>& colors_or_zero() const { return colors_zero_; }

  bool operator==(const Pattern& o) const;
  bool operator!=(const Pattern& o) const { return !(*this == o); }

 private:
  int rows_ = 1;
  int cols_ = 1;
  std::vector<int32_t> codes_;
  std::vector<int32_t> colors_;       // empty when no colour matrix was given
  std::vector<int32_t> colors_zero_;  // colors_ or zeros
};

}  // namespace knit
