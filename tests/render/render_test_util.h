// Shared helpers of the renderer tests: per-test output folders, scene files
// written from text, small renders, image statistics.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "render/renderer.h"
#include "render/scene.h"
#include "render/scene_desc.h"

namespace knit::render::test {

inline std::string source_dir() { return KNIT_SOURCE_DIR; }
inline std::string meshes_dir() { return source_dir() + "/examples/scenes/meshes"; }
inline std::string mesh(const std::string& name) { return meshes_dir() + "/" + name; }

// KNIT_TEST_OUTPUT_DIR/render/<suite>.<test>/, created empty.
inline std::string test_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = std::string(info->test_suite_name()) + "." + info->name();
  for (char& c : name)
    if (c == '/') c = '_';
  const std::filesystem::path p = std::filesystem::path(KNIT_TEST_OUTPUT_DIR) / "render" / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline std::string write_file(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream f(path, std::ios::binary);
  f << text;
  return path;
}

inline std::string read_file(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  std::ostringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

// A rendered image, the render's result and the scene's warnings.
struct Rendered {
  RgbImage image;
  RenderResult result;
  Warnings warnings;
};

// Builds and renders a scene description with its film's spp and seed.
inline Rendered render_desc(const SceneDesc& desc, int threads = 0, BuildOptions options = {}) {
  Rendered r;
  r.warnings = desc.warnings;
  const Scene scene(desc, options, r.warnings);
  RenderSettings s;
  s.spp = desc.film.spp;
  s.seed = desc.film.seed;
  s.threads = threads;
  r.result = render_image(scene, s);
  r.image = r.result.image;
  return r;
}

// Renders scene text (written as <dir>/scene.json).
inline Rendered render_text(const std::string& dir, const std::string& scene_text, int threads = 0,
                            BuildOptions options = {}) {
  return render_desc(load_scene_file(write_file(dir, "scene.json", scene_text)), threads, options);
}

inline double mean_channel_value(const RgbImage& img) {
  double s = 0;
  for (const Rgb& p : img.pixels) s += static_cast<double>(p.r) + p.g + p.b;
  return s / (3.0 * static_cast<double>(img.pixels.size()));
}

// Runs `fn`, expects a SceneError, returns its message.
template <class Fn>
std::string scene_error_of(Fn&& fn) {
  try {
    fn();
  } catch (const SceneError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected a SceneError, got another exception: " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "expected a SceneError, nothing was thrown";
  return "";
}

}  // namespace knit::render::test
