// The example scenes (examples/scenes/*.json): every one loads and renders,
// and the two far swatches are in the regimes the README says they are in.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "render/renderer.h"
#include "render/report.h"
#include "render/scene.h"
#include "render/scene_desc.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

std::vector<std::string> example_scenes() {
  std::vector<std::string> names;
  for (const auto& e : std::filesystem::directory_iterator(test::source_dir() + "/examples/scenes"))
    if (e.path().extension() == ".json") names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// Each example scene, shrunk to 32 pixels wide at 1 spp: it loads (meshes,
// patterns, images), builds and renders to a finite image with light in it.
// A change to the scene format that an example was not updated for fails
// here, not in a user's hands.
TEST(Examples, EverySceneLoadsAndRenders) {
  const std::vector<std::string> names = example_scenes();
  EXPECT_GE(names.size(), 11u) << "examples/scenes lost scenes";
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/" + name);
    const double aspect = double(d.film.height) / double(d.film.width);
    d.film.width = 32;
    d.film.height = std::max(1, int(std::lround(32 * aspect)));
    d.film.spp = 1;
    const RenderResult r = test::render_desc(d).result;
    EXPECT_EQ(r.stats.invalid_samples, 0u);
    ASSERT_EQ(r.image.pixels.size(), size_t(d.film.width) * size_t(d.film.height));
    double sum = 0;
    size_t bad = 0;
    for (const auto& p : r.image.pixels) {
      for (float c : {p.r, p.g, p.b}) {
        if (!std::isfinite(c) || c < 0) ++bad;
        sum += c;
      }
    }
    EXPECT_EQ(bad, 0u);
    EXPECT_GT(sum, 0.0) << "a black image";
    std::printf("[examples] %s: %dx%d, mean %.4f, knit hits %llu\n", name.c_str(), d.film.width, d.film.height,
                sum / (3.0 * double(r.image.pixels.size())), static_cast<unsigned long long>(r.stats.resolves));
  }
}

// At their default size (480 x 360) the far swatch's footprints are a
// third of a stitch cell, so multi-scale mode reads them from the class
// table's sub-cells (table_min_cells 0.25), and the distant swatch
// (stitches a third the size) has every footprint a cell or more, read from
// its whole cells (README, "Examples").
TEST(Examples, SwatchesFarAndDistantAreInTheirRegimes) {
  struct Case {
    const char* name;
    double min_table_share, max_table_share, min_sub_share, max_sub_share;  // shares of the knit hits
  };
  for (const Case& c : {Case{"swatch_far.json", 0.95, 1.0, 0.95, 1.0}, Case{"swatch_distant.json", 0.99, 1.0, 0.0, 0.01}}) {
    SCOPED_TRACE(c.name);
    SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/" + c.name);
    ASSERT_EQ(d.film.width, 480);
    d.film.spp = 1;
    const RenderResult r = test::render_desc(d).result;
    ASSERT_GT(r.stats.resolves, 0u);
    const double share = double(r.stats.table_resolves) / double(r.stats.resolves);
    std::printf("[examples] %s: %.1f%% of %llu knit hits from the class table\n", c.name, 100 * share,
                static_cast<unsigned long long>(r.stats.resolves));
    EXPECT_GE(share, c.min_table_share);
    EXPECT_LE(share, c.max_table_share);
    const double sub = double(r.stats.sub_cell_resolves) / double(r.stats.resolves);
    std::printf("[examples] %s: %.1f%% from its sub-cells\n", c.name, 100 * sub);
    EXPECT_GE(sub, c.min_sub_share);
    EXPECT_LE(sub, c.max_sub_share);
  }
}

// The far swatch at its default table_min_cells (0.25) takes its
// footprints from the class table's sub-cells (docs/multiscale.md,
// "Footprints of a quarter cell") and counts none as a quarter cell shaded
// as the near field; with 0.5 (the default until the eighths) it shades
// most of them as the near field, counts those, and the report's hint names
// table_min_cells 0.25.
TEST(Examples, SwatchFarFromTheTableWithQuarterCells) {
  for (const float min_cells : {0.25f, 0.5f}) {
    SCOPED_TRACE(min_cells);
    SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/swatch_far.json");
    d.film.spp = 1;
    for (MaterialDesc& m : d.materials) {
      if (m.type != MaterialType::Knit) continue;
      KnitMaterialParams p = m.knit.model->params();
      ASSERT_EQ(p.table_min_cells, 0.25f);  // (the example's, the default)
      p.table_min_cells = min_cells;
      m.knit.model = std::make_shared<const KnitMaterial>(m.knit.model->surface().pattern(), p);
    }
    const RenderResult r = test::render_desc(d).result;
    ASSERT_GT(r.stats.resolves, 0u);
    const double table = double(r.stats.table_resolves) / double(r.stats.resolves);
    const double quarter = double(r.stats.quarter_cell_resolves) / double(r.stats.resolves);
    std::printf("[examples] swatch_far.json, table_min_cells %.2f: %.1f%% of %llu knit hits from the class table, "
                "%.1f%% near field of a quarter cell or more\n",
                min_cells, 100 * table, static_cast<unsigned long long>(r.stats.resolves), 100 * quarter);
    RenderReport rep;
    rep.resolves = r.stats.resolves;
    rep.table_resolves = r.stats.table_resolves;
    rep.quarter_cell_resolves = r.stats.quarter_cell_resolves;
    rep.knit_materials = 1;
    const bool hint = rep.to_text().find("\"table_min_cells\": 0.25") != std::string::npos;
    if (min_cells == 0.5f) {
      EXPECT_LE(table, 0.1);
      EXPECT_GE(quarter, 0.8);
      EXPECT_TRUE(hint) << rep.to_text();
    } else {
      EXPECT_GE(table, 0.95);
      EXPECT_EQ(r.stats.quarter_cell_resolves, 0u);
      EXPECT_FALSE(hint) << rep.to_text();
    }
  }
}

