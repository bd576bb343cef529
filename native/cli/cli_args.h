// Small helpers shared by the subcommands for strict option parsing.
#pragma once

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

#include "cli.h"

namespace knit::cli {

// The value after option `args[i]`; advances i. Throws UsageError when missing.
inline const std::string& option_value(const std::vector<std::string>& args, size_t& i) {
  if (i + 1 >= args.size()) throw UsageError{"option " + args[i] + " needs a value"};
  return args[++i];
}

// A whole decimal integer in [lo, hi]; UsageError naming the option otherwise.
inline int64_t parse_int_option(const std::string& opt, const std::string& text, int64_t lo, int64_t hi) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || errno != 0 || end == nullptr || *end != '\0' || v < lo || v > hi)
    throw UsageError{opt + " needs an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                     "], got '" + text + "'"};
  return static_cast<int64_t>(v);
}

// "WxH": two whole decimal integers in [lo, hi]; UsageError naming the
// option and the value otherwise.
struct SizeOption {
  int width = 0, height = 0;
};
inline SizeOption parse_size_option(const std::string& opt, const std::string& text, int64_t lo, int64_t hi) {
  const UsageError bad{opt + " needs WxH, W and H integers in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                       "], got '" + text + "'"};
  const size_t x = text.find('x');
  if (x == std::string::npos) throw bad;
  SizeOption s;
  try {
    s.width = static_cast<int>(parse_int_option(opt, text.substr(0, x), lo, hi));
    s.height = static_cast<int>(parse_int_option(opt, text.substr(x + 1), lo, hi));
  } catch (const UsageError&) {
    throw bad;
  }
  return s;
}

}  // namespace knit::cli
