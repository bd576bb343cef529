// `knitshade cache`: the class-table cache of `knitshade render` (its
// folder, entries and size), and --clear to empty it.
#include <cstdio>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "knit/table_cache.h"

namespace knit::cli {
namespace {

const char* kHelp = R"(usage: knitshade cache [--dir DIR] [--clear]

The class-table cache of `knitshade render` (docs/renderer.md): multi-scale
materials keep their class tables there between runs. Prints the folder, how
many entries it holds and their size; --clear removes the entries (its
*.knittable files, and temporaries of interrupted writes over an hour old;
nothing else).

options:
  --dir DIR   the folder (default: as `knitshade render` picks it:
              $KNITSHADE_CACHE_DIR, else $XDG_CACHE_HOME/knitshade, else
              ~/.cache/knitshade, or where that cannot be written,
              $TMPDIR/knitshade-cache-UID; KNITSHADE_CACHE_DIR=off: none)
  --clear     remove the entries
)";

std::string mib(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / double(1 << 20));
  return buf;
}

int run(const std::vector<std::string>& args) {
  std::string dir;
  bool have_dir = false, clear = false;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kHelp);
      return 0;
    } else if (a == "--dir") {
      dir = option_value(args, i);
      have_dir = true;
      if (dir.empty()) throw UsageError{"--dir: empty folder name"};
    } else if (a == "--clear") {
      clear = true;
    } else {
      throw UsageError{"unknown argument " + a};
    }
  }
  if (!have_dir) dir = writable_table_cache_dir();
  if (dir.empty()) {
    std::printf("class-table cache: off (KNITSHADE_CACHE_DIR=off, or no home folder)\n");
    return 0;
  }
  if (clear) {
    const TableCacheUsage r = clear_table_cache(dir);
    std::printf("class-table cache %s: removed %llu entries (%s)\n", dir.c_str(),
                static_cast<unsigned long long>(r.entries), mib(r.bytes).c_str());
    return 0;
  }
  const TableCacheUsage u = table_cache_usage(dir);
  std::printf("class-table cache %s: %llu entries, %s (trimmed to %s)\n", dir.c_str(),
              static_cast<unsigned long long>(u.entries), mib(u.bytes).c_str(),
              mib(TableCacheSettings{}.max_bytes).c_str());
  // (a material has three entries, one per stage of its build: docs/renderer.md)
  const uint64_t other = u.entries - u.finished - u.marches - u.shadows;
  std::printf("  %llu finished tables, %llu marches, %llu shadows%s\n", static_cast<unsigned long long>(u.finished),
              static_cast<unsigned long long>(u.marches), static_cast<unsigned long long>(u.shadows),
              other ? (", " + std::to_string(other) + " of another format").c_str() : "");
  return 0;
}

const bool registered =
    register_command({"cache", "show the class-table cache of `knitshade render`, or clear it", &run});

}  // namespace
}  // namespace knit::cli
