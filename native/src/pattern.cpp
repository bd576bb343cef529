// knit::Pattern as a value: construction, validation, cell access, the
// canonical text form and equality. Text parsing lives in pattern_parse.cpp.
#include "knit/pattern.h"

#include <algorithm>
#include <cstddef>
#include <string>
#include <utility>

namespace knit {

namespace {

std::string shape(int rows, int cols) { return std::to_string(rows) + "x" + std::to_string(cols); }

// Checks rows/cols against the limits and that `n` values fill the matrix.
void check_shape(const std::string& source, int rows, int cols, size_t n, const char* what) {
  if (rows < 1 || cols < 1) {
    throw PatternError(source, 0, 0, "empty pattern (" + shape(rows, cols) + ")");
  }
  if (rows > Pattern::kMaxRows) {
    throw PatternError(source, 0, 0,
                       "pattern has " + std::to_string(rows) + " rows, more than " +
                           std::to_string(Pattern::kMaxRows) + " (the limit)");
  }
  if (cols > Pattern::kMaxCols) {
    throw PatternError(source, 0, 0,
                       "pattern has " + std::to_string(cols) + " columns, more than " +
                           std::to_string(Pattern::kMaxCols) + " (the limit)");
  }
  size_t cells = static_cast<size_t>(rows) * static_cast<size_t>(cols);
  if (n != cells) {
    throw PatternError(source, 0, 0,
                       std::string(what) + " has " + std::to_string(n) + " entries, expected " +
                           std::to_string(cells) + " for a " + shape(rows, cols) + " pattern");
  }
}

// Checks every value of a row-major matrix; errors name row and column
// (1-based, as line and column).
void check_values(const std::string& source, int cols, const std::vector<int32_t>& v, bool colour) {
  for (size_t i = 0; i < v.size(); ++i) {
    int32_t x = v[i];
    bool ok = colour ? (x >= 0 && x < Pattern::kMaxColors) : (x >= 0 && x <= 3);
    if (ok) continue;
    int line = static_cast<int>(i / static_cast<size_t>(cols)) + 1;
    int column = static_cast<int>(i % static_cast<size_t>(cols)) + 1;
    if (colour) {
      throw PatternError(source, line, column,
                         "colour index " + std::to_string(x) + " out of range 0.." +
                             std::to_string(Pattern::kMaxColors - 1));
    }
    throw PatternError(source, line, column,
                       "unknown stitch code " + std::to_string(x) +
                           " (expected 0-3: 0 knit, 1 purl, 2 front, 3 back)");
  }
}

// Appends one row of `src` to `out`, checking its length against `cols`.
void append_row(const std::string& source, const std::vector<int>& src, size_t r, size_t cols,
                const char* what, std::vector<int32_t>& out) {
  if (src.size() != cols) {
    int column = static_cast<int>(std::min(src.size(), cols)) + 1;
    throw PatternError(source, static_cast<int>(r) + 1, column,
                       std::string(what) + " row " + std::to_string(r + 1) + " has " +
                           std::to_string(src.size()) + " cells, expected " + std::to_string(cols) +
                           " like row 1");
  }
  for (int x : src) out.push_back(static_cast<int32_t>(x));
}

}  // namespace

// "src:3:5: message", or "src: message" for the whole source (line 0)
static std::string pattern_error_text(const std::string& source, int line, int column, const std::string& message) {
  std::string at = source;
  if (line > 0) at += ":" + std::to_string(line) + (column > 0 ? ":" + std::to_string(column) : std::string());
  return at + ": " + message;
}

PatternError::PatternError(std::string source, int line, int column, const std::string& message)
    : std::runtime_error(pattern_error_text(source, line, column, message)),
      source_(std::move(source)),
      line_(line),
      column_(column),
      message_(message) {}

Pattern::Pattern() : codes_{0}, colors_zero_{0} {}

Pattern::Pattern(int rows, int cols, std::vector<int32_t> codes, std::vector<int32_t> colors) {
  const std::string source = "<pattern>";
  check_shape(source, rows, cols, codes.size(), "code array");
  if (!colors.empty()) check_shape(source, rows, cols, colors.size(), "colour array");
  check_values(source, cols, codes, false);
  check_values(source, cols, colors, true);
  rows_ = rows;
  cols_ = cols;
  codes_ = std::move(codes);
  colors_ = std::move(colors);
  colors_zero_ = colors_.empty() ? std::vector<int32_t>(codes_.size(), 0) : colors_;
}

Pattern Pattern::from_rows(const std::vector<std::vector<int>>& codes,
                           const std::vector<std::vector<int>>& colors) {
  const std::string source = "<rows>";
  if (codes.empty() || codes[0].empty()) {
    throw PatternError(source, 0, 0, "empty pattern (no rows or an empty first row)");
  }
  if (codes.size() > static_cast<size_t>(kMaxRows)) {
    throw PatternError(source, kMaxRows + 1, 1,
                       "more than " + std::to_string(kMaxRows) + " rows (the limit)");
  }
  if (codes[0].size() > static_cast<size_t>(kMaxCols)) {
    throw PatternError(source, 1, kMaxCols + 1,
                       "more than " + std::to_string(kMaxCols) + " columns (the limit)");
  }
  const size_t cols = codes[0].size();
  std::vector<int32_t> flat_codes, flat_colors;
  flat_codes.reserve(codes.size() * cols);
  for (size_t r = 0; r < codes.size(); ++r)
    append_row(source, codes[r], r, cols, "stitch", flat_codes);
  if (!colors.empty()) {
    if (colors.size() != codes.size()) {
      int line = static_cast<int>(std::min(colors.size(), codes.size())) + 1;
      throw PatternError(source, line, 1,
                         "colour matrix has " + std::to_string(colors.size()) + " rows, expected " +
                             std::to_string(codes.size()) + " like the pattern");
    }
    flat_colors.reserve(flat_codes.size());
    for (size_t r = 0; r < colors.size(); ++r) {
      append_row(source, colors[r], r, cols, "colour", flat_colors);
    }
  }
  const int rows = static_cast<int>(codes.size());
  check_values(source, static_cast<int>(cols), flat_codes, false);
  check_values(source, static_cast<int>(cols), flat_colors, true);
  return Pattern(rows, static_cast<int>(cols), std::move(flat_codes), std::move(flat_colors));
}

Stitch Pattern::stitch(int row, int col) const {
  if (row < 0 || row >= rows_ || col < 0 || col >= cols_) {
    throw std::out_of_range("Pattern: cell (" + std::to_string(row) + ", " + std::to_string(col) +
                            ") outside the " + shape(rows_, cols_) + " pattern");
  }
  return static_cast<Stitch>(codes_[static_cast<size_t>(row) * cols_ + col]);
}

int Pattern::color(int row, int col) const {
  stitch(row, col);  // bounds check
  return colors_zero_[static_cast<size_t>(row) * cols_ + col];
}

int Pattern::num_colors() const {
  if (colors_.empty()) return 1;
  return 1 + *std::max_element(colors_.begin(), colors_.end());
}

bool Pattern::uses(Stitch s) const {
  return std::find(codes_.begin(), codes_.end(), static_cast<int32_t>(s)) != codes_.end();
}

std::string Pattern::to_text() const {
  static const char kLetters[4] = {'K', 'P', 'F', 'B'};
  std::string out;
  out.reserve(codes_.size() * (colors_.empty() ? 2 : 6) + 16);
  for (int r = 0; r < rows_; ++r) {
    for (int c = 0; c < cols_; ++c) {
      if (c) out += ' ';
      out += kLetters[codes_[static_cast<size_t>(r) * cols_ + c]];
    }
    out += '\n';
  }
  if (colors_.empty()) return out;
  out += "colors:\n";
  for (int r = 0; r < rows_; ++r) {
    for (int c = 0; c < cols_; ++c) {
      if (c) out += ' ';
      out += std::to_string(colors_[static_cast<size_t>(r) * cols_ + c]);
    }
    out += '\n';
  }
  return out;
}

bool Pattern::operator==(const Pattern& o) const {
  return rows_ == o.rows_ && cols_ == o.cols_ && codes_ == o.codes_ && colors_ == o.colors_;
}

}  // namespace knit
