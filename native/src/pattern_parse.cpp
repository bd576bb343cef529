// The pattern text format (docs/patterns.md): Pattern::parse and
// Pattern::from_file. Every error names the source, line and column.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "knit/pattern.h"

namespace knit {

namespace {

constexpr size_t kMaxInputBytes = Pattern::kMaxTextBytes;
constexpr size_t kQuoteMax = 24;  // code points quoted from a bad token

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }
bool is_sep(char c) { return is_space(c) || c == ','; }
bool is_cont(unsigned char c) { return (c & 0xC0) == 0x80; }

char lower(char c) { return (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c; }

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (lower(a[i]) != lower(b[i])) return false;
  return true;
}

bool istarts_with(std::string_view s, std::string_view prefix) {
  return s.size() >= prefix.size() && iequals(s.substr(0, prefix.size()), prefix);
}

// Length of the well-formed UTF-8 sequence starting at s[i] (RFC 3629: no
// overlongs, no surrogates, nothing above U+10FFFF), or 0.
size_t utf8_len(std::string_view s, size_t i) {
  auto at = [&](size_t k) { return static_cast<unsigned char>(s[k]); };
  unsigned char c = at(i);
  size_t n = c < 0x80                   ? 1
             : (c >= 0xC2 && c <= 0xDF) ? 2
             : (c >= 0xE0 && c <= 0xEF) ? 3
             : (c >= 0xF0 && c <= 0xF4) ? 4
                                        : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k)
    if (!is_cont(at(i + k))) return 0;
  unsigned char c1 = n > 1 ? at(i + 1) : 0;
  if (c == 0xE0 && c1 < 0xA0) return 0;  // overlong
  if (c == 0xED && c1 > 0x9F) return 0;  // surrogate
  if (c == 0xF0 && c1 < 0x90) return 0;  // overlong
  if (c == 0xF4 && c1 > 0x8F) return 0;  // above U+10FFFF
  return n;
}

// 1-based column, in code points, of byte `off` of `line`.
int column_of(std::string_view line, size_t off) {
  int col = 1;
  for (size_t i = 0; i < off && i < line.size(); ++i)
    if (!is_cont(static_cast<unsigned char>(line[i]))) ++col;
  return col;
}

std::string hex_byte(unsigned char c) {
  static const char kHex[] = "0123456789ABCDEF";
  return std::string("0x") + kHex[c >> 4] + kHex[c & 15];
}

// A token in quotes, cut after kQuoteMax code points.
std::string quote(std::string_view tok) {
  size_t points = 0, end = 0;
  while (end < tok.size()) {
    if (!is_cont(static_cast<unsigned char>(tok[end])) && ++points > kQuoteMax) break;
    ++end;
  }
  return "'" + std::string(tok.substr(0, end)) + (end < tok.size() ? "...'" : "'");
}

int stitch_code(char c) {
  switch (lower(c)) {
    case '0':
    case 'k':
      return 0;
    case '1':
    case 'p':
      return 1;
    case '2':
    case 'f':
      return 2;
    case '3':
    case 'b':
      return 3;
    default:
      return -1;
  }
}

struct Cell {
  size_t off;             // byte offset in the line
  std::string_view text;  // the token (one code point in a compact row)
};

