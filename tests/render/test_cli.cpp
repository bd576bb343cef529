// The `knitshade render` and `knitshade bake-frames` commands, run as a
// user would: exit codes, the one-line errors, outputs and the JSON report.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "knit/surface.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

struct CliRun {
  int code = -1;
  std::string out, err;
};

CliRun run(const std::string& dir, const std::string& args) {
  const std::string cmd = std::string(KNIT_CLI) + " " + args + " > " + dir + "/stdout.txt 2> " + dir + "/stderr.txt";
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = test::read_file(dir + "/stdout.txt");
  r.err = test::read_file(dir + "/stderr.txt");
  return r;
}

int lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

std::string small_scene(const std::string& material = R"({"type": "diffuse", "albedo": [0.6, 0.5, 0.4]})") {
  return R"({
    "film": {"width": 24, "height": 16, "spp": 4, "seed": 1},
    "camera": {"position": [0, 1, 3], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"type": "environment", "color": [0.8, 0.9, 1.0]}, {"type": "directional", "to_light": [1, 2, 1], "irradiance": [2, 2, 2]}],
    "materials": {"m": )" + material + R"(},
    "objects": [{"mesh": ")" + test::mesh("quad.obj") + R"(", "material": "m", "transform": {"rotate": [-60, 0, 0], "scale": 2}}]
  })";
}

