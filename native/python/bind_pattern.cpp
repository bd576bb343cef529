// knitshade.Pattern and knitshade.PatternError (docs/patterns.md, "Python").
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <climits>
#include <string>
#include <vector>

#include "bindings.h"
#include "knit/osl_source.h"
#include "knit/pattern.h"

namespace pb = pybind11;

namespace {

using knit::Pattern;
using knit::PatternError;

// The Python exception type; created once per process with the module, never freed.
pb::object* g_pattern_error = nullptr;

void translate(std::exception_ptr p) {
  try {
    if (p) std::rethrow_exception(p);
  } catch (const PatternError& e) {
    pb::object err = (*g_pattern_error)(e.what());
    err.attr("source") = e.source();
    err.attr("line") = e.line();
    err.attr("column") = e.column();
    err.attr("message") = e.message();
    PyErr_SetObject(g_pattern_error->ptr(), err.ptr());
  }
}

// An integer cell of a nested sequence, clamped to int so that values out of
// range still reach the validator (and its positioned error).
int cell_value(pb::handle cell, size_t r, size_t c, const char* what) {
  if (!PyIndex_Check(cell.ptr())) {
    throw pb::type_error(std::string(what) + " row " + std::to_string(r + 1) + ", column " +
                         std::to_string(c + 1) + ": expected an integer, got " +
                         std::string(pb::str(pb::type::handle_of(cell).attr("__name__"))));
  }
  pb::object index = pb::reinterpret_steal<pb::object>(PyNumber_Index(cell.ptr()));
  if (!index) throw pb::error_already_set();
  int overflow = 0;
  long long v = PyLong_AsLongLongAndOverflow(index.ptr(), &overflow);
  if (overflow != 0) return overflow > 0 ? INT_MAX : INT_MIN;
  if (v == -1 && PyErr_Occurred()) throw pb::error_already_set();
  return v > INT_MAX ? INT_MAX : v < INT_MIN ? INT_MIN : static_cast<int>(v);
}

bool is_row_sequence(pb::handle h) {
  return pb::isinstance<pb::sequence>(h) && !pb::isinstance<pb::str>(h) &&
         !pb::isinstance<pb::bytes>(h);
}

// A list of lists (or any sequence of sequences, e.g. a 2-D numpy array).
std::vector<std::vector<int>> to_matrix(pb::handle obj, const char* what) {
  if (!is_row_sequence(obj)) {
    throw pb::type_error(std::string(what) + ": expected a sequence of rows (a list of lists)");
  }
  std::vector<std::vector<int>> out;
  size_t r = 0;
  for (pb::handle row : obj) {
    if (!is_row_sequence(row)) {
      throw pb::type_error(std::string(what) + " row " + std::to_string(r + 1) +
                           ": expected a sequence of integers");
    }
    std::vector<int> cells;
    size_t c = 0;
    for (pb::handle cell : row) cells.push_back(cell_value(cell, r, c++, what));
    out.push_back(std::move(cells));
    ++r;
  }
  return out;
}

pb::array_t<int32_t> to_array(const Pattern& p, const std::vector<int32_t>& v) {
  pb::array_t<int32_t> a({p.rows(), p.cols()});
  std::copy(v.begin(), v.end(), a.mutable_data());
  return a;
}

std::string repr(const Pattern& p) {
  std::string s = "<knitshade.Pattern " + std::to_string(p.rows()) + "x" + std::to_string(p.cols());
  if (!p.has_colors()) return s + " without colors>";
  return s + " with " + std::to_string(p.num_colors()) + " colors>";
}

}  // namespace

