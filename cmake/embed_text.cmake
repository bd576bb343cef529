# cmake -DIN=<text file> -DOUT=<.cpp> -DNAMESPACE=<ns> -DFUNCTION=<name> -P embed_text.cmake
# Writes a C++ source defining `const std::string& NAMESPACE::FUNCTION()`
# that returns the file's bytes (a raw string literal, in pieces that stay
# below the compilers' literal length limits).
file(READ "${IN}" text)
string(FIND "${text}" ")knit_embed\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${IN} contains the raw string delimiter )knit_embed\"")
endif()
string(LENGTH "${text}" len)
set(body "")
set(pos 0)
set(piece 16000)
while(pos LESS len)
  string(SUBSTRING "${text}" ${pos} ${piece} chunk)
  string(APPEND body "    R\"knit_embed(${chunk})knit_embed\",\n")
  math(EXPR pos "${pos} + ${piece}")
endwhile()
set(out "// Generated from ${IN} by cmake/embed_text.cmake; do not edit.
#include <string>

namespace ${NAMESPACE} {

const std::string& ${FUNCTION}() {
  static const char* const pieces[] = {
${body}  };
  static const std::string text = [] {
    std::string s;
    for (const char* p : pieces) s += p;
    return s;
  }();
  return text;
}

}  // namespace ${NAMESPACE}
")
if(EXISTS "${OUT}")
  file(READ "${OUT}" old)
  if(old STREQUAL out)
    return()
  endif()
endif()
file(WRITE "${OUT}" "${out}")