class Parser {
 public:
  Parser(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  Pattern run() {
    if (text_.size() > kMaxInputBytes) {
      throw PatternError(source_, 0, 0,
                         "input is " + std::to_string(text_.size()) + " bytes, more than the " +
                             std::to_string(kMaxInputBytes >> 20) + " MiB limit");
    }
    size_t start = text_.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;  // UTF-8 byte order mark
    check_text(start);
    int line_no = 0;
    while (start <= text_.size()) {
      size_t nl = text_.find('\n', start);
      if (nl == std::string_view::npos) nl = text_.size();
      line_ = text_.substr(start, nl - start);
      line_no_ = ++line_no;
      parse_line();
      start = nl + 1;
    }
    return finish();
  }

 private:
  [[noreturn]] void fail(size_t off, const std::string& message) const {
    throw PatternError(source_, line_no_, column_of(line_, off), message);
  }

  // Rejects input that is not UTF-8 text: NUL, control bytes other than
  // whitespace, malformed sequences.
  void check_text(size_t start) {
    size_t line_start = start;
    line_no_ = 1;
    for (size_t i = start; i < text_.size();) {
      unsigned char c = static_cast<unsigned char>(text_[i]);
      size_t n = utf8_len(text_, i);
      std::string what;
      if (c == '\n') {
        ++line_no_;
        line_start = ++i;
        continue;
      } else if (c == 0) {
        what = "NUL byte";
      } else if ((c < 0x20 && !is_space(static_cast<char>(c))) || c == 0x7F) {
        what = "control byte " + hex_byte(c);
      } else if (n == 0) {
        what = "invalid UTF-8 byte " + hex_byte(c);
      }
      if (!what.empty()) {
        size_t eol = text_.find('\n', line_start);
        line_ = text_.substr(line_start, eol == std::string_view::npos ? eol : eol - line_start);
        fail(i - line_start, "input is not text (" + what + ")");
      }
      i += n;
    }
  }

  void parse_line() {
    std::string_view content = line_.substr(0, line_.find('#'));
    size_t b = 0, e = content.size();
    while (b < e && is_space(content[b])) ++b;
    while (e > b && is_space(content[e - 1])) --e;
    if (b == e) return;  // blank or comment only
    std::string_view body = content.substr(b, e - b);
    if (istarts_with(body, "colors:") || istarts_with(body, "colours:")) {
      size_t len = lower(body[4]) == 'u' ? 8 : 7;
      if (body.size() > len) {
        fail(b + len, "unexpected text after '" + std::string(body.substr(0, len)) +
                          "' (the colour matrix starts on the next line)");
      }
      start_colors(b);
      return;
    }
    split(body, b);
    if (in_colors_) {
      colour_row();
    } else {
      pattern_row();
    }
  }

  void start_colors(size_t off) {
    if (in_colors_)
      fail(off,
           "second colour section (the first is at line " + std::to_string(colors_line_) + ")");
    if (rows_ == 0) fail(off, "colour section without a pattern (no stitch rows before it)");
    in_colors_ = true;
    colors_line_ = line_no_;
  }

  // Splits a non-empty row body (at byte `base` of the line) into cells.
  void split(std::string_view body, size_t base) {
    cells_.clear();
    bool separated = false;
    for (char c : body) separated = separated || is_sep(c);
    // One column: a colour row without separators is one index, not digits.
    bool one_token = in_colors_ && cols_ == 1;
    size_t i = 0;
    while (i < body.size()) {
      size_t start = i;
      if (separated || one_token) {
        if (body[i] == ',') fail(base + i, "empty cell (a comma with no cell before it)");
        while (i < body.size() && !is_sep(body[i])) ++i;
        size_t commas = 0;
        for (; i < body.size() && is_sep(body[i]); ++i) {
          if (body[i] == ',' && ++commas > 1) fail(base + i, "empty cell (two commas in a row)");
        }
      } else {
        i += utf8_len(body, i);  // text already checked: never 0
      }
      if (cells_.size() == static_cast<size_t>(Pattern::kMaxCols)) {
        fail(base + start,
             "row has more than " + std::to_string(Pattern::kMaxCols) + " cells (the limit)");
      }
      size_t end = start;
      while (end < i && !is_sep(body[end])) ++end;
      cells_.push_back({base + start, body.substr(start, end - start)});
    }
  }

  // Fails unless the row has `cols_` cells; `what` names the row's kind.
  void check_count(const std::string& what, const std::string& like) const {
    size_t n = cells_.size(), want = static_cast<size_t>(cols_);
    if (n == want) return;
    size_t off = n > want ? cells_[want].off : cells_.back().off + cells_.back().text.size();
    fail(off, what + " has " + std::to_string(n) + " cells, expected " + std::to_string(want) +
                  " " + like);
  }

  void pattern_row() {
    if (rows_ == Pattern::kMaxRows) {
      fail(cells_[0].off, "more than " + std::to_string(Pattern::kMaxRows) + " rows (the limit)");
    }
    if (rows_ == 0) {
      cols_ = static_cast<int>(cells_.size());
      first_line_ = line_no_;
    }
    check_count("row", "like the first row (line " + std::to_string(first_line_) + ")");
    for (const Cell& cell : cells_) {
      int code = cell.text.size() == 1 ? stitch_code(cell.text[0]) : -1;
      if (code < 0) {
        fail(cell.off, "unknown stitch code " + quote(cell.text) + " (expected 0-3 or K, P, F, B)");
      }
      codes_.push_back(code);
    }
    ++rows_;
  }

  void colour_row() {
    if (color_rows_ == rows_) {
      fail(cells_[0].off,
           "colour matrix has more rows than the pattern (" + std::to_string(rows_) + ")");
    }
    check_count("colour row", "like the pattern");
    for (const Cell& cell : cells_) colors_.push_back(colour_index(cell));
    ++color_rows_;
  }

  int32_t colour_index(const Cell& cell) const {
    std::string_view t = cell.text;
    size_t i = (t[0] == '+' || t[0] == '-') ? 1 : 0;
    bool digits = i < t.size();
    long value = 0;
    for (size_t k = i; k < t.size() && digits; ++k) {
      digits = t[k] >= '0' && t[k] <= '9';
      if (digits && value < 100000) value = value * 10 + (t[k] - '0');
    }
    if (!digits) fail(cell.off, "colour index " + quote(t) + " is not an integer");
    if (t[0] == '-') value = -value;
    if (value < 0 || value >= Pattern::kMaxColors) {
      fail(cell.off, "colour index " + quote(t) + " out of range 0.." +
                         std::to_string(Pattern::kMaxColors - 1));
    }
    return static_cast<int32_t>(value);
  }

  Pattern finish() {
    if (rows_ == 0) throw PatternError(source_, 0, 0, "empty pattern (no stitch rows)");
    if (in_colors_ && color_rows_ != rows_) {
      throw PatternError(source_, colors_line_, 1,
                         "colour matrix has " + std::to_string(color_rows_) + " rows, expected " +
                             std::to_string(rows_) + " like the pattern");
    }
    return Pattern(rows_, cols_, std::move(codes_), std::move(colors_));
  }

  std::string_view text_;
  const std::string& source_;
  std::string_view line_;  // the current line, without its '\n'
  int line_no_ = 0;
  std::vector<Cell> cells_;
  int rows_ = 0, cols_ = 0, first_line_ = 0;
  bool in_colors_ = false;
  int colors_line_ = 0, color_rows_ = 0;
  std::vector<int32_t> codes_, colors_;
};

}  // namespace

Pattern Pattern::parse(std::string_view text, const std::string& source) {
  return Parser(text, source).run();
}

Pattern Pattern::from_file(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) {
    int err = errno;
    throw PatternError(path, 0, 0,
                       "cannot open pattern file '" + path + "': " + std::strerror(err));
  }
  std::string data;
  char buf[1 << 16];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) {
    data.append(buf, n);
    if (data.size() > kMaxInputBytes) {
      std::fclose(f);
      throw PatternError(path, 0, 0,
                         "pattern file '" + path + "' is larger than the " +
                             std::to_string(kMaxInputBytes >> 20) + " MiB limit");
    }
  }
  int err = std::ferror(f) ? errno : 0;
  std::fclose(f);
  if (err != 0) {
    throw PatternError(path, 0, 0,
                       "cannot read pattern file '" + path + "': " + std::strerror(err));
  }
  return parse(data, path);
}

}  // namespace knit