// --version: the version line, then the compiler, the batched query's
// vector path on this CPU and the libraries' versions, one per line.
TEST(Cli, VersionNamesThePathAndTheLibraries) {
  const std::string dir = test::test_dir();
  const CliRun r = run(dir, "--version");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("knitshade ", 0), 0u) << r.out;
  const std::string isa = KnitSurface::batch_isa_name(KnitSurface::batch_best_isa());
  EXPECT_NE(r.out.find("batched query  " + isa + " ("), std::string::npos) << r.out;
  for (const char* lib : {"compiler", "Embree         3.", "OpenImageIO    2.", "OpenColorIO    2.", "oneTBB"})
    EXPECT_NE(r.out.find(lib), std::string::npos) << lib << " in\n" << r.out;
  EXPECT_EQ(lines(r.out), 7) << r.out;
  EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST(Cli, RendersPngAndExrWithAReport) {
  const std::string dir = test::test_dir();
  const std::string scene = test::write_file(dir, "scene.json", small_scene());
  const CliRun r = run(dir, "render " + scene + " -o " + dir + "/out.png --report " + dir + "/report.json --threads 2");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("samples/s"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Embree BVH"), std::string::npos);
  auto png = OIIO::ImageInput::open(dir + "/out.png");
  ASSERT_TRUE(png);
  EXPECT_EQ(png->spec().width, 24);
  EXPECT_EQ(png->spec().format, OIIO::TypeDesc::UINT8);

  const nlohmann::json rep = nlohmann::json::parse(test::read_file(dir + "/report.json"));
  EXPECT_EQ(rep["width"], 24);
  EXPECT_EQ(rep["spp"], 4);
  EXPECT_EQ(rep["threads"], 2);
  EXPECT_EQ(rep["samples"], 24 * 16 * 4);
  EXPECT_GT(rep["samples_per_second"].get<double>(), 0);
  EXPECT_GT(rep["rays_per_second"].get<double>(), 0);
  EXPECT_GT(rep["memory_bytes"]["peak_rss"].get<int64_t>(), 0);
  EXPECT_GT(rep["memory_bytes"]["embree"].get<int64_t>(), 0);
  EXPECT_EQ(rep["rays"]["camera"], 24 * 16 * 4);
  EXPECT_EQ(rep["invalid_samples"], 0);

  const CliRun e = run(dir, "render " + scene + " -o " + dir + "/out.exr --quiet --spp 2 --seed 9");
  ASSERT_EQ(e.code, 0) << e.err;
  EXPECT_EQ(e.out, "");  // --quiet
  const RgbImage exr = read_rgb_image(dir + "/out.exr");
  EXPECT_EQ(exr.width, 24);
}

// --size overrides the film's size (a quick preview of a scene): the image
// and the report have it; the camera keeps its vertical field of view, so
// the middle columns of a wider image see what the scene's own size sees.
TEST(Cli, SizeOverridesTheFilm) {
  const std::string dir = test::test_dir();
  const std::string scene = test::write_file(dir, "scene.json", small_scene());
  const CliRun r = run(dir, "render " + scene + " -o " + dir + "/wide.exr --quiet --spp 64 --size 48x16 --report " +
                                dir + "/wide.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const RgbImage wide = read_rgb_image(dir + "/wide.exr");
  EXPECT_EQ(wide.width, 48);
  EXPECT_EQ(wide.height, 16);
  const nlohmann::json rep = nlohmann::json::parse(test::read_file(dir + "/wide.json"));
  EXPECT_EQ(rep["width"], 48);
  EXPECT_EQ(rep["height"], 16);
  // The scene's own 24 x 16 against the middle 24 columns of the wide image
  // (other samples, so within the noise: measured 0.03% apart on the mean,
  // 0.8% per pixel).
  ASSERT_EQ(run(dir, "render " + scene + " -o " + dir + "/own.exr --quiet --spp 64").code, 0);
  const RgbImage own = read_rgb_image(dir + "/own.exr");
  ASSERT_EQ(own.width, 24);
  double sum_own = 0, sum_mid = 0, diff = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) {
      const Rgb a = own.at(x, y), b = wide.at(x + 12, y);
      sum_own += a.r + a.g + a.b;
      sum_mid += b.r + b.g + b.b;
      diff += std::fabs(a.r - b.r) + std::fabs(a.g - b.g) + std::fabs(a.b - b.b);
    }
  std::printf("[size] middle of 48x16 against 24x16: means %.4f, %.4f; mean |difference| %.4f\n", sum_mid / 1152,
              sum_own / 1152, diff / 1152);
  EXPECT_NEAR(sum_mid / sum_own, 1.0, 0.02);
  EXPECT_LT(diff / sum_own, 0.1);
  for (const char* bad : {"48", "0x16", "48x", "x16", "48x16x2", "-4x16", "48x99999", "48X16"}) {
    const CliRun b = run(dir, "render " + scene + " -o " + dir + "/bad.exr --size " + bad);
    EXPECT_EQ(b.code, 2) << bad;
    EXPECT_NE(b.err.find("--size"), std::string::npos) << b.err;
    EXPECT_NE(b.err.find(std::string("'") + bad), std::string::npos) << b.err;
  }
}

TEST(Cli, BadSceneGivesOneLineAndExitCode1) {
  const std::string dir = test::test_dir();
  std::string text = small_scene();
  text.replace(text.find("\"width\": 24"), 11, "\"width\": -24");
  const std::string scene = test::write_file(dir, "scene.json", text);
  const CliRun r = run(dir, "render " + scene + " -o " + dir + "/out.png");
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(lines(r.err), 1) << r.err;
  // (at the line and column of the field, counted here)
  const size_t at = text.find("\"width\": -24");
  const size_t line = 1 + size_t(std::count(text.begin(), text.begin() + long(at), '\n'));
  const size_t col = at - (text.rfind('\n', at) == std::string::npos ? 0 : text.rfind('\n', at) + 1) + 1;
  EXPECT_NE(r.err.find("knitshade render: error: " + scene + ":" + std::to_string(line) + ":" + std::to_string(col) +
                       ": film.width: must be in [1, 16384], got -24"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir + "/out.png"));

  const CliRun missing = run(dir, "render " + dir + "/none.json -o " + dir + "/out.png");
  EXPECT_EQ(missing.code, 1);
  EXPECT_EQ(lines(missing.err), 1);
  EXPECT_NE(missing.err.find("none.json: scene file not found"), std::string::npos) << missing.err;

  test::write_file(dir, "syntax.json", "{\"film\": }");
  const CliRun syntax = run(dir, "render " + dir + "/syntax.json -o " + dir + "/out.png");
  EXPECT_EQ(syntax.code, 1);
  EXPECT_NE(syntax.err.find("syntax.json:1:10: JSON syntax error"), std::string::npos) << syntax.err;
}

TEST(Cli, RendersKnitWithTheModelAndAsExplicitYarns) {
  const std::string dir = test::test_dir();
  const std::string scene = test::write_file(
      dir, "scene.json",
      small_scene(R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 12, "yarn_colors": [[0.7, 0.1, 0.1]]})"));
  // The knit model: its state is reported; no yarn geometry.
  const CliRun m = run(dir, "render " + scene + " -o " + dir + "/model.exr --quiet --report " + dir + "/model.json");
  ASSERT_EQ(m.code, 0) << m.err;
  const nlohmann::json rm = nlohmann::json::parse(test::read_file(dir + "/model.json"));
  EXPECT_EQ(rm["knit"]["materials"], 1);
  EXPECT_EQ(rm["knit"]["explicit_yarns"], false);
  EXPECT_GT(rm["knit"]["hits"].get<uint64_t>(), 0u);
  EXPECT_EQ(rm["knit"]["table_hits"], 0);  // near field: no class table ...
  EXPECT_EQ(rm["knit"]["aggregated_hits"], 0);  // ... nor footprint aggregates
  EXPECT_GT(rm["memory_bytes"]["knit_state"].get<uint64_t>(), 0u);
  EXPECT_EQ(rm["memory_bytes"]["yarn_geometry"], 0);
  EXPECT_EQ(rm["triangles"], 2);
  // The diffuse preview (a debug option) renders the quad in its first yarn colour ...
  const CliRun p = run(dir, "render " + scene + " -o " + dir + "/preview.exr --quiet --knit-preview-diffuse");
  ASSERT_EQ(p.code, 0) << p.err;
  // (with --size too: the preview's film is the one asked for)
  const CliRun ps = run(dir, "render " + scene + " -o " + dir + "/preview_small.exr --quiet --knit-preview-diffuse --size 12x8");
  ASSERT_EQ(ps.code, 0) << ps.err;
  const RgbImage small_preview = read_rgb_image(dir + "/preview_small.exr");
  EXPECT_EQ(small_preview.width, 12);
  EXPECT_EQ(small_preview.height, 8);
  auto red_pixels = [](const RgbImage& img) {
    int n = 0;
    for (const Rgb& c : img.pixels) n += c.r > 1.5f * c.b;
    return n;
  };
  const int preview_red = red_pixels(read_rgb_image(dir + "/preview.exr"));
  EXPECT_GT(preview_red, 30);
  // ... and the model covers part of it with red yarn: the sky shows through the gaps.
  const int model_red = red_pixels(read_rgb_image(dir + "/model.exr"));
  EXPECT_GT(model_red, preview_red / 10);
  EXPECT_LT(model_red, preview_red);

  // Explicit yarns: tube geometry and its BVH are reported apart from the rest.
  const CliRun e = run(dir, "render " + scene + " -o " + dir + "/explicit.exr --quiet --explicit-yarns --report " + dir +
                                "/explicit.json");
  ASSERT_EQ(e.code, 0) << e.err;
  const nlohmann::json re = nlohmann::json::parse(test::read_file(dir + "/explicit.json"));
  EXPECT_EQ(re["knit"]["explicit_yarns"], true);
  EXPECT_GT(re["knit"]["yarn_segments"].get<uint64_t>(), 100u);
  EXPECT_GT(re["memory_bytes"]["yarn_geometry"].get<uint64_t>(), 16 * re["knit"]["yarn_points"].get<uint64_t>() - 1);
  EXPECT_GT(re["memory_bytes"]["embree_yarns"].get<int64_t>(), 0);
  EXPECT_EQ(re["triangles"], 0);  // the base mesh is replaced by the tubes
  EXPECT_EQ(rm["seconds"]["knit_tables"], 0.0);  // near field: nothing built
}

// How a multi-scale knit shaded its hits: footprints below a stitch cell
// (here every camera footprint, at uv_scale 1) as the near field by
// default, as marched aggregates with near_field_below_cell false; the
// report counts both kinds apart from the class table's.
TEST(Cli, ReportsHowMultiScaleHitsWereShaded) {
  const std::string dir = test::test_dir();
  for (const bool near : {true, false}) {
    const std::string scene = test::write_file(
        dir, "scene.json",
        small_scene(std::string(R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 1, "mode": "multi_scale",
                                    "near_field_below_cell": )") +
                    (near ? "true" : "false") + R"(, "yarn_colors": [[0.7, 0.1, 0.1]]})"));
    const CliRun r = run(dir, "render " + scene + " -o " + dir + "/ms.exr --report " + dir + "/ms.json");
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json k = nlohmann::json::parse(test::read_file(dir + "/ms.json"))["knit"];
    EXPECT_EQ(k["table_hits"], 0) << near;
    if (near) {
      EXPECT_EQ(k["aggregated_hits"], 0);
      EXPECT_EQ(r.out.find("aggregated over marched points"), std::string::npos) << r.out;  // (none to report)
    } else {
      EXPECT_GT(k["aggregated_hits"].get<uint64_t>(), 0u);
      EXPECT_LE(k["aggregated_hits"].get<uint64_t>(), k["hits"].get<uint64_t>());
      EXPECT_NE(r.out.find("aggregated over marched points"), std::string::npos) << r.out;
    }
  }
}

// At uv_scale 60 nearly every camera footprint is half a cell to a cell:
// the class table's sub-cells by default, counted apart in the report;
// with table_min_cells 1 none of them.
TEST(Cli, ReportsTheClassTablesSubCells) {
  const std::string dir = test::test_dir();
  for (const char* min_cells : {"0.5", "1"}) {
    const std::string scene = test::write_file(
        dir, "scene.json",
        small_scene(std::string(R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 60, "mode": "multi_scale",
                                    "table_min_cells": )") +
                    min_cells + R"(, "yarn_colors": [[0.7, 0.1, 0.1]]})"));
    const CliRun r = run(dir, "render " + scene + " -o " + dir + "/ms.exr --report " + dir + "/ms.json");
    ASSERT_EQ(r.code, 0) << r.err;
    const nlohmann::json k = nlohmann::json::parse(test::read_file(dir + "/ms.json"))["knit"];
    const uint64_t hits = k["hits"], table = k["table_hits"], sub = k["sub_cell_hits"];
    ASSERT_GT(hits, 100u);
    EXPECT_LE(sub, table);
    if (std::string(min_cells) == "0.5") {
      EXPECT_GT(sub, hits / 2) << r.out;
      EXPECT_NE(r.out.find("sub-cells)"), std::string::npos) << r.out;
    } else {
      EXPECT_EQ(sub, 0u);
      EXPECT_LT(table, hits / 2) << "below a cell: the near field";
    }
  }
}

TEST(Cli, ReportsTheClassTableBuildApartFromParsing) {
  // A multi-scale knit builds its class table while the scene is parsed:
  // the report gives that time its own entry, and the parts still add up.
  const std::string dir = test::test_dir();
  const std::string scene = test::write_file(
      dir, "scene.json",
      small_scene(R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 40, "mode": "multi_scale", "yarn_colors": [[0.7, 0.1, 0.1]]})"));
  // (--no-cache: built here, not read from the class-table cache)
  const CliRun r = run(dir, "render " + scene + " -o " + dir + "/ms.exr --no-cache --report " + dir + "/ms.json");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json rep = nlohmann::json::parse(test::read_file(dir + "/ms.json"));
  EXPECT_EQ(rep["knit_tables"]["built"], 1);
  EXPECT_EQ(rep["knit_tables"]["from_cache"], 0);
  const nlohmann::json& s = rep["seconds"];
  const double tables = s["knit_tables"].get<double>();
  // Seed stitch: several classes, hundreds of thousands of marched rays, never 0 s.
  EXPECT_GT(tables, 0.0);
  double parts = 0;
  for (const char* k : {"parse", "knit_tables", "load", "build", "render", "write"}) {
    EXPECT_GE(s[k].get<double>(), 0.0) << k;
    parts += s[k].get<double>();
  }
  EXPECT_LE(parts, s["total"].get<double>() + 1e-6);
  EXPECT_NE(r.out.find("knit class tables"), std::string::npos) << r.out;

  // Rendered as explicit yarns (the option, or the scene's integrator), the
  // model shades nothing: no class table is built, and the tubes' own
  // set-up time joins the breakdown.
  for (const std::string& how : {std::string("--explicit-yarns"), std::string("")}) {
    std::string file = scene;
    if (how.empty()) {
      nlohmann::json j = nlohmann::json::parse(test::read_file(scene));
      j["integrator"] = {{"explicit_yarns", true}};
      file = test::write_file(dir, "explicit_scene.json", j.dump());
    }
    const CliRun e = run(dir, "render " + file + " -o " + dir + "/ex.exr " + how + " --report " + dir + "/ex.json");
    ASSERT_EQ(e.code, 0) << e.err;
    const nlohmann::json re = nlohmann::json::parse(test::read_file(dir + "/ex.json"));
    EXPECT_EQ(re["knit"]["explicit_yarns"], true) << how;
    EXPECT_EQ(re["seconds"]["knit_tables"], 0.0) << how;
    EXPECT_GT(re["seconds"]["yarns"].get<double>(), 0.0) << how;
    EXPECT_EQ(e.out.find("knit class tables"), std::string::npos) << e.out;
    EXPECT_NE(e.out.find(", yarns "), std::string::npos) << e.out;
  }
  // The skipped table's key is still checked.
  const std::string bad = test::write_file(
      dir, "bad.json",
      small_scene(R"({"type": "knit", "pattern": ["KP"], "uv_scale": 40, "mode": "multi_scale", "footprint_table": 3, "yarn_colors": [[1, 1, 1]]})"));
  const CliRun b = run(dir, "render " + bad + " -o " + dir + "/bad.exr --explicit-yarns");
  EXPECT_EQ(b.code, 1);
  EXPECT_NE(b.err.find("footprint_table"), std::string::npos) << b.err;
}

// An EXR's pixels (its header carries the time it was written).
std::vector<float> exr_pixels(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) return {};
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> px(size_t(spec.width) * size_t(spec.height) * size_t(spec.nchannels));
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  return px;
}

