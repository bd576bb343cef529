// The `knitshade` Python module. Each area binds itself in its own file.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "knit/version.h"

PYBIND11_MODULE(knitshade, m) {
  m.doc() = "Knitshade: texture-free knitted-fabric model (patterns, stitch geometry, "
            "analytic queries, CAPM, yarn BSDF).";
  m.attr("__version__") = knit::version();
  knit::py::bind_pattern(m);
  knit::py::bind_geometry(m);
  knit::py::bind_appearance(m);
}
