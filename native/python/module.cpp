// The `knitshade` Python module. Each area binds itself in its own file.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "knit/table_cache.h"
#include "knit/version.h"

PYBIND11_MODULE(knitshade, m) {
  m.doc() = "Knitshade: texture-free knitted-fabric model (patterns, stitch geometry, "
            "analytic queries, CAPM, yarn BSDF).";
  m.attr("__version__") = knit::version();
  knit::py::bind_pattern(m);
  knit::py::bind_geometry(m);
  knit::py::bind_appearance(m);

  m.def(
      "set_table_cache",
      [](pybind11::object dir, uint64_t max_bytes) {
        knit::TableCacheSettings s;
        if (!dir.is_none()) {
          s.dir = pybind11::str(pybind11::module_::import("os").attr("fspath")(dir));
          if (s.dir.empty()) throw pybind11::value_error("set_table_cache: empty folder name (None turns the cache off)");
        }
        if (max_bytes == 0) throw pybind11::value_error("set_table_cache: max_bytes must be > 0");
        s.max_bytes = max_bytes;
        knit::set_table_cache(s);
      },
      pybind11::arg("dir"), pybind11::arg("max_bytes") = uint64_t(512) << 20, R"doc(
Keep the class tables of multi-scale materials made from now on in folder
`dir` (str or path; None: no cache, the default), and find them there
again: a material whose pattern and parameters match an entry written by
this same build of knitshade reads its tables instead of building them
(KnitMaterial.table_from_cache), bit for bit the built ones. After each
write the folder's entries are trimmed to max_bytes, least recently used
first. knitshade.writable_table_cache_dir() is the CLI's folder.)doc");
  m.def(
      "table_cache",
      []() -> pybind11::object {
        const knit::TableCacheSettings s = knit::table_cache();
        if (s.dir.empty()) return pybind11::none();
        return pybind11::str(s.dir);
      },
      "The class-table cache's folder, or None when it is off.");
  m.def("default_table_cache_dir", &knit::default_table_cache_dir, R"doc(
The preferred class-table cache folder: $KNITSHADE_CACHE_DIR ("off": none,
returned as ""), else $XDG_CACHE_HOME/knitshade, else ~/.cache/knitshade (the
CLI's, unless it cannot be written: writable_table_cache_dir).)doc");
  m.def("writable_table_cache_dir", &knit::writable_table_cache_dir, R"doc(
The folder the CLI uses when none is given: default_table_cache_dir(), or where
that is under $XDG_CACHE_HOME or $HOME and cannot be written (a read-only home),
a folder of this user's own under $TMPDIR (else /tmp), knitshade-cache-<uid>
("" when that is not the user's own or others can write to it).)doc");
}
