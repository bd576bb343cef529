// Mesh loading through assimp: triangulated, every sub-mesh merged into one
// TriangleMesh with node transforms applied, then validated.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <functional>

#include "render/mesh.h"

namespace knit::render {

namespace {

Transform to_transform(const aiMatrix4x4& m) {
  return Transform({m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1,
                    m.d2, m.d3, m.d4});
}

[[noreturn]] void fail(const std::string& file, const std::string& msg) {
  throw MeshError(file + ": " + msg);
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, Warnings* warnings) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "mesh file not found");

  Assimp::Importer importer;
  // Points and lines are dropped; polygons are triangulated. No normal or
  // UV generation here: we compute normals ourselves, and UVs must be real.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) fail(path, std::string("cannot read mesh: ") + importer.GetErrorString());

  TriangleMesh out;
  out.file = path;
  // A part without normals or UVs makes the whole mesh lack them.
  bool all_normals = true, all_uvs = true, any_part = false;
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[i];
    if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    any_part = true;
    all_normals = all_normals && m->HasNormals();
    all_uvs = all_uvs && m->HasTextureCoords(0);
  }
  if (!any_part) fail(path, "the file contains no triangles");

  std::function<void(const aiNode*, const Transform&)> visit = [&](const aiNode* node,
                                                                   const Transform& parent) {
    const Transform xf = parent * to_transform(node->mTransformation);
    const bool identity = xf.is_identity();
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const aiMesh* m = scene->mMeshes[node->mMeshes[k]];
      if (!(m->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
      const uint32_t base = static_cast<uint32_t>(out.positions.size());
      for (unsigned v = 0; v < m->mNumVertices; ++v) {
        Vec3 p(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z);
        if (!is_finite(p))
          fail(path, "vertex " + std::to_string(base + v) + " has a non-finite position");
        out.positions.push_back(identity ? p : xf.point(p));
        if (all_normals) {
          Vec3 n(m->mNormals[v].x, m->mNormals[v].y, m->mNormals[v].z);
          if (!is_finite(n))
            fail(path, "vertex " + std::to_string(base + v) + " has a non-finite normal");
          if (!identity) n = xf.normal(n);
          const float l = length(n);
          if (!(l > 1e-20f)) fail(path, "vertex " + std::to_string(base + v) + " has a zero-length normal");
          out.normals.push_back(n / l);
        }
        if (all_uvs) {
          Vec2 uv(m->mTextureCoords[0][v].x, m->mTextureCoords[0][v].y);
          if (!std::isfinite(uv.x) || !std::isfinite(uv.y))
            fail(path, "vertex " + std::to_string(base + v) + " has a non-finite UV");
          out.uvs.push_back(uv);
        }
      }
      const bool flip = xf.determinant3() < 0;
      for (unsigned f = 0; f < m->mNumFaces; ++f) {
        const aiFace& face = m->mFaces[f];
        if (face.mNumIndices != 3) continue;
        const uint32_t a = base + face.mIndices[0];
        uint32_t b = base + face.mIndices[1], c = base + face.mIndices[2];
        if (flip) std::swap(b, c);
        out.indices.insert(out.indices.end(), {a, b, c});
      }
    }
    for (unsigned c = 0; c < node->mNumChildren; ++c) visit(node->mChildren[c], xf);
  };
  visit(scene->mRootNode, Transform());

  const size_t total = out.num_triangles();
  if (total == 0) fail(path, "the file contains no triangles");
  size_t first_bad = 0;
  const size_t removed = remove_degenerate_triangles(out, &first_bad);
  if (out.num_triangles() == 0)
    fail(path, "all " + std::to_string(total) + " triangles are degenerate (first: triangle " +
                   std::to_string(first_bad) + ")");
  if (removed > 0 && warnings)
    warnings->add(path + ": skipped " + std::to_string(removed) + " degenerate triangle" +
                  (removed == 1 ? "" : "s") + " of " + std::to_string(total) + " (first: triangle " +
                  std::to_string(first_bad) + ")");
  out.degenerate_removed = removed;
  out.normals_from_file = all_normals;
  if (!all_normals) compute_smooth_normals(out);
  if (out.has_uvs()) compute_tangents(out);
  return out;
}

}  // namespace knit::render