TEST(Cli, ClassTablesComeFromTheCacheTheSecondTime) {
  // Two multi-scale knits (one of two colours); the first render builds and
  // keeps their class tables, the second reads them, and its image is the
  // first's to the last bit. --no-cache builds them again and keeps nothing.
  const std::string dir = test::test_dir();
  const std::string cache = dir + "/cache";
  std::filesystem::remove_all(cache);
  nlohmann::json j = nlohmann::json::parse(small_scene(
      R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 40, "mode": "multi_scale", "yarn_colors": [[0.7, 0.1, 0.1]]})"));
  j["materials"]["two"] = {{"type", "knit"}, {"pattern", {"KK", "KK"}}, {"colors", {{0, 1}, {1, 0}}}, {"uv_scale", 40},
                           {"mode", "multi_scale"}, {"yarn_colors", {{0.7, 0.1, 0.1}, {0.1, 0.2, 0.7}}}};
  j["objects"].push_back(j["objects"][0]);
  j["objects"][1]["material"] = "two";
  j["objects"][1]["transform"]["translate"] = {0.5, 0.2, -0.5};
  const std::string scene = test::write_file(dir, "scene.json", j.dump());
  auto render = [&](const std::string& name, const std::string& how) {
    const CliRun r = run(dir, "render " + scene + " -o " + dir + "/" + name + ".exr " + how + " --report " + dir + "/" +
                                  name + ".json");
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(r.err.find("warning"), std::string::npos) << r.err;
    return std::make_pair(r, nlohmann::json::parse(test::read_file(dir + "/" + name + ".json")));
  };
  const auto [r1, first] = render("first", "--cache-dir " + cache);
  // The builds' progress on stderr (not a terminal here: a line per tenth
  // reached, the last at 100%), one bar per material that builds; none for
  // tables read from the cache.
  int table_bars = 0;
  for (size_t at = r1.err.find("knit class tables: 100%"); at != std::string::npos;
       at = r1.err.find("knit class tables: 100%", at + 1))
    ++table_bars;
  EXPECT_EQ(table_bars, 2) << r1.err;
  EXPECT_EQ(first["knit_tables"]["built"], 2);
  EXPECT_EQ(first["knit_tables"]["from_cache"], 0);
  const auto count_entries = [&] {
    int n = 0;
    for (const auto& e : std::filesystem::directory_iterator(cache)) n += e.path().extension() == ".knittable";
    return n;
  };
  EXPECT_EQ(count_entries(), 6);  // (each material's finished tables, their marches and their shadows)
  const auto [r2, second] = render("second", "--cache-dir " + cache);
  EXPECT_EQ(second["knit_tables"]["built"], 0);
  EXPECT_EQ(second["knit_tables"]["from_cache"], 2);
  EXPECT_NE(r2.out.find("knit class tables"), std::string::npos) << r2.out;
  EXPECT_NE(r2.out.find("from the cache"), std::string::npos) << r2.out;
  EXPECT_EQ(r2.err.find("knit class tables"), std::string::npos) << r2.err;
  EXPECT_LT(second["seconds"]["knit_tables"].get<double>(), first["seconds"]["knit_tables"].get<double>());
  const std::vector<float> image = exr_pixels(dir + "/first.exr");
  ASSERT_EQ(image.size(), size_t(24 * 16 * 3));
  EXPECT_TRUE(exr_pixels(dir + "/second.exr") == image);
  // $KNITSHADE_CACHE_DIR is the default folder (the tests point it into the
  // build folder); --no-cache reads and writes nothing.
  const std::string none = dir + "/none";
  std::filesystem::remove_all(none);
  const CliRun r3 = run(dir, "render " + scene + " -o " + dir + "/third.exr --no-cache --report " + dir + "/third.json");
  ASSERT_EQ(r3.code, 0) << r3.err;
  const nlohmann::json third = nlohmann::json::parse(test::read_file(dir + "/third.json"));
  EXPECT_EQ(third["knit_tables"]["built"], 2);
  EXPECT_TRUE(exr_pixels(dir + "/third.exr") == image);
  const CliRun env = run(dir, "render " + scene + " -o " + dir + "/fourth.exr --quiet");  // (no KNITSHADE_CACHE_DIR change)
  EXPECT_EQ(env.code, 0) << env.err;
  // The two-colour knit in other colours: its tables finished from the
  // cached marches, the image of a render without the cache to the bit.
  nlohmann::json k = j;
  k["materials"]["two"]["yarn_colors"] = {{0.2, 0.6, 0.3}, {0.9, 0.8, 0.3}};
  const std::string recoloured = test::write_file(dir, "recoloured.json", k.dump());
  const CliRun r4 = run(dir, "render " + recoloured + " -o " + dir + "/recoloured.exr --cache-dir " + cache +
                                 " --report " + dir + "/recoloured.json.report");
  ASSERT_EQ(r4.code, 0) << r4.err;
  EXPECT_EQ(r4.err.find("warning"), std::string::npos) << r4.err;
  const nlohmann::json rep4 = nlohmann::json::parse(test::read_file(dir + "/recoloured.json.report"));
  EXPECT_EQ(rep4["knit_tables"]["built"], 0);
  EXPECT_EQ(rep4["knit_tables"]["from_cache"], 1);
  EXPECT_EQ(rep4["knit_tables"]["finished_from_cached_marches"], 1);
  EXPECT_NE(r4.out.find("(1 of 2 from the cache, 1 finished from its marches)"), std::string::npos) << r4.out;
  EXPECT_LT(rep4["seconds"]["knit_tables"].get<double>(), 0.5 * first["seconds"]["knit_tables"].get<double>());
  EXPECT_EQ(count_entries(), 7);
  ASSERT_EQ(run(dir, "render " + recoloured + " -o " + dir + "/recoloured_plain.exr --no-cache --quiet").code, 0);
  EXPECT_TRUE(exr_pixels(dir + "/recoloured.exr") == exr_pixels(dir + "/recoloured_plain.exr"));
  EXPECT_FALSE(exr_pixels(dir + "/recoloured.exr") == image);
  // Every entry damaged: warnings naming them, the tables built again, the
  // same image.
  for (const auto& e : std::filesystem::directory_iterator(cache)) {
    std::string bytes = test::read_file(e.path().string());
    bytes[bytes.size() / 2] ^= 1;
    test::write_file(cache, e.path().filename().string(), bytes);
  }
  const CliRun r5 = run(dir, "render " + scene + " -o " + dir + "/fifth.exr --cache-dir " + cache + " --report " +
                                 dir + "/fifth.json");
  EXPECT_EQ(r5.code, 0) << r5.err;
  EXPECT_NE(r5.err.find("warning: class-table cache entry " + cache + "/"), std::string::npos) << r5.err;
  EXPECT_NE(r5.err.find("is damaged (checksum); built the tables again"), std::string::npos) << r5.err;
  EXPECT_EQ(nlohmann::json::parse(test::read_file(dir + "/fifth.json"))["knit_tables"]["built"], 2);
  EXPECT_TRUE(exr_pixels(dir + "/fifth.exr") == image);
  // A home that cannot be written (and no KNITSHADE_CACHE_DIR): the cache
  // in a folder of the user's own under $TMPDIR, no warning, and the second
  // render reads it.
  test::write_file(dir, "not_a_folder", "x");
  std::filesystem::remove_all(dir + "/tmp");
  std::filesystem::create_directories(dir + "/tmp");
  const std::string home_env = "env -u KNITSHADE_CACHE_DIR -u XDG_CACHE_HOME HOME=" + dir + "/not_a_folder/home TMPDIR=" +
                          dir + "/tmp ";
  for (int pass = 0; pass < 2; ++pass) {
    const std::string cmd = home_env + KNIT_CLI + " render " + scene + " -o " + dir + "/home.exr --report " + dir +
                            "/home.json > " + dir + "/stdout.txt 2> " + dir + "/stderr.txt";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << test::read_file(dir + "/stderr.txt");
    EXPECT_EQ(test::read_file(dir + "/stderr.txt").find("warning"), std::string::npos)
        << test::read_file(dir + "/stderr.txt");
    const nlohmann::json rh = nlohmann::json::parse(test::read_file(dir + "/home.json"));
    EXPECT_EQ(rh["knit_tables"]["cache_dir"], dir + "/tmp/knitshade-cache-" + std::to_string(long(getuid())));
    EXPECT_EQ(rh["knit_tables"]["from_cache"], pass == 0 ? 0 : 2);
  }
  EXPECT_TRUE(exr_pixels(dir + "/home.exr") == image);
  // Both options at once, or an empty folder name: usage errors.
  EXPECT_EQ(run(dir, "render " + scene + " -o x.exr --cache-dir " + cache + " --no-cache").code, 2);
  EXPECT_EQ(run(dir, "render " + scene + " -o x.exr --cache-dir ''").code, 2);

  // `knitshade cache`: the folder's entries and size; --clear removes the
  // entries and nothing else.
  test::write_file(cache, "notes.txt", "mine");
  const CliRun show = run(dir, "cache --dir " + cache);
  ASSERT_EQ(show.code, 0) << show.err;
  EXPECT_NE(show.out.find("class-table cache " + cache + ": 7 entries, "), std::string::npos) << show.out;
  // By stage: each material's three entries, and the recoloured material's finished tables.
  EXPECT_NE(show.out.find("  3 finished tables, 2 marches, 2 shadows\n"), std::string::npos) << show.out;
  const CliRun clear = run(dir, "cache --dir " + cache + " --clear");
  ASSERT_EQ(clear.code, 0) << clear.err;
  EXPECT_NE(clear.out.find("removed 7 entries"), std::string::npos) << clear.out;
  EXPECT_NE(run(dir, "cache --dir " + cache).out.find(": 0 entries, 0.0 MiB"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(cache + "/notes.txt"));
  // A folder that is not one: an error naming it; and usage errors.
  const CliRun file = run(dir, "cache --dir " + cache + "/notes.txt");
  EXPECT_EQ(file.code, 1);
  EXPECT_NE(file.err.find(cache + "/notes.txt: not a folder"), std::string::npos) << file.err;
  EXPECT_EQ(run(dir, "cache --frobnicate").code, 2);
  EXPECT_EQ(run(dir, "cache --dir").code, 2);
}

TEST(Cli, CompareReportsLinearErrors) {
  const std::string dir = test::test_dir();
  RgbImage a(4, 2), b(4, 2);
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    a.pixels[i] = Rgb(0.5f);
    b.pixels[i] = Rgb(i < 4 ? 0.5f : 0.3f);
  }
  write_float_image(dir + "/a.exr", a);
  write_float_image(dir + "/b.exr", b);
  const CliRun r = run(dir, "compare " + dir + "/a.exr " + dir + "/b.exr");
  ASSERT_EQ(r.code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_NEAR(j["mae"].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(j["rmse"].get<double>(), std::sqrt(0.02), 1e-6);
  EXPECT_NEAR(j["bias"].get<double>(), 0.1, 1e-6);
  EXPECT_NEAR(j["rel_bias"].get<double>(), 0.25, 1e-6);
  EXPECT_EQ(run(dir, "compare " + dir + "/a.exr").code, 2);
  const CliRun missing = run(dir, "compare " + dir + "/a.exr " + dir + "/none.exr");
  EXPECT_EQ(missing.code, 1);
  EXPECT_NE(missing.err.find("none.exr"), std::string::npos) << missing.err;
}

// A coverage mask of one object, and the error over the pixels it selects.
TEST(Cli, MaskObjectAndCompareWithAMask) {
  const std::string dir = test::test_dir();
  std::string text = small_scene(R"({"type": "knit", "pattern": ["KP", "PK"], "uv_scale": 12, "yarn_colors": [[0.7, 0.1, 0.1]]})");
  text.replace(text.find("\"objects\": [{"), 13, "\"objects\": [{\"name\": \"cloth\", ");
  const std::string scene = test::write_file(dir, "scene.json", text);
  const CliRun m = run(dir, "render " + scene + " -o " + dir + "/mask.exr --quiet --mask-object cloth");
  ASSERT_EQ(m.code, 0) << m.err;
  const RgbImage mask = read_rgb_image(dir + "/mask.exr");
  // The tilted quad covers the middle of the frame, not its top corners; the
  // mask sees the base mesh, whatever the yarn gaps let through.
  int full = 0, empty = 0;
  for (const Rgb& c : mask.pixels) {
    ASSERT_TRUE(c.r >= 0 && c.r <= 1) << c.r;
    full += c.r == 1.0f;
    empty += c.r == 0.0f;
  }
  EXPECT_EQ(mask.at(12, 8).r, 1.0f);
  EXPECT_EQ(mask.at(0, 0).r, 0.0f);
  EXPECT_GT(full, 50);
  EXPECT_GT(empty, 20);
  // --size widens the mask's film as it widens a render's: the middle 24
  // columns of a 48 x 16 mask are the 24 x 16 mask, up to the edge pixels'
  // coverage, which other samples estimate (measured: 22 of 384 differ,
  // none between empty and full, mean |difference| 0.014).
  const CliRun wide = run(dir, "render " + scene + " -o " + dir + "/mask_wide.exr --quiet --mask-object cloth --size 48x16");
  ASSERT_EQ(wide.code, 0) << wide.err;
  const RgbImage wmask = read_rgb_image(dir + "/mask_wide.exr");
  ASSERT_EQ(wmask.width, 48);
  ASSERT_EQ(wmask.height, 16);
  int differ = 0, swapped = 0;
  double diff_sum = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 24; ++x) {
      const float a = wmask.at(x + 12, y).r, b = mask.at(x, y).r;
      differ += std::fabs(a - b) > 1e-4f;
      swapped += std::fabs(a - b) == 1.0f;
      diff_sum += std::fabs(a - b);
    }
  std::printf("[size] mask: %d of 384 pixels differ, mean |difference| %.4f\n", differ, diff_sum / 384);
  EXPECT_EQ(swapped, 0);
  EXPECT_LT(diff_sum / 384, 0.03);
  EXPECT_LT(differ, 384 / 8);

  // Images equal inside the mask and different outside: no error with the mask.
  RgbImage a(mask.width, mask.height), b(mask.width, mask.height);
  int selected = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    const bool in = mask.pixels[i].r >= 0.5f;
    selected += in;
    a.pixels[i] = Rgb(0.5f);
    b.pixels[i] = Rgb(in ? 0.5f : 2.0f);
  }
  write_float_image(dir + "/a.exr", a);
  write_float_image(dir + "/b.exr", b);
  const CliRun c = run(dir, "compare " + dir + "/a.exr " + dir + "/b.exr --mask " + dir + "/mask.exr");
  ASSERT_EQ(c.code, 0) << c.err;
  const nlohmann::json j = nlohmann::json::parse(c.out);
  EXPECT_EQ(j["pixels"], selected);
  EXPECT_EQ(j["rmse"].get<double>(), 0.0);
  const nlohmann::json all = nlohmann::json::parse(run(dir, "compare " + dir + "/a.exr " + dir + "/b.exr").out);
  EXPECT_EQ(all["pixels"], mask.width * mask.height);
  EXPECT_GT(all["rmse"].get<double>(), 0.5);

  // Errors name what is wrong.
  const CliRun unknown = run(dir, "render " + scene + " -o " + dir + "/m2.exr --quiet --mask-object scarf");
  EXPECT_EQ(unknown.code, 1);
  EXPECT_NE(unknown.err.find("--mask-object scarf: no object of that name (objects: cloth)"), std::string::npos)
      << unknown.err;
  const CliRun tubes = run(dir, "render " + scene + " -o " + dir + "/m3.exr --quiet --explicit-yarns --mask-object cloth");
  EXPECT_EQ(tubes.code, 1);
  EXPECT_NE(tubes.err.find("explicit yarn tubes"), std::string::npos) << tubes.err;
  write_float_image(dir + "/small.exr", RgbImage(3, 3));
  const CliRun size = run(dir, "compare " + dir + "/a.exr " + dir + "/b.exr --mask " + dir + "/small.exr");
  EXPECT_EQ(size.code, 1);
  EXPECT_NE(size.err.find("small.exr: compare_images: the mask is 3x3, the images 24x16"), std::string::npos) << size.err;
  write_float_image(dir + "/zero.exr", RgbImage(mask.width, mask.height));
  const CliRun none = run(dir, "compare " + dir + "/a.exr " + dir + "/b.exr --mask " + dir + "/zero.exr");
  EXPECT_EQ(none.code, 1);
  EXPECT_NE(none.err.find("selects no pixel"), std::string::npos) << none.err;
}

