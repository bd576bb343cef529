// libFuzzer harness for mesh files (docs/scene-format.md, "Meshes"): any
// input either loads into a mesh that passes the loader's own checks
// (finite positions and UVs, unit normals and tangents, triangle indices
// in range) or throws a MeshError that names the file.
// Anything else (a crash, a hang, another exception) is a finding. Input
// starting with "ply" is written as a .ply file, anything else as .obj: the
// two formats the examples use, read by Debian's assimp behind the loader's
// checks. Built as `fuzz_mesh` (clang, KNIT_FUZZ=ON) and as the corpus
// replay test with any compiler.
#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "render/mesh.h"

namespace {

[[noreturn]] void fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz_mesh: %s\n%s\n", what, detail.c_str());
  std::abort();
}

// Finite and of unit length (within float rounding of the normalisation).
bool unit(knit::render::Vec3 v) {
  return knit::render::is_finite(v) && std::fabs(knit::render::dot(v, v) - 1.0f) <= 1e-3f;
}

void check_mesh(const knit::render::TriangleMesh& m) {
  const size_t n = m.positions.size();
  if (m.indices.empty() || m.indices.size() % 3 != 0) fail("no whole triangles", std::to_string(m.indices.size()));
  for (uint32_t i : m.indices)
    if (i >= n) fail("index out of range", std::to_string(i) + " of " + std::to_string(n));
  for (const auto& p : m.positions)
    if (!knit::render::is_finite(p)) fail("non-finite position", "");
  if (m.normals.size() != n) fail("normals missing", std::to_string(m.normals.size()));
  for (const auto& v : m.normals)
    if (!unit(v)) fail("normal not unit", "");
  if (m.has_uvs()) {
    for (const auto& uv : m.uvs)
      if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) fail("non-finite UV", "");
    if (m.tangents.size() != n || m.tangent_sign.size() != n) fail("tangents missing", "");
    for (const auto& t : m.tangents)
      if (!unit(t)) fail("tangent not unit", "");
  }
}

// One scratch file per process (libFuzzer runs inputs one after another).
std::string scratch(const char* ext) {
  return "/tmp/knit_fuzz_mesh_" + std::to_string(getpid()) + "." + ext;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const bool ply = size >= 3 && data[0] == 'p' && data[1] == 'l' && data[2] == 'y';
  const std::string path = scratch(ply ? "ply" : "obj");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    if (!out) fail("cannot write the scratch file", path);
  }
  try {
    check_mesh(knit::render::load_mesh(path));
  } catch (const knit::render::MeshError& e) {
    const std::string msg = e.what();
    if (msg.find(path) == std::string::npos) fail("error does not name the file", msg);
    if (msg.size() < path.size() + 3) fail("error without a message", msg);
  }
  std::remove(path.c_str());
  return 0;
}
