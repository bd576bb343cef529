// One function per area of the Python module, each in bind_<area>.cpp.
#pragma once
#include <pybind11/pybind11.h>

#include <cstdio>
#include <string>

namespace knit::py {

// A number in an error message or repr: "%.6g" (1e+08, 0.5, nan).
inline std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

void bind_pattern(pybind11::module_& m);     // bind_pattern.cpp
void bind_geometry(pybind11::module_& m);    // bind_geometry.cpp
void bind_appearance(pybind11::module_& m);  // bind_appearance.cpp
}  // namespace knit::py
