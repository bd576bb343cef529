// One function per area of the Python module, each in bind_<area>.cpp.
#pragma once
#include <pybind11/pybind11.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdio>
#include <exception>
#include <mutex>
#include <string>

namespace knit::py {

// A number in an error message or repr: "%.6g" (1e+08, 0.5, nan).
inline std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Runs body(begin, end) over ranges covering [0, n) with the GIL released:
// on every core (TBB, ranges of about `grain` rows) from kParallelRows rows
// up, in the calling thread (one range) below that. Each body writes only
// its rows of the outputs through raw pointers taken with the GIL held. A
// C++ exception (which the validation at the boundary should have made
// impossible) surfaces as ValueError once all ranges are done.
constexpr pybind11::ssize_t kParallelRows = 1024;
template <class F>
void for_each_range(pybind11::ssize_t n, pybind11::ssize_t grain, F&& body) {
  std::string error;
  std::mutex error_mutex;
  auto rows = [&](pybind11::ssize_t begin, pybind11::ssize_t end) {
    try {
      body(begin, end);
    } catch (const std::exception& e) {
      const std::lock_guard<std::mutex> lock(error_mutex);
      if (error.empty()) error = e.what();
    }
  };
  {
    pybind11::gil_scoped_release nogil;
    if (n < kParallelRows) {
      rows(0, n);
    } else {
      tbb::parallel_for(tbb::blocked_range<pybind11::ssize_t>(0, n, grain),
                        [&](const tbb::blocked_range<pybind11::ssize_t>& r) { rows(r.begin(), r.end()); });
    }
  }
  if (!error.empty()) throw pybind11::value_error(error);
}

// body(i) for every i in [0, n), as for_each_range.
template <class F>
void for_each_row(pybind11::ssize_t n, F&& body) {
  for_each_range(n, 256, [&](pybind11::ssize_t begin, pybind11::ssize_t end) {
    for (pybind11::ssize_t i = begin; i < end; ++i) body(i);
  });
}

void bind_pattern(pybind11::module_& m);     // bind_pattern.cpp
void bind_geometry(pybind11::module_& m);    // bind_geometry.cpp
void bind_appearance(pybind11::module_& m);  // bind_appearance.cpp
}  // namespace knit::py