TEST(Cli, UsageErrorsExitWith2AndBadOutputFailsBeforeRendering) {
  const std::string dir = test::test_dir();
  const std::string scene = test::write_file(dir, "scene.json", small_scene());
  EXPECT_EQ(run(dir, "render " + scene).code, 2);                        // no -o
  EXPECT_EQ(run(dir, "render -o x.png").code, 2);                        // no scene
  EXPECT_EQ(run(dir, "render " + scene + " -o x.png --spp zero").code, 2);
  EXPECT_EQ(run(dir, "render " + scene + " -o x.png --frobnicate").code, 2);
  const CliRun jpg = run(dir, "render " + scene + " -o " + dir + "/out.jpg");
  EXPECT_EQ(jpg.code, 1);
  EXPECT_NE(jpg.err.find("unsupported output format '.jpg' (use .exr or .png)"), std::string::npos) << jpg.err;
  const CliRun folder = run(dir, "render " + scene + " -o " + dir + "/no/such/folder/out.exr");
  EXPECT_EQ(folder.code, 1);
  EXPECT_NE(folder.err.find("the output folder " + dir + "/no/such/folder does not exist"), std::string::npos) << folder.err;
  const CliRun view = run(dir, "render " + scene + " -o " + dir + "/out.png --view NoSuchView");
  EXPECT_EQ(view.code, 1);
  EXPECT_NE(view.err.find("unknown view 'NoSuchView'"), std::string::npos) << view.err;
  EXPECT_EQ(run(dir, "render --help").code, 0);
}

TEST(Cli, BakeFrames) {
  const std::string dir = test::test_dir();
  const CliRun r = run(dir, "bake-frames " + test::mesh("half_cylinder.obj") + " -o " + dir + "/frames.exr --size 64x16");
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("baked 64x16 frames"), std::string::npos) << r.out;
  auto in = OIIO::ImageInput::open(dir + "/frames.exr");
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().nchannels, 8);
  EXPECT_EQ(in->spec().width, 64);

  const std::string no_uv = test::write_file(dir, "n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const CliRun bad = run(dir, "bake-frames " + no_uv + " -o " + dir + "/n.exr");
  EXPECT_EQ(bad.code, 1);
  EXPECT_EQ(lines(bad.err), 1);
  EXPECT_NE(bad.err.find("n.obj: the mesh has no UV coordinates"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace knit::render
