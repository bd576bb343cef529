// The class-table cache: multi-scale materials keep their class table and
// tabulated BSDF (FootprintTable, TableBsdf) on disk between runs, so that
// the second render of a scene does not build them again (about 0.4-1.6 s
// per material on 2 cores, docs/multiscale.md, "The class-table cache").
//
// A material has three entries, one per stage of the build (TableBsdf::
// Stage): its shadows, its marches and its finished tables, so that a
// material cached in other colours is only finished, and one cached with
// other yarn parameters reuses the shadows. An entry is found by a key made of everything
// its stage reads: the pattern, the material parameters that stage reads
// (table_cache.cpp, put_key, names those it leaves out), the build's own
// settings, the SIMD path that counts the layers and the GNU build id of
// the binary that holds this code (so an entry never outlives the code that
// wrote it). The key is stored in the entry and compared in full, and a
// checksum covers the whole file: a damaged entry, one of another key or
// an unreadable folder means a build (or finishing the cached marches), as
// if there were no cache, with a note saying why
// (KnitMaterial::table_cache_note), never a failed load. A loaded table is
// the built one to the last bit.
//
// Process-wide and off by default: the CLI turns it on (its --cache-dir and
// --no-cache; default_table_cache_dir()), the Python module through
// knitshade.set_table_cache.
#pragma once

#include <cstdint>
#include <string>

namespace knit {

struct TableCacheSettings {
  std::string dir;                         // the entries' folder; empty: no cache
  uint64_t max_bytes = uint64_t(512) << 20;  // after a write the folder's entries are trimmed to this, oldest first
};

// The settings every KnitMaterial constructed afterwards uses (thread-safe).
void set_table_cache(const TableCacheSettings& settings);
TableCacheSettings table_cache();

// $KNITSHADE_CACHE_DIR if set ("off": no cache, returned as ""), else
// $XDG_CACHE_HOME/knitshade, else $HOME/.cache/knitshade, else "".
std::string default_table_cache_dir();

// The folder `knitshade render` and `knitshade cache` use when none is
// given: default_table_cache_dir(), unless that is the one under
// $XDG_CACHE_HOME or $HOME and it cannot be made or written to (a read-only
// home: a container, a render node), in which case a folder of this user's
// own under $TMPDIR (else /tmp), knitshade-cache-<uid>, made with mode 0700;
// a fallback folder that exists but is not this user's, or that others can
// write to, is not used (""). $KNITSHADE_CACHE_DIR is used as it is set:
// that choice was the user's, and a folder it names that cannot be written
// gives the cache's usual note.
std::string writable_table_cache_dir();

// The GNU build id (hex) of the binary that holds this library's code;
// empty when it has none, and then nothing is cached.
const std::string& library_build_id();

// The file name of cache entries (their extension).
inline constexpr const char* kTableCacheExtension = ".knittable";

// The entries in folder `dir` (none when it does not exist), and
// clear_table_cache: removes them (the *.knittable files, nothing else) and
// says what it removed. Both also remove the temporaries of interrupted
// writes once they are an hour old, and throw std::runtime_error naming the
// folder when it cannot be read, or an entry that cannot be removed.
// table_cache_usage also counts the entries by the stage their key names
// (read from each file's first bytes; an entry whose key is not of this
// format, or cannot be read, is in `entries` alone).
struct TableCacheUsage {
  uint64_t entries = 0, bytes = 0;
  uint64_t finished = 0, marches = 0, shadows = 0;
};
TableCacheUsage table_cache_usage(const std::string& dir);
TableCacheUsage clear_table_cache(const std::string& dir);

}  // namespace knit
