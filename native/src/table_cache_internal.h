// What KnitMaterial's constructor asks of the class-table cache
// (table_cache.cpp; the settings and the file format are described there
// and in knit/table_cache.h).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "knit/aggregate_table.h"
#include "knit/table_bsdf.h"
#include "knit/table_cache.h"

namespace knit {

class KnitMaterial;

// The build's own settings, which the key holds beside the material's.
struct ClassTableBuild {
  int rays_per_direction = 256;  // FootprintTable
  bool sub_cells = true;
  bool table_bsdf = true;        // a TableBsdf is built beside it
  int hits_per_view = 512;       // TableBsdf
  int march_stride = 8;
};

// The entry of `material` and `build` in the cache folder for one stage
// of the build (TableBsdf::Stage; table_cache.cpp): the key (empty when
// nothing can be cached: no build id), the file's path and the stage of
// the TableBsdf it holds (without build.table_bsdf, none: Shadows, whose
// key holds the geometry alone, the class table's only entry).
struct ClassTableEntry {
  std::string key;
  std::string path;
  TableBsdf::Stage stage = TableBsdf::Stage::Finished;
};
ClassTableEntry class_table_entry(const KnitMaterial& material, const ClassTableBuild& build,
                                  const TableCacheSettings& settings, TableBsdf::Stage stage);

// Reads the entry into table (and bsdf, when build.table_bsdf), for a
// pattern of rows x cols cells; false, with `note` saying why ("class-table
// cache entry PATH is damaged (checksum)", for the caller to add what it
// did instead) when it is not simply absent or another key's, when it cannot
// be used.
bool load_class_tables(const ClassTableEntry& entry, const ClassTableBuild& build, int rows, int cols,
                       std::shared_ptr<const FootprintTable>& table, std::shared_ptr<const TableBsdf>& bsdf,
                       std::string& note);
// The bytes of an entry file decoded for `key`: ok, another key's entry,
// or why it cannot be used (`why`, a phrase after the file's name). Every
// size is checked before it is read and the tables' shapes after, so no
// bytes make it read out of bounds (tests/native/test_table_cache.cpp
// decodes mutated entries whose checksum was made to fit).
struct DecodeResult {
  bool ok = false, other_key = false;
  const char* why = "";
};
DecodeResult decode_class_tables(const std::vector<unsigned char>& bytes, const std::string& key,
                                 const ClassTableBuild& build, TableBsdf::Stage stage, int rows, int cols,
                                 std::shared_ptr<const FootprintTable>& table,
                                 std::shared_ptr<const TableBsdf>& bsdf);
// Writes the entry (atomically: a temporary file renamed), then trims the
// folder to settings.max_bytes; on failure `note` says why.
void store_class_tables(const ClassTableEntry& entry, const TableCacheSettings& settings,
                        const FootprintTable& table, const TableBsdf* bsdf, std::string& note);

}  // namespace knit
