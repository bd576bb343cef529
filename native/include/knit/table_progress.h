// Progress of the multi-scale class-table builds, for a host to show: a
// first multi-scale render of a material spends seconds building its
// tables (KnitMaterial's constructor), before any sample.
//
// KnitMaterial calls begin() when it starts to build (not when the tables
// come from the class-table cache), FootprintTable and TableBsdf add() the
// work units of each job they finish, from their building threads, and the
// material calls end() when its tables are done. The units weigh a job of
// the TableBsdf's marches twice one of the class table's, about as they
// cost; finishing a table (hundredths of a second) is not counted.
#pragma once

#include <cstdint>

namespace knit {

class TableBuildProgress {
 public:
  virtual ~TableBuildProgress() = default;
  virtual void begin(uint64_t total_units) = 0;
  virtual void add(uint64_t units) = 0;  // (called concurrently)
  virtual void end() = 0;
};

// The process's observer (null: none), not owned: set it before materials
// are constructed and keep it alive while any is.
void set_table_build_progress(TableBuildProgress* progress);
TableBuildProgress* table_build_progress();

// Units of each build job (see above), and of a build for `classes`
// classes present that builds the class table and/or the tabulated BSDF's
// marches (FootprintTable::kThetaBins and TableBsdf::kNodes jobs per class).
inline constexpr uint64_t kClassTableJobUnits = 1;
inline constexpr uint64_t kTableBsdfJobUnits = 2;
inline constexpr uint64_t kClassTableJobsPerClass = 24;
inline constexpr uint64_t kTableBsdfJobsPerClass = 144;
inline constexpr uint64_t table_build_units(int classes, bool class_table, bool table_bsdf) {
  return uint64_t(classes) * ((class_table ? kClassTableJobsPerClass * kClassTableJobUnits : 0) +
                              (table_bsdf ? kTableBsdfJobsPerClass * kTableBsdfJobUnits : 0));
}

}  // namespace knit
