// `knitshade bake-frames`: the base mesh's normal and tangent over UV space,
// baked into a float EXR (channels and layout in docs/renderer.md#baked-frames).
#pragma once

#include <string>

#include "render/mesh.h"

namespace knit::render {

struct BakeSettings {
  int width = 1024, height = 1024;
  int dilate = 2;  // texel rings filled from covered neighbours, so bilinear lookups work at chart borders
};

struct BakeResult {
  int width = 0, height = 0;
  Vec2 uv_min, uv_max;   // UV rectangle the image covers
  size_t covered = 0;    // texels whose centre lies inside a UV triangle
};

// Channels (EXR keeps them sorted by name; read them by name): N.X N.Y N.Z
// (normal) T.X T.Y T.Z (tangent along +u) B.sign (+1 when cross(N, T) points
// along +v) A (1 covered, 0.5 dilated, 0 empty).
BakeResult bake_frames(const TriangleMesh& mesh, const std::string& path, const BakeSettings& settings);

}  // namespace knit::render
