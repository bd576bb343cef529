// Helpers shared by the pattern tests: exact error assertions.
#pragma once

#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <string_view>

#include "knit/pattern.h"

namespace knit_test {

// Succeeds when `f` throws a PatternError whose what() is exactly
// "<source>:<line>:<column>: <message>" ("<source>: <message>" for line 0:
// no position) and whose accessors agree.
inline testing::AssertionResult ThrowsPatternError(const std::function<void()>& f,
                                                   const std::string& source, int line, int column,
                                                   const std::string& message) {
  try {
    f();
  } catch (const knit::PatternError& e) {
    const std::string want =
        (line == 0 ? source : source + ":" + std::to_string(line) + ":" + std::to_string(column)) + ": " + message;
    if (want == e.what() && e.source() == source && e.line() == line && e.column() == column &&
        e.message() == message) {
      return testing::AssertionSuccess();
    }
    return testing::AssertionFailure()
           << "got      \"" << e.what() << "\"\nexpected \"" << want << "\"";
  } catch (const std::exception& e) {
    return testing::AssertionFailure() << "threw another exception: " << e.what();
  }
  return testing::AssertionFailure() << "did not throw";
}

// Parsing `text` (source "t.knit") fails at line:column with `message`.
inline testing::AssertionResult ParseFails(std::string_view text, int line, int column,
                                           const std::string& message) {
  return ThrowsPatternError([&] { knit::Pattern::parse(text, "t.knit"); }, "t.knit", line, column,
                            message);
}

}  // namespace knit_test
