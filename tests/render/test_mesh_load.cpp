// Mesh loading through assimp: OBJ and PLY, with and without UVs and normals,
// computed smooth normals and tangents, degenerate triangles, mirroring.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "render/mesh.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

void expect_vec_near(Vec3 a, Vec3 b, float tol, const char* what) {
  EXPECT_NEAR(a.x, b.x, tol) << what;
  EXPECT_NEAR(a.y, b.y, tol) << what;
  EXPECT_NEAR(a.z, b.z, tol) << what;
}

// A unit square in the xy plane, 2 triangles; optional UVs (mirrored in u on request).
std::string square_obj(bool uvs, bool normals, bool mirror_u = false) {
  std::string s = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
  if (uvs) {
    s += mirror_u ? "vt 1 0\nvt 0 0\nvt 0 1\nvt 1 1\n" : "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
  }
  if (normals) s += "vn 0 0 1\n";
  auto corner = [&](int i) {
    std::string c = std::to_string(i);
    if (uvs && normals) return c + "/" + c + "/1";
    if (uvs) return c + "/" + c;
    if (normals) return c + "//1";
    return c;
  };
  s += "f " + corner(1) + " " + corner(2) + " " + corner(3) + "\n";
  s += "f " + corner(1) + " " + corner(3) + " " + corner(4) + "\n";
  return s;
}

std::string square_ply(bool uvs) {
  std::string s = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
  if (uvs) s += "property float s\nproperty float t\n";
  s += "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  s += uvs ? "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n" : "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
  s += "3 0 1 2\n3 0 2 3\n";
  return s;
}

TEST(MeshLoad, ObjWithUvsAndNormals) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(test::write_file(dir, "sq.obj", square_obj(true, true)));
  EXPECT_EQ(m.num_triangles(), 2u);
  EXPECT_TRUE(m.has_uvs());
  EXPECT_TRUE(m.normals_from_file);
  ASSERT_EQ(m.tangents.size(), m.positions.size());
  for (size_t v = 0; v < m.positions.size(); ++v) {
    expect_vec_near(m.normals[v], {0, 0, 1}, 1e-6f, "normal");
    expect_vec_near(m.tangents[v], {1, 0, 0}, 1e-6f, "tangent along +u");
    EXPECT_EQ(m.tangent_sign[v], 1.0f);
  }
}

TEST(MeshLoad, ObjWithoutUvsOrNormalsGetsSmoothNormals) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(test::write_file(dir, "sq.obj", square_obj(false, false)));
  EXPECT_EQ(m.num_triangles(), 2u);
  EXPECT_FALSE(m.has_uvs());
  EXPECT_FALSE(m.normals_from_file);
  EXPECT_TRUE(m.tangents.empty());
  for (const Vec3& n : m.normals) expect_vec_near(n, {0, 0, 1}, 1e-6f, "computed normal");
}

TEST(MeshLoad, PlyWithAndWithoutUvs) {
  const std::string dir = test::test_dir();
  const TriangleMesh a = load_mesh(test::write_file(dir, "uv.ply", square_ply(true)));
  EXPECT_EQ(a.num_triangles(), 2u);
  ASSERT_TRUE(a.has_uvs());
  for (size_t v = 0; v < a.positions.size(); ++v) {
    EXPECT_NEAR(a.uvs[v].x, a.positions[v].x, 1e-6f);
    EXPECT_NEAR(a.uvs[v].y, a.positions[v].y, 1e-6f);
  }
  const TriangleMesh b = load_mesh(test::write_file(dir, "plain.ply", square_ply(false)));
  EXPECT_EQ(b.num_triangles(), 2u);
  EXPECT_FALSE(b.has_uvs());
  for (const Vec3& n : b.normals) expect_vec_near(n, {0, 0, 1}, 1e-6f, "computed normal");
}

TEST(MeshLoad, MirroredUvsFlipTheTangentSign) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(test::write_file(dir, "mirror.obj", square_obj(true, true, true)));
  for (size_t v = 0; v < m.positions.size(); ++v) {
    expect_vec_near(m.tangents[v], {-1, 0, 0}, 1e-6f, "tangent along +u (which runs toward -x)");
    // b = sign * cross(n, t) must point along +v = +y.
    const Vec3 b = cross(m.normals[v], m.tangents[v]) * m.tangent_sign[v];
    expect_vec_near(b, {0, 1, 0}, 1e-6f, "bitangent along +v");
  }
}