// The near field's "mode" hint. The far swatch at its 480 pixels has
// footprints of about a third of a stitch cell (the tests above: multi-scale
// reads them from the class table); at half the size two thirds, at 1,200
// pixels about a seventh, below table_min_cells (0.25). Rendered in
// near-field mode, the camera's hits are counted as footprints multi-scale
// would read from its table accordingly, and the report's hint names
// "multi_scale" where a tenth or more are. Multi-scale mode and explicit
// yarns count none.
TEST(Examples, NearFieldCountsTheFootprintsMultiScaleWouldReadFromItsTable) {
  struct Case {
    int width;
    bool explicit_yarns;
    KnitMode mode;
    double min_share, max_share;
  };
  for (const Case& c : {Case{240, false, KnitMode::NearField, 0.98, 1.0}, Case{480, false, KnitMode::NearField, 0.9, 1.0},
                        Case{1200, false, KnitMode::NearField, 0.0, 0.02},
                        Case{240, false, KnitMode::MultiScale, 0.0, 0.0}, Case{240, true, KnitMode::NearField, 0.0, 0.0}}) {
    SCOPED_TRACE(c.width);
    SCOPED_TRACE(c.explicit_yarns ? "explicit yarns" : c.mode == KnitMode::NearField ? "near field" : "multi-scale");
    SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/swatch_far.json");
    ASSERT_EQ(d.film.width, 480);
    d.film.height = d.film.height * c.width / d.film.width;
    d.film.width = c.width;
    d.film.spp = 1;
    d.integrator.explicit_yarns = c.explicit_yarns;
    for (MaterialDesc& m : d.materials) {
      if (m.type != MaterialType::Knit) continue;
      KnitMaterialParams p = m.knit.model->params();
      ASSERT_EQ(p.table_min_cells, 0.25f);
      p.mode = c.mode;
      m.knit.model = std::make_shared<const KnitMaterial>(m.knit.model->surface().pattern(), p);
    }
    const RenderResult r = test::render_desc(d).result;
    ASSERT_GT(r.stats.camera_resolves, uint64_t(c.width) * uint64_t(d.film.height) / 4);  // the swatch fills the view
    const double share = double(r.stats.camera_table_footprints) / double(r.stats.camera_resolves);
    std::printf("[examples] swatch_far.json at %dx%d, %s: %.1f%% of %llu camera hits on footprints the class table "
                "would serve\n",
                c.width, d.film.height, c.explicit_yarns ? "explicit yarns" : c.mode == KnitMode::NearField ? "near field" : "multi-scale",
                100 * share, static_cast<unsigned long long>(r.stats.camera_resolves));
    EXPECT_GE(share, c.min_share);
    EXPECT_LE(share, c.max_share);
    RenderReport rep;
    rep.knit_materials = 1;
    rep.resolves = r.stats.resolves;
    rep.camera_resolves = r.stats.camera_resolves;
    rep.camera_table_footprints = r.stats.camera_table_footprints;
    const std::string text = rep.to_text();
    EXPECT_EQ(text.find("\"mode\": \"multi_scale\"") != std::string::npos, share >= 0.1) << text;
  }
}

// The hint's threshold, on counts made up for it: a tenth of the camera's
// hits.
TEST(Examples, NearFieldModeHintReadsTheCounts) {
  RenderReport rep;
  rep.knit_materials = 1;
  rep.resolves = 2000;
  rep.camera_resolves = 1000;
  rep.camera_table_footprints = 99;
  EXPECT_EQ(rep.to_text().find("multi_scale"), std::string::npos) << rep.to_text();
  rep.camera_table_footprints = 100;
  const std::string text = rep.to_text();
  EXPECT_NE(text.find("  hint        10% of the camera's knit hits"), std::string::npos) << text;
  EXPECT_NE(rep.to_json().find("\"camera_table_footprint_hits\": 100"), std::string::npos) << rep.to_json();
}

}  // namespace
}  // namespace knit::render