namespace knit::py {

void bind_pattern(pb::module_& m) {
  auto* exc = new pb::exception<PatternError>(m, "PatternError", PyExc_ValueError);
  exc->doc() =
      "A pattern that does not parse or validate. str(e) is "
      "'source:line:column: message'; attributes source, line, column "
      "(1-based, 0 when not tied to a position) and message.";
  exc->attr("source") = pb::none();
  exc->attr("line") = 0;
  exc->attr("column") = 0;
  exc->attr("message") = "";
  g_pattern_error = exc;
  pb::register_exception_translator(&translate);

  pb::class_<Pattern> cls(m, "Pattern",
                          "A knit pattern: a matrix of stitch codes (0 knit K, 1 purl P, 2 front "
                          "slip F, 3 back slip B) with an optional colour-index matrix.");
  cls.attr("MAX_ROWS") = Pattern::kMaxRows;
  cls.attr("MAX_COLS") = Pattern::kMaxCols;
  cls.attr("MAX_COLORS") = Pattern::kMaxColors;
  cls.def(pb::init<>(), "A 1x1 knit pattern.")
      .def_static(
          "from_text",
          [](const std::string& text, const std::string& source) {
            return Pattern::parse(text, source);
          },
          pb::arg("text"), pb::arg("source") = "<string>", pb::call_guard<pb::gil_scoped_release>(),
          "Parses the pattern text format; errors name `source`, line and column.")
      .def_static(
          "from_rows",
          [](pb::handle rows, pb::handle colors) {
            std::vector<std::vector<int>> codes = to_matrix(rows, "stitch");
            std::vector<std::vector<int>> cols;
            if (!colors.is_none()) cols = to_matrix(colors, "colour");
            return Pattern::from_rows(codes, cols);
          },
          pb::arg("rows"), pb::arg("colors") = pb::none(),
          "From a list of rows of integer codes and an optional list of rows of colour indices.")
      .def_static(
          "from_file",
          [](pb::handle path) {
            std::string p = pb::str(pb::module_::import("os").attr("fsdecode")(path));
            pb::gil_scoped_release release;
            return Pattern::from_file(p);
          },
          pb::arg("path"), "Reads a pattern file (str or os.PathLike).")
      .def_property_readonly("rows", &Pattern::rows)
      .def_property_readonly("cols", &Pattern::cols)
      .def_property_readonly("has_colors", &Pattern::has_colors)
      .def_property_readonly("num_colors", &Pattern::num_colors,
                             "1 + the largest colour index (1 without a colour matrix).")
      .def("stitch", &Pattern::code, pb::arg("row"), pb::arg("col"),
           "The stitch code (0-3) of a cell; IndexError outside the pattern.")
      .def("color", &Pattern::color, pb::arg("row"), pb::arg("col"),
           "The colour index of a cell (0 without a colour matrix).")
      .def("to_text", &Pattern::to_text, "The canonical text form.")
      .def(
          "codes", [](const Pattern& p) { return to_array(p, p.codes()); },
          "Stitch codes as an int32 array of shape (rows, cols).")
      .def(
          "colors", [](const Pattern& p) { return to_array(p, p.colors_or_zero()); },
          "Colour indices as an int32 array of shape (rows, cols); zeros without colors.")
      .def("__eq__",
           [](const Pattern& a, pb::handle b) -> pb::object {
             if (!pb::isinstance<Pattern>(b))
               return pb::reinterpret_borrow<pb::object>(Py_NotImplemented);
             return pb::bool_(a == b.cast<const Pattern&>());
           })
      .def("__repr__", &repr)
      .def(pb::pickle([](const Pattern& p) { return p.to_text(); },
                      [](const std::string& text) { return Pattern::parse(text, "<pickle>"); }));
  m.def("osl_source", &osl_source, pb::arg("pattern"), R"doc(
The knit shader for Cycles (OSL) with `pattern` compiled in: one
self-contained text (the shared kernel inlined, no #include), the same bytes
for the same pattern; every other setting is a shader parameter
(docs/shader.md). Raises ValueError for a pattern over 256 x 256 stitches or
with a colour index over 7 (the shader's palette).)doc");
}

}  // namespace knit::py