TEST(MeshLoad, SmoothNormalsAcrossUvSeams) {
  // The generated sphere has a UV seam (duplicated vertices); computed normals
  // must agree across it and point outward.
  const TriangleMesh sphere = load_mesh(test::mesh("sphere.obj"));
  TriangleMesh m = sphere;
  compute_smooth_normals(m);
  float worst = 0;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3 expected = normalize(m.positions[v]);
    worst = std::max(worst, length(m.normals[v] - expected));
  }
  EXPECT_LT(worst, 2e-3f);
}

TEST(MeshLoad, TangentsFollowUOnTheHalfCylinder) {
  const TriangleMesh m = load_mesh(test::mesh("half_cylinder.obj"));
  ASSERT_TRUE(m.has_uvs());
  for (size_t v = 0; v < m.positions.size(); v += 7) {
    const float s = m.uvs[v].x / 3.14159265f;  // u = pi * s on a unit radius
    const Vec3 expected_t(std::sin(3.14159265f * s), 0, std::cos(3.14159265f * s));
    expect_vec_near(m.tangents[v], expected_t, 2e-3f, "tangent");
    EXPECT_EQ(m.tangent_sign[v], 1.0f);
  }
}

TEST(MeshLoad, DegenerateTrianglesAreDroppedWithAWarning) {
  const std::string dir = test::test_dir();
  // Two good triangles, one with a repeated vertex, one with collinear points.
  const std::string path = test::write_file(
      dir, "deg.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\nf 1 3 4\nf 1 2 5\n");
  Warnings w;
  const TriangleMesh m = load_mesh(path, &w);
  EXPECT_EQ(m.num_triangles(), 2u);
  EXPECT_EQ(m.degenerate_removed, 2u);
  ASSERT_EQ(w.messages.size(), 1u);
  EXPECT_NE(w.messages[0].find("deg.obj: skipped 2 degenerate triangles of 4 (first: triangle 1)"), std::string::npos)
      << w.messages[0];
}

