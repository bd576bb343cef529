// One function per area of the Python module, each in bind_<area>.cpp.
#pragma once
#include <pybind11/pybind11.h>

namespace knit::py {
void bind_pattern(pybind11::module_& m);     // bind_pattern.cpp
void bind_geometry(pybind11::module_& m);    // bind_geometry.cpp
void bind_appearance(pybind11::module_& m);  // bind_appearance.cpp
}  // namespace knit::py
