#include "render/frame_bake.h"

#include <OpenImageIO/imageio.h>

#include <cctype>
#include <stdexcept>

#include "render/mesh_frame.h"
#include "render/uv_grid.h"

namespace knit::render {

namespace OIIO = OIIO_NAMESPACE;

BakeResult bake_frames(const TriangleMesh& mesh, const std::string& path, const BakeSettings& s) {
  if (!mesh.has_uvs()) throw std::runtime_error(mesh.file + ": the mesh has no UV coordinates to bake over");
  {
    std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : "";
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".exr") throw std::runtime_error(path + ": baked frames are written as EXR (use a .exr file name)");
  }
  if (s.width < 1 || s.height < 1 || s.width > 16384 || s.height > 16384)
    throw std::runtime_error("bake resolution must be in [1, 16384]");
  const UvTriangleGrid grid(mesh);
  if (grid.num_triangles() == 0) throw std::runtime_error(mesh.file + ": no triangle has a non-zero UV area");
  BakeResult r;
  r.width = s.width;
  r.height = s.height;
  r.uv_min = grid.uv_min();
  r.uv_max = grid.uv_max();
  const int w = s.width, h = s.height;
  std::vector<float> img(static_cast<size_t>(w) * h * 8, 0.0f);
  auto texel = [&](int x, int y) { return &img[(static_cast<size_t>(y) * w + x) * 8]; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const Vec2 uv = {r.uv_min.x + (static_cast<float>(x) + 0.5f) / static_cast<float>(w) * (r.uv_max.x - r.uv_min.x),
                       r.uv_max.y - (static_cast<float>(y) + 0.5f) / static_cast<float>(h) * (r.uv_max.y - r.uv_min.y)};
      float b1, b2;
      const int64_t tri = grid.locate(uv, b1, b2);
      if (tri < 0) continue;
      const Frame f = interpolate_frame(mesh, static_cast<size_t>(tri), b1, b2);
      float* p = texel(x, y);
      p[0] = f.n.x, p[1] = f.n.y, p[2] = f.n.z;
      p[3] = f.t.x, p[4] = f.t.y, p[5] = f.t.z;
      p[6] = dot(cross(f.n, f.t), f.b) < 0 ? -1.0f : 1.0f;
      p[7] = 1;
      ++r.covered;
    }
  // Dilation: empty texels next to filled ones take their average.
  for (int pass = 0; pass < s.dilate; ++pass) {
    std::vector<float> next = img;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (texel(x, y)[7] > 0) continue;
        Vec3 n(0, 0, 0), t(0, 0, 0);
        float sign = 0;
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const float* q = texel(nx, ny);
            if (!(q[7] > 0)) continue;
            n += Vec3(q[0], q[1], q[2]);
            t += Vec3(q[3], q[4], q[5]);
            sign += q[6];
            ++count;
          }
        if (count == 0 || !(length(n) > 1e-20f)) continue;
        const Frame f = Frame::from_normal_tangent(normalize(n), t);
        float* p = &next[(static_cast<size_t>(y) * w + x) * 8];
        p[0] = f.n.x, p[1] = f.n.y, p[2] = f.n.z;
        p[3] = f.t.x, p[4] = f.t.y, p[5] = f.t.z;
        p[6] = sign < 0 ? -1.0f : 1.0f;
        p[7] = 0.5f;
      }
    img.swap(next);
  }

  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(path + ": cannot create image writer: " + OIIO::geterror());
  OIIO::ImageSpec spec(w, h, 8, OIIO::TypeDesc::FLOAT);
  spec.channelnames = {"N.X", "N.Y", "N.Z", "T.X", "T.Y", "T.Z", "B.sign", "A"};
  spec.alpha_channel = -1;
  const float lo[2] = {r.uv_min.x, r.uv_min.y}, hi[2] = {r.uv_max.x, r.uv_max.y};
  spec.attribute("knitshade:uv_min", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 2), lo);
  spec.attribute("knitshade:uv_max", OIIO::TypeDesc(OIIO::TypeDesc::FLOAT, 2), hi);
  spec.attribute("knitshade:format", "frames/1");
  spec.attribute("knitshade:mesh", mesh.file);
  spec.attribute("compression", "zip");
  if (!out->open(path, spec)) throw std::runtime_error(path + ": cannot open for writing: " + out->geterror());
  if (!out->write_image(OIIO::TypeDesc::FLOAT, img.data()))
    throw std::runtime_error(path + ": cannot write image: " + out->geterror());
  if (!out->close()) throw std::runtime_error(path + ": cannot close image: " + out->geterror());
  return r;
}

}  // namespace knit::render