// The loader's error for `path`, or "(no error)".
std::string error_of(const std::string& path) {
  try {
    load_mesh(path);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(MeshLoad, Errors) {
  const std::string dir = test::test_dir();
  EXPECT_NE(error_of(dir + "/none.obj").find("none.obj: mesh file not found"), std::string::npos);
  const std::string garbage = test::write_file(dir, "garbage.ply", "ply\nthis is not a ply file\n");
  EXPECT_NE(error_of(garbage).find("garbage.ply: "), std::string::npos);
  const std::string inf = test::write_file(dir, "inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e999 0\nf 1 2 3\n");
  EXPECT_NE(error_of(inf).find("inf.obj: line 3: '1e999' in a 'v' line is not finite in single precision"),
            std::string::npos)
      << error_of(inf);
  // (an ASCII PLY file's values are checked before assimp reads them, each
  // named by its line, property and element; in a binary one they are
  // found in what assimp read, named by the vertex)
  const std::string nan_uv = test::write_file(
      dir, "nanuv.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0\n1 0 0 nan 0\n0 1 0 0 1\n3 0 1 2\n");
  EXPECT_NE(error_of(nan_uv).find("nanuv.ply: line 13: 'nan' for property 's' of 'vertex' element 1 is not a number"),
            std::string::npos)
      << error_of(nan_uv);
  const std::string nan_n = test::write_file(dir, "nann.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 nan\nf 1//1 2//1 3//1\n");
  EXPECT_NE(error_of(nan_n).find("nann.obj: line 4: 'nan' in a 'vn' line is not a number"), std::string::npos)
      << error_of(nan_n);
  const std::string nan_pn = test::write_file(
      dir, "nanpn.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 nan 1\n3 0 1 2\n");
  EXPECT_NE(error_of(nan_pn).find("nanpn.ply: line 15: 'nan' for property 'ny' of 'vertex' element 2 is not a number"),
            std::string::npos)
      << error_of(nan_pn);
  // a word, a value beyond single precision, a face index that is no number
  const std::string ply_head =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string word = test::write_file(dir, "word.ply", ply_head + "0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(error_of(word).find("word.ply: line 11: 'zero' for property 'y' of 'vertex' element 1 is not a number"),
            std::string::npos)
      << error_of(word);
  const std::string big = test::write_file(dir, "big.ply", ply_head + "0 0 0\n1 0 0\n0 1 -1e39\n3 0 1 2\n");
  EXPECT_NE(error_of(big).find("big.ply: line 12: '-1e39' for property 'z' of 'vertex' element 2 is not finite"),
            std::string::npos)
      << error_of(big);
  const std::string index = test::write_file(dir, "index.ply", ply_head + "0 0 0\n1 0 0\n0 1 0\n\n3 0 1 two\n");
  EXPECT_NE(error_of(index).find("index.ply: line 14: 'two' for property 'vertex_indices' of 'face' element 0 is not "
                                 "a number"),
            std::string::npos)
      << error_of(index);
  // and what is fine: signs, exponents, a point on either side, CRLF
  const std::string fine =
      test::write_file(dir, "fine.ply", ply_head + "0 0 0\r\n1.5e0 -0 .0\r\n0 +1. 1E-400\r\n3 0 1 2\r\n");
  EXPECT_EQ(error_of(fine), "(no error)");
  const std::string zero_n = test::write_file(dir, "zeron.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n");
  EXPECT_NE(error_of(zero_n).find("zeron.obj: vertex 0 has a zero-length normal"), std::string::npos) << error_of(zero_n);
}

// An OBJ file's vertex lines are read before assimp reads them (which
// would take a word or an infinite UV for 0 without a word): each bad
// value is an error naming its line.
TEST(MeshLoad, ObjVertexValuesAreCheckedWithTheirLine) {
  const std::string dir = test::test_dir();
  const std::string tri = "f 1/1 2/2 3/3\n";
  const auto obj = [&](const std::string& name, const std::string& vertices) {
    return error_of(test::write_file(dir, name, vertices + tri));
  };
  const std::string uvs = "vt 0 0\nvt 1 0\nvt 0 1\n";
  EXPECT_NE(obj("uv_inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 inf\nvt 0 1\n")
                .find("uv_inf.obj: line 5: 'inf' in a 'vt' line is not a number"),
            std::string::npos);
  EXPECT_NE(obj("uv_big.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 -3.5e38\n")
                .find("uv_big.obj: line 6: '-3.5e38' in a 'vt' line is not finite in single precision"),
            std::string::npos);
  EXPECT_NE(obj("word.obj", "# a triangle\nv 0 0 0\nv one 0 0\nv 0 1 0\n" + uvs)
                .find("word.obj: line 3: 'one' in a 'v' line is not a number"),
            std::string::npos);
  EXPECT_NE(obj("hex.obj", "v 0 0 0\nv 0x1p0 0 0\nv 0 1 0\n" + uvs)
                .find("hex.obj: line 2: '0x1p0' in a 'v' line is not a number"),
            std::string::npos);
  EXPECT_NE(obj("exp.obj", "v 0 0 0\nv 1e 0 0\nv 0 1 0\n" + uvs)
                .find("exp.obj: line 2: '1e' in a 'v' line is not a number"),
            std::string::npos);
  // A continued line is named by its first line; the lines after count on.
  EXPECT_NE(obj("cont.obj", "v 0 0 \\\n 0\nv 1 0 0\nv 0 1 nan\n" + uvs)
                .find("cont.obj: line 4: 'nan' in a 'v' line is not a number"),
            std::string::npos);

  // What is fine: CRLF line ends, a continuation, a comment after the
  // values, signs, exponents, a point on either side, a fourth value, and
  // (in lines no face uses) a number below a double's range (0) and the
  // largest float.
  const std::string good = test::write_file(
      dir, "good.obj",
      "v 0 0 0\r\nv 1 \\\r\n 0 0 # the second corner\r\nv -.0 +1. 25e2 1\nv 1e-400 0 0\n"
      "vt 0 0\nvt 1E+0 0\nvt 0 1\nvt 3.4028234e38 0\nf 1/1 2/2 3/3\n");
  TriangleMesh m;
  ASSERT_NO_THROW(m = load_mesh(good)) << error_of(good);
  ASSERT_EQ(m.num_triangles(), 1u);
  float max_x = 0, max_z = 0;
  for (const Vec3& p : m.positions) {
    max_x = std::max(max_x, p.x);
    max_z = std::max(max_z, p.z);
  }
  EXPECT_EQ(max_x, 1.0f);
  EXPECT_EQ(max_z, 2500.0f);
}

// assimp 5.2's PLY reader hangs on a header that never reaches end_header
// and crashes in its post-processing on a face index beyond the vertices
// (both found by mutating the examples' meshes, 2026-11-23; the files are in
// tests/fuzz/corpus/mesh/found-*). The loader checks a PLY header itself
// and has assimp validate what it read: each case is a one-line error.
TEST(MeshLoad, MalformedPlyFilesGiveErrorsNotHangsOrCrashes) {
  const std::string dir = test::test_dir();
  const std::string vertex_header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string unended = test::write_file(dir, "unended.ply", vertex_header + "element face 2\nproper");
  EXPECT_NE(error_of(unended).find("unended.ply: the PLY header has no end_header line"), std::string::npos)
      << error_of(unended);
  const std::string no_end = test::write_file(dir, "noend.ply", vertex_header + "0 0 0\n1 0 0\n");
  EXPECT_NE(error_of(no_end).find("noend.ply: PLY header line 7: unknown header line '0 0 0'"), std::string::npos)
      << error_of(no_end);
  const std::string first = test::write_file(dir, "first.ply", "ply\xd6\nformat ascii 1.0\nelement vertex 4\nprort");
  EXPECT_NE(error_of(first).find("first.ply: PLY header line 1: a PLY file starts with a line 'ply'"),
            std::string::npos)
      << error_of(first);
  // (a line of vertical tabs after the face's list property, in a binary
  // file: assimp's reader crashed on it, found by fuzz_mesh 2026-12-03; the
  // file is tests/fuzz/corpus/mesh/found-ply-crash-vertical-tab.ply)
  const std::string vtab = test::write_file(dir, "vtab.ply",
                                            "ply\nformat binary_little_endian 1.0\nelement vertex 0\n\x0b\x0b\nend_header\n");
  EXPECT_NE(error_of(vtab).find("vtab.ply: PLY header line 4: a control character (0x0b) in the header"),
            std::string::npos)
      << error_of(vtab);
  // (an ASCII face claiming 30,022 indices: assimp spent 13 s on it, found
  // by fuzz_mesh 2026-12-03)
  const std::string long_list = test::write_file(
      dir, "longlist.ply",
      vertex_header + "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n30022 0 1 2\n");
  EXPECT_NE(error_of(long_list).find("longlist.ply: 'face' element 0 has a list of length '30022', more than the "
                                     "values left in the file (3)"),
            std::string::npos)
      << error_of(long_list);
  // (an element named '77777777777777777vertex': assimp read its digits as
  // a count of 266 million vertices and allocated 9 GB for them, found by
  // fuzz_mesh 2026-12-03; the file is
  // tests/fuzz/corpus/mesh/found-ply-slow-digit-name.ply)
  const std::string digit_name = test::write_file(
      dir, "digitname.ply", "ply\nformat ascii 1.0\nelement 77777777777777777vertex 4\nproperty float x\nend_header\n");
  EXPECT_NE(error_of(digit_name).find("digitname.ply: PLY header line 3: the element name '77777777777777777vertex' "
                                      "does not start with a letter or '_'"),
            std::string::npos)
      << error_of(digit_name);
  const std::string short_data =
      test::write_file(dir, "short.ply", vertex_header + "end_header\n0 0 0\n1 0 0\n1 1\n");
  EXPECT_NE(error_of(short_data).find("short.ply: the PLY data ends inside 'vertex' element 2 of 4"),
            std::string::npos)
      << error_of(short_data);
  const std::string no_format = test::write_file(dir, "noformat.ply", "ply\nelement vertex 0\nend_header\n");
  EXPECT_NE(error_of(no_format).find("noformat.ply: the PLY header has no format line"), std::string::npos)
      << error_of(no_format);
  const std::string bad_type = test::write_file(dir, "type.ply", vertex_header + "property floatx s\nend_header\n");
  EXPECT_NE(error_of(bad_type).find("type.ply: PLY header line 7: expected 'property TYPE NAME'"), std::string::npos)
      << error_of(bad_type);
  const std::string huge = test::write_file(
      dir, "huge.ply",
      vertex_header + "element face 100000000\nproperty list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(error_of(huge).find("huge.ply: the PLY header declares 100000000 'face' elements, more than the"),
            std::string::npos)
      << error_of(huge);
  const std::string index = test::write_file(
      dir, "index.ply",
      vertex_header + "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
                      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 999999999 3\n");
  EXPECT_NE(error_of(index).find("index.ply: cannot read mesh: Validation failed: aiMesh::mFaces[1]::mIndices[1] is "
                                 "out of range"),
            std::string::npos)
      << error_of(index);
  // What the check must let through: binary PLY, comments, CRLF lines, a quad.
  std::string bin =
      "ply\r\nformat binary_little_endian 1.0\r\ncomment written by hand\r\nelement vertex 4\r\n"
      "property float x\r\nproperty float y\r\nproperty float z\r\nproperty float u\r\nproperty float v\r\n"
      "element face 1\r\nproperty list uchar int vertex_indices\r\nend_header\n";
  const float verts[4][5] = {{0, 0, 0, 0, 0}, {1, 0, 0, 1, 0}, {1, 1, 0, 1, 1}, {0, 1, 0, 0, 1}};
  bin.append(reinterpret_cast<const char*>(verts), sizeof verts);
  bin.push_back(char(4));
  const int32_t quad[4] = {0, 1, 2, 3};
  bin.append(reinterpret_cast<const char*>(quad), sizeof quad);
  const TriangleMesh m = load_mesh(test::write_file(dir, "bin.ply", bin));
  EXPECT_EQ(m.num_triangles(), 2u);
  ASSERT_TRUE(m.has_uvs());
  EXPECT_EQ(m.positions.size(), 4u);
}

// A file normal of 1e38s overflowed its length, and the normal became zero
// (found by the mesh fuzzer); scaled first, it is the direction it gives. A
// subnormal one (8.8e-44) overflowed the scale's reciprocal and became NaN
// (fuzz_mesh, 2026-12-03; tests/fuzz/corpus/mesh/found-ply-subnormal-normal.ply).
TEST(MeshLoad, HugeAndTinyFileNormalsAreDirections) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(test::write_file(
      dir, "bign.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 1e38 1e38\nvn 0 0 1e-30\nf 1//1 2//2 3//1\n"));
  ASSERT_TRUE(m.normals_from_file);
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3 n = m.normals[v];
    EXPECT_NEAR(length(n), 1.0f, 1e-6f) << v;
    EXPECT_TRUE(std::fabs(n.z - 1.0f) < 1e-6f || std::fabs(n.y - 0.70710678f) < 1e-6f) << v;
  }
  const TriangleMesh sub = load_mesh(test::write_file(
      dir, "subn.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0 8.8e-44 0 0\n1 0 0 0 0 1\n0 1 0 0 -3e-45 3e-45\n3 0 1 2\n"));
  ASSERT_TRUE(sub.normals_from_file);
  ASSERT_EQ(sub.normals.size(), 3u);
  expect_vec_near(sub.normals[0], Vec3(1, 0, 0), 1e-6f, "subnormal x");
  expect_vec_near(sub.normals[1], Vec3(0, 0, 1), 1e-6f, "unit z");
  expect_vec_near(sub.normals[2], Vec3(0, -0.70710678f, 0.70710678f), 1e-6f, "subnormal -y +z");
}

TEST(MeshLoad, MirroringTransformKeepsWindingAndNormalsConsistent) {
  const TriangleMesh m = load_mesh(test::mesh("quad.obj"));
  const TriangleMesh w = transform_mesh(m, Transform::scale({-1, 1, 1}));
  for (size_t t = 0; t < w.num_triangles(); ++t) {
    const Vec3 p0 = w.positions[w.indices[3 * t]], p1 = w.positions[w.indices[3 * t + 1]],
               p2 = w.positions[w.indices[3 * t + 2]];
    const Vec3 ng = normalize(cross(p1 - p0, p2 - p0));
    EXPECT_GT(dot(ng, w.normals[w.indices[3 * t]]), 0.99f);
  }
  for (size_t v = 0; v < w.positions.size(); ++v) {
    expect_vec_near(w.tangents[v], {-1, 0, 0}, 1e-6f, "tangent mirrored with the geometry");
    expect_vec_near(cross(w.normals[v], w.tangents[v]) * w.tangent_sign[v], {0, 1, 0}, 1e-6f, "bitangent along +v");
  }
}

}  // namespace
}  // namespace knit::render
