// Mesh loading through assimp: triangulated, every sub-mesh merged into one
// TriangleMesh with node transforms applied, then validated.
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <assimp/Importer.hpp>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <sstream>
#include <string_view>
#include <vector>

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

// The file name's extension in lower case (".ply"); assimp picks a reader by it.
std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// Bytes of a PLY scalar type in binary files; 0 for an unknown name.
int ply_type_bytes(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

// Whether `t` is a decimal number as OBJ and PLY files write them: [+-] digits [. digits]
// [e [+-] digits], with digits on at least one side of the point.
bool is_decimal(std::string_view t) {
  size_t i = 0, digits = 0;
  const auto run = [&] {
    const size_t s = i;
    while (i < t.size() && t[i] >= '0' && t[i] <= '9') ++i;
    return i - s;
  };
  if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
  digits += run();
  if (i < t.size() && t[i] == '.') {
    ++i;
    digits += run();
  }
  if (digits == 0) return false;
  if (i < t.size() && (t[i] == 'e' || t[i] == 'E')) {
    ++i;
    if (i < t.size() && (t[i] == '+' || t[i] == '-')) ++i;
    if (run() == 0) return false;
  }
  return i == t.size();
}

// Whether the decimal number `t` (is_decimal) is finite in single
// precision; one too small for a double is 0, which is.
bool finite_as_float(std::string_view t) {
  const char* b = t.data() + (t[0] == '+' ? 1 : 0);
  double x = 0;
  const auto r = std::from_chars(b, t.data() + t.size(), x);
  if (r.ec == std::errc()) return std::fabs(x) <= double(std::numeric_limits<float>::max());
  // Out of a double's range: too large when the point's place, moved by the
  // exponent, lies right of the first digit (the exponent saturates)
  const size_t e = t.find_first_of("eE");
  const std::string_view m = t.substr(0, e);
  const size_t lead = m.find_first_of("123456789");
  const size_t point = std::min(m.find('.'), m.size());
  long exp10 = 0;
  if (e != std::string_view::npos) {
    // (is_decimal: an exponent has digits after its sign)
    const bool sign = t[e + 1] == '+' || t[e + 1] == '-';
    for (size_t i = e + 1 + (sign ? 1 : 0); i < t.size(); ++i)
      exp10 = std::min(exp10 * 10 + (t[i] - '0'), 100000L);
    if (t[e + 1] == '-') exp10 = -exp10;
  }
  return lead == std::string_view::npos || long(point) - long(lead) + exp10 <= 0;
}

// assimp 5.2's PLY reader does not stop on a header that never reaches
// end_header (it keeps seeking through the file: a hang), and trusts its
// element counts. A file that starts as PLY gets its header checked here
// first: known lines only, a format, counts the data after the header can
// hold (at least one byte per property of each element, whether ASCII or
// binary), and an end_header within the first 64 KiB.
void check_ply_header(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(65536, '\0');
  in.read(&head[0], static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<size_t>(in.gcount()));
  // (assimp takes a file for PLY by its extension or its first three bytes)
  if (head.compare(0, 3, "ply") != 0 && lower_extension(path) != ".ply") return;
  struct Element {
    std::string name;
    uint64_t count = 0, min_bytes = 0;  // entries; bytes each takes at least
    std::vector<bool> lists;             // per property: a list?
    std::vector<std::string> names;      // per property
  };
  std::vector<Element> elements;
  bool binary = false, have_format = false, ended = false;
  size_t pos = 0;
  int line = 0;
  auto bad = [&](const std::string& what) { fail(path, "PLY header line " + std::to_string(line) + ": " + what); };
  while (!ended) {
    const size_t nl = head.find('\n', pos);
    if (nl == std::string::npos) break;
    std::string text = head.substr(pos, nl - pos);
    pos = nl + 1;
    ++line;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    // Spaces and tabs only: assimp does not take a vertical tab or a form
    // feed for a separator, so a line of them, blank to the tokens below,
    // is not blank to it, and its binary reader then reads past the file's
    // data (a crash, found by fuzz_mesh, 2026-12-03).
    for (const char c : text)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') || c == 0x7f) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
        bad(std::string("a control character (") + hex + ") in the header: only text, spaces and tabs");
      }
    std::istringstream ss(text);
    std::vector<std::string> tok;
    for (std::string t; ss >> t;) tok.push_back(t);
    if (line == 1) {
      if (text != "ply") bad("a PLY file starts with a line 'ply'");
      continue;
    }
    if (tok.empty()) continue;
    const std::string& kw = tok[0];
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "format") {
      if (tok.size() != 3 || (tok[1] != "ascii" && tok[1] != "binary_little_endian" && tok[1] != "binary_big_endian"))
        bad("expected 'format ascii|binary_little_endian|binary_big_endian 1.0', got '" + text + "'");
      binary = tok[1] != "ascii";
      have_format = true;
    } else if (kw == "element") {
      if (tok.size() != 3 || tok[2].find_first_not_of("0123456789") != std::string::npos || tok[2].size() > 10)
        bad("expected 'element NAME COUNT', got '" + text + "'");
      // A name is a word: assimp 5.2 reads an element name's leading digits
      // as the element's count (9 GB and 17 s for a name of seventeen 7s,
      // found by fuzz_mesh, 2026-12-03).
      const unsigned char first = static_cast<unsigned char>(tok[1][0]);
      if (!std::isalpha(first) && first != '_')
        bad("the element name '" + tok[1] + "' does not start with a letter or '_'");
      Element e;
      e.name = tok[1];
      e.count = std::stoull(tok[2]);
      elements.push_back(e);
    } else if (kw == "property") {
      if (elements.empty()) bad("a property before any element: '" + text + "'");
      const bool list = tok.size() >= 2 && tok[1] == "list";
      if (list ? (tok.size() != 5 || !ply_type_bytes(tok[2]) || !ply_type_bytes(tok[3]))
               : (tok.size() != 3 || !ply_type_bytes(tok[1])))
        bad("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME', got '" + text + "'");
      elements.back().min_bytes += binary ? uint64_t(ply_type_bytes(list ? tok[2] : tok[1])) : 1;
      elements.back().lists.push_back(list);
      elements.back().names.push_back(tok.back());
    } else if (kw == "end_header") {
      ended = true;
    } else {
      bad("unknown header line '" + text + "'");
    }
  }
  if (!ended) fail(path, "the PLY header has no end_header line (in its first 64 KiB)");
  if (!have_format) fail(path, "the PLY header has no format line");
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  const uint64_t data = ec || size < pos ? 0 : size - pos;
  uint64_t need = 0;
  for (const Element& e : elements) {
    const uint64_t each = e.min_bytes > 0 ? e.min_bytes : 1;
    need += e.count * each;  // counts below 10^10, at most 8 bytes a property: no overflow
    if (need > data)
      fail(path, "the PLY header declares " + std::to_string(e.count) + " '" + e.name +
                     "' elements, more than the " + std::to_string(data) + " bytes after the header can hold");
  }
  if (binary) return;
  // ASCII data: every list's length must fit in the values left. assimp 5.2
  // takes a long time over a list longer than the file (13 s for a 290-byte
  // file whose face claimed 30,022 indices: found by fuzz_mesh, 2026-12-03).
  // And every value must be a decimal number finite in single precision
  // (is_decimal, finite_as_float): assimp reads a word as 0 and passes nan
  // and inf through, without a word; the error names the line and value.
  // The values are streamed, not kept.
  in.clear();
  in.seekg(static_cast<std::streamoff>(pos));
  std::istreambuf_iterator<char> it(in);
  const std::istreambuf_iterator<char> end;
  size_t at_line = size_t(line) + 1, token_line = 0;  // (the data starts after end_header's line)
  const auto space = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  // The next value (its first 64 bytes, and a 65th if there are more), or false at the end.
  const auto next = [&](std::string& t) {
    t.clear();
    for (; it != end && space(*it); ++it)
      if (*it == '\n') ++at_line;
    token_line = at_line;
    for (; it != end && !space(*it); ++it)
      if (t.size() <= 64) t += *it;
    return !t.empty();
  };
  const auto values_left = [&] {
    uint64_t n = 0;
    for (std::string t; next(t);) ++n;
    return n;
  };
  const auto check = [&](const std::string& t, const Element& e, uint64_t i, size_t p) {
    const bool decimal = t.size() <= 64 && is_decimal(t);
    if (decimal && finite_as_float(t)) return;
    fail(path, "line " + std::to_string(token_line) + ": '" + t.substr(0, 40) + "' for property '" + e.names[p] +
                   "' of '" + e.name + "' element " + std::to_string(i) + " is not " +
                   (decimal ? "finite in single precision" : "a number"));
  };
  std::string v, t;
  for (const Element& e : elements)
    for (uint64_t i = 0; i < e.count; ++i)
      for (size_t p = 0; p < e.lists.size(); ++p) {
        if (!next(v))
          fail(path, "the PLY data ends inside '" + e.name + "' element " + std::to_string(i) + " of " +
                         std::to_string(e.count));
        if (!e.lists[p]) {
          check(v, e, i, p);
          continue;
        }
        const bool number = !v.empty() && v.size() <= 10 && v.find_first_not_of("0123456789") == std::string::npos;
        const uint64_t n = number ? std::stoull(v) : 0;
        uint64_t k = 0;
        for (; k < n && next(t); ++k) check(t, e, i, p);
        if (!number || k < n)
          fail(path, "'" + e.name + "' element " + std::to_string(i) + " has a list of length '" + v +
                         "', more than the values left in the file (" + std::to_string(number ? k : values_left()) +
                         ")");
      }
}

