// libFuzzer harness for scene files (docs/scene-format.md): any input either
// parses to a scene description whose numbers are finite and whose sizes are
// within the documented limits, or throws a SceneError that names the file
// (and, for a field of the scene, its line and column, within the text).
// Anything else (a crash, another exception, a NaN that got through) aborts.
// Relative paths resolve against examples/scenes, so mutated inputs can reach
// the real meshes, patterns and environment map there. Built as `fuzz_scene`
// (clang, KNIT_FUZZ=ON) and as the corpus replay test with any compiler.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "render/errors.h"
#include "render/scene_desc.h"

namespace {

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_scene: %s\n%s\n", what, detail.c_str());
  std::abort();
}

void check_scene(const knit::render::SceneDesc& s) {
  if (s.film.width < 1 || s.film.width > 16384 || s.film.height < 1 || s.film.height > 16384 ||
      s.film.spp < 1) {
    fail("film out of limits", std::to_string(s.film.width) + "x" + std::to_string(s.film.height));
  }
  if (!std::isfinite(s.film.exposure)) fail("exposure not finite", "");
  const auto& c = s.camera;
  for (float v : {c.position.x, c.position.y, c.position.z, c.look_at.x, c.look_at.y, c.look_at.z, c.fov})
    if (!std::isfinite(v)) fail("camera number not finite", "");
  if (!(c.fov > 0 && c.fov < 180)) fail("fov out of range", std::to_string(c.fov));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    check_scene(knit::render::parse_scene(text, "<fuzz>", KNIT_FUZZ_SCENE_DIR));
  } catch (const knit::render::SceneError& e) {
    const std::string msg = e.what();
    if (e.file() != "<fuzz>" && msg.find("<fuzz>") == std::string::npos &&
        msg.find(KNIT_FUZZ_SCENE_DIR) == std::string::npos) {
      fail("error does not name the scene or the asset file", msg);
    }
    if (msg.size() < e.file().size() + 3) fail("error without a message", msg);
    // An error about a field of the scene names its line and column, and
    // they lie in the text.
    if (e.file() == "<fuzz>" && !e.path().empty() && e.line() == 0) fail("error without a position", msg);
    if (e.line() > 0) {
      size_t start = 0;
      for (int l = 1; l < e.line(); ++l) {
        start = text.find('\n', start);
        if (start == std::string::npos) fail("error's line beyond the text", msg);
        ++start;
      }
      const size_t end = std::min(text.find('\n', start), text.size());
      if (e.column() < 1 || size_t(e.column()) > end - start + 1) fail("error's column beyond its line", msg);
    }
  }
  return 0;
}