// OBJ text: every value of a vertex line ('v', 'vt', 'vn') must be a
// decimal number that is finite in single precision. assimp 5.2 reads
// "nan", "inf" and "1e999" into positions and normals, turns them into 0 in
// UVs, and reads a word as 0, all without a word; this names the line and
// the value instead. A line ending in a backslash continues on the next.
void check_obj_numbers(const std::string& path) {
  if (lower_extension(path) != ".obj") return;
  std::ifstream in(path, std::ios::binary);
  std::string line, part;
  size_t number = 0;
  while (std::getline(in, line)) {
    const size_t first = ++number;
    // (continuations: the logical line is named by its first line)
    while (!line.empty() && (line.back() == '\r' || line.back() == '\\')) {
      if (line.back() == '\r') {
        line.pop_back();
        continue;
      }
      line.back() = ' ';
      if (!std::getline(in, part)) break;
      ++number;
      line += part;
    }
    const std::string_view text = std::string_view(line).substr(0, line.find('#'));
    const auto space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; };
    std::string_view key;
    size_t i = 0;
    for (int token = 0;; ++token) {
      while (i < text.size() && space(text[i])) ++i;
      if (i >= text.size()) break;
      const size_t s = i;
      while (i < text.size() && !space(text[i])) ++i;
      const std::string_view t = text.substr(s, i - s);
      if (token == 0) {
        key = t;
        if (key != "v" && key != "vt" && key != "vn") break;
        continue;
      }
      const auto bad = [&](const char* what) {
        fail(path, "line " + std::to_string(first) + ": '" + std::string(t.substr(0, 40)) + "' in a '" +
                       std::string(key) + "' line " + what);
      };
      if (!is_decimal(t)) bad("is not a number");
      if (!finite_as_float(t)) bad("is not finite in single precision");
    }
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, Warnings* warnings) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) fail(path, "mesh file not found");

  check_ply_header(path);
  check_obj_numbers(path);

  Assimp::Importer importer;
  // Points and lines are dropped; polygons are triangulated. No normal or
  // UV generation here: we compute normals ourselves, and UVs must be real.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read and validated alone first (ValidateDataStructure: assimp's own
  // check of what its importers made, face indices included), then the
  // faces checked for what assimp's post-processing asserts on (Debian
  // builds it with assertions: an abort, not an error), then processed.
  auto read = [&](const aiScene* s) {
    if (!s || !s->mRootNode) fail(path, std::string("cannot read mesh: ") + importer.GetErrorString());
    return s;
  };
  const aiScene* scene = read(importer.ReadFile(path, aiProcess_ValidateDataStructure));
  for (unsigned i = 0; i < scene->mNumMeshes; ++i) {
    const aiMesh* m = scene->mMeshes[i];
    for (unsigned f = 0; f < m->mNumFaces; ++f)
      if (m->mFaces[f].mNumIndices == 0 || m->mFaces[f].mIndices == nullptr)
        fail(path, "face " + std::to_string(f) + " of part " + std::to_string(i) + " has no vertices");
  }
  scene = read(importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices |
                                            aiProcess_SortByPType));

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
          // (in double: a normal of 1e38s overflows its length in float, and
          // a subnormal one its reciprocal, 1 / 8.8e-44 (found by fuzz_mesh,
          // 2026-12-03); tiny ones are directions too)
          const double nx = n.x, ny = n.y, nz = n.z, len = std::sqrt(nx * nx + ny * ny + nz * nz);
          if (!(len > 0) || !std::isfinite(len))
            fail(path, "vertex " + std::to_string(base + v) + " has a zero-length normal");
          out.normals.push_back(Vec3(float(nx / len), float(ny / len), float(nz / len)));
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
        for (unsigned corner = 0; corner < 3; ++corner)
          if (face.mIndices[corner] >= m->mNumVertices)
            fail(path, "face " + std::to_string(f) + " refers to vertex " + std::to_string(face.mIndices[corner]) +
                           " of " + std::to_string(m->mNumVertices));
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
