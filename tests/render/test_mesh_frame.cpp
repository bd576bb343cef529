// MeshFrame (knit::FrameProvider over a mesh): exact lookups through the UV
// grid, lookups in a baked frame image, and the bake itself.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <string>

#include "render/frame_bake.h"
#include "render/mesh_frame.h"
#include "render/uv_grid.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

constexpr float kPiF = 3.14159265358979f;

Vec3 v3(knit::Vec3 k) { return {k.x, k.y, k.z}; }

void expect_orthonormal(Vec3 t, Vec3 b, Vec3 n) {
  EXPECT_NEAR(length(t), 1.0f, 1e-5f);
  EXPECT_NEAR(length(b), 1.0f, 1e-5f);
  EXPECT_NEAR(length(n), 1.0f, 1e-5f);
  EXPECT_NEAR(dot(t, b), 0.0f, 1e-5f);
  EXPECT_NEAR(dot(t, n), 0.0f, 1e-5f);
  EXPECT_NEAR(dot(b, n), 0.0f, 1e-5f);
}

// Expected frame of the unit half cylinder at u = pi s: n = (-cos, 0, sin),
// t = dP/du = (sin, 0, cos), b = +y.
void half_cylinder_frame(float u, Vec3& t, Vec3& b, Vec3& n) {
  const float a = u;  // radius 1: angle = arc length
  n = {-std::cos(a), 0, std::sin(a)};
  t = {std::sin(a), 0, std::cos(a)};
  b = {0, 1, 0};
}

TEST(MeshFrame, FlatQuadIsTheIdentityFrame) {
  auto quad = std::make_shared<const TriangleMesh>(load_mesh(test::mesh("quad.obj")));
  const MeshFrame f(quad, 8.0f);
  for (float x : {0.5f, 2.0f, 7.9f})
    for (float y : {0.1f, 4.0f, 7.5f}) {
      knit::Vec3 t, b, n;
      f.frame(x, y, t, b, n);
      EXPECT_NEAR(v3(t).x, 1.0f, 1e-6f);
      EXPECT_NEAR(v3(b).y, 1.0f, 1e-6f);
      EXPECT_NEAR(v3(n).z, 1.0f, 1e-6f);
    }
}

TEST(MeshFrame, HalfCylinderMatchesTheAnalyticFrame) {
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(test::mesh("half_cylinder.obj")));
  const float uv_scale = 20.0f;
  const MeshFrame f(mesh, uv_scale);
  float worst = 0;
  for (int i = 1; i < 40; ++i)
    for (int j = 1; j < 5; ++j) {
      const float u = kPiF * i / 40.0f + 0.003f, v = 2.0f * j / 5.0f;
      knit::Vec3 t, b, n;
      f.frame(uv_scale * u, uv_scale * v, t, b, n);
      Vec3 et, eb, en;
      half_cylinder_frame(u, et, eb, en);
      expect_orthonormal(v3(t), v3(b), v3(n));
      worst = std::max({worst, length(v3(t) - et), length(v3(b) - eb), length(v3(n) - en)});
    }
  // 96 segments around the half circle: smooth normals interpolate within a
  // small fraction of the 1.9 degree facet angle.
  EXPECT_LT(worst, 2e-3f);
}

TEST(MeshFrame, OutsideTheUvChartsUsesTheNearestTriangle) {
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(test::mesh("half_cylinder.obj")));
  const MeshFrame f(mesh, 1.0f);
  Frame fr;
  EXPECT_TRUE(f.lookup({1.0f, 1.0f}, fr));
  EXPECT_FALSE(f.lookup({-0.5f, 1.0f}, fr));  // left of u = 0: the frame at u = 0
  EXPECT_NEAR(fr.n.x, -1.0f, 1e-3f);
  EXPECT_FALSE(f.lookup({kPiF + 0.3f, 2.5f}, fr));  // beyond the far corner
  EXPECT_NEAR(fr.n.x, 1.0f, 1e-3f);
  EXPECT_FALSE(f.lookup({1e6f, 1.0f}, fr));
  EXPECT_NEAR(fr.n.x, 1.0f, 1e-3f);
  // Very far (a march at a tiny uv_scale divides pattern units by it): the
  // squared distance overflowed float, no triangle was nearest, and the
  // lookup read triangle -1 (a crash found by rendering the demo with
  // extreme values). Now some boundary triangle answers (at 1e30 the
  // charts' width is below the distances' rounding), and a non-finite UV
  // gets the flat frame.
  for (const Vec2 far : {Vec2{3e30f, 1.0f}, Vec2{-3e30f, -3e30f}, Vec2{1.0f, 3e38f}}) {
    EXPECT_FALSE(f.lookup(far, fr));
    EXPECT_NEAR(length(fr.n), 1.0f, 1e-5f);
  }
  EXPECT_FALSE(f.lookup({std::nanf(""), 1.0f}, fr));
  EXPECT_EQ(fr.n.z, 1.0f);
  int64_t hint = -1;
  knit::Vec3 t, b, n;
  const MeshFrame tiny(mesh, 1e-30f);
  tiny.frame_near(2.0f, 1.0f, hint, t, b, n);
  EXPECT_TRUE(std::isfinite(n.x) && std::isfinite(n.y) && std::isfinite(n.z));
}

// A march's lookups with one hint: the same frames and curvatures as
// lookups without, along a wandering path that stays in triangles, leaves
// them and leaves the UV charts (where the nearest triangle answers).
TEST(MeshFrame, HintedLookupsMatchUnhintedOnes) {
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(test::mesh("half_cylinder.obj")));
  const float uv_scale = 20.0f;
  const MeshFrame f(mesh, uv_scale);
  int64_t hint = -1;
  std::set<int64_t> hints;
  float x = 0.3f, y = 0.2f, dx = 1.7f, dy = 0.9f;
  for (int i = 0; i < 4000; ++i) {
    // Straight runs (a march) that turn every 16 steps, bouncing off the
    // walls of [-5, 68] x [-5, 45], the charts' [0, 62.8] x [0, 40] grown.
    if (i % 16 == 0) {
      dx = 2.5f * std::sin(1.7f * i + 0.3f);
      dy = 2.5f * std::cos(2.9f * i);
    }
    x += dx;
    y += dy;
    if (x < -5 || x > 68) dx = -dx;
    if (y < -5 || y > 45) dy = -dy;
    knit::Vec3 t0, b0, n0, t1, b1, n1;
    f.frame(x, y, t0, b0, n0);
    f.frame_near(x, y, hint, t1, b1, n1);
    ASSERT_LT(length(v3(t1) - v3(t0)) + length(v3(b1) - v3(b0)) + length(v3(n1) - v3(n0)), 1e-5f)
        << "at (" << x << ", " << y << ") step " << i;
    const knit::Vec3 k0 = f.curvature(x, y), k1 = f.curvature_near(x, y, hint);
    ASSERT_NEAR(k1.x, k0.x, 1e-6f);
    ASSERT_NEAR(k1.y, k0.y, 1e-6f);
    hints.insert(hint);
  }
  EXPECT_GT(hints.size(), 50u);  // the hint followed the path across triangles
  // A caller's starting hint (BaseHit::frame_hint) that is wrong, or names
  // no triangle at all, costs only the ordinary lookup.
  for (int64_t start : {int64_t(0), int64_t(mesh->num_triangles()) - 1, int64_t(mesh->num_triangles()),
                        int64_t(mesh->num_triangles()) + 1000, int64_t(1) << 40})
    for (float px : {3.0f, 31.0f, 60.0f}) {
      knit::Vec3 t0, b0, n0, t1, b1, n1;
      f.frame(px, 20.0f, t0, b0, n0);
      int64_t h = start;
      f.frame_near(px, 20.0f, h, t1, b1, n1);
      EXPECT_LT(length(v3(t1) - v3(t0)) + length(v3(b1) - v3(b0)) + length(v3(n1) - v3(n0)), 1e-5f)
          << "hint " << start << " at x " << px;
      EXPECT_GE(h, 0);
      EXPECT_LT(h, int64_t(mesh->num_triangles()));  // now the triangle found
    }
}

// UvTriangleGrid::nearest against a brute-force search in double over every
// triangle, on meshes of one chart (half cylinder), several charts
// (cushion, scarf) and a sphere, for points inside, just outside and far
// outside the charts: the point it returns (its barycentrics) is as near to
// the query as the nearest point of any triangle.
double uv_distance_to_triangle(const TriangleMesh& m, size_t t, Vec2 p) {
  const Vec2 a = m.uvs[m.indices[3 * t]], b = m.uvs[m.indices[3 * t + 1]], c = m.uvs[m.indices[3 * t + 2]];
  const double ax = a.x, ay = a.y, bx = b.x, by = b.y, cx = c.x, cy = c.y, qx = p.x, qy = p.y;
  const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  const double w1 = ((qx - ax) * (cy - ay) - (qy - ay) * (cx - ax)) / area;
  const double w2 = ((bx - ax) * (qy - ay) - (by - ay) * (qx - ax)) / area;
  if (w1 >= 0 && w2 >= 0 && w1 + w2 <= 1) return 0;
  double best = HUGE_VAL;
  const double vx[3] = {ax, bx, cx}, vy[3] = {ay, by, cy};
  for (int e = 0; e < 3; ++e) {
    const double ex = vx[(e + 1) % 3] - vx[e], ey = vy[(e + 1) % 3] - vy[e];
    const double l2 = ex * ex + ey * ey;
    const double s = l2 > 0 ? std::clamp(((qx - vx[e]) * ex + (qy - vy[e]) * ey) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(vx[e] + s * ex - qx, vy[e] + s * ey - qy));
  }
  return best;
}

TEST(UvTriangleGrid, NearestIsTheNearestTriangle) {
  for (const char* name : {"half_cylinder.obj", "cushion.obj", "scarf.obj", "sphere.obj"}) {
    const TriangleMesh m = load_mesh(test::mesh(name));
    const UvTriangleGrid grid(m);
    const Vec2 lo = grid.uv_min(), hi = grid.uv_max();
    const float w = hi.x - lo.x, h = hi.y - lo.y;
    uint32_t state = 12345;
    auto uni = [&]() {
      state = state * 1664525u + 1013904223u;
      return float(state >> 8) / float(1 << 24);
    };
    double worst = 0;
    int outside = 0;
    for (int i = 0; i < 600; ++i) {
      // the bounding box grown by 2%, by 50% and by 1000 times its size
      const float grow = i < 300 ? 0.02f : (i < 500 ? 0.5f : 1000.0f);
      const Vec2 p{lo.x - grow * w + (1 + 2 * grow) * w * uni(), lo.y - grow * h + (1 + 2 * grow) * h * uni()};
      double truth = HUGE_VAL;
      for (size_t t = 0; t < m.num_triangles(); ++t) {
        const Vec2 a = m.uvs[m.indices[3 * t]], b = m.uvs[m.indices[3 * t + 1]], c = m.uvs[m.indices[3 * t + 2]];
        if ((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x) == 0) continue;  // (no UV area: not in the grid)
        truth = std::min(truth, uv_distance_to_triangle(m, t, p));
      }
      float b1 = -1, b2 = -1;
      bool inside = false;
      const int64_t t = grid.nearest(p, b1, b2, &inside);
      ASSERT_GE(t, 0) << name << " at (" << p.x << ", " << p.y << ")";
      // (inside: within locate()'s tolerance of a triangle)
      EXPECT_EQ(inside, truth <= 1e-5 * std::max(w, h)) << name << " at (" << p.x << ", " << p.y << ")";
      const Vec2 a = m.uvs[m.indices[3 * t]], b = m.uvs[m.indices[3 * t + 1]], c = m.uvs[m.indices[3 * t + 2]];
      const double qx = double(a.x) * (1 - b1 - b2) + double(b.x) * b1 + double(c.x) * b2;
      const double qy = double(a.y) * (1 - b1 - b2) + double(b.y) * b1 + double(c.y) * b2;
      const double got = truth == 0 ? uv_distance_to_triangle(m, size_t(t), p) : std::hypot(qx - p.x, qy - p.y);
      const double err = std::fabs(got - truth) / std::max(1.0, double(std::max(w, h)) * (1 + 2 * grow));
      worst = std::max(worst, err);
      ASSERT_LT(err, 1e-5) << name << " at (" << p.x << ", " << p.y << "): " << got << " against " << truth;
      outside += truth > 0;
    }
    EXPECT_GT(outside, 250) << name;  // nearly half the points lie outside the charts
    std::printf("%s: worst relative distance error %.2g over 600 points, %d outside the charts\n", name, worst,
                outside);
  }
}

TEST(MeshFrame, MirroredUvsGiveABitangentAlongPlusV) {
  const std::string dir = test::test_dir();
  const std::string obj = test::write_file(dir, "mirror.obj",
                                           "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 1 0\nvt 0 0\nvt 0 1\nvt 1 1\n"
                                           "vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n");
  auto mesh = std::make_shared<const TriangleMesh>(load_mesh(obj));
  const MeshFrame f(mesh, 1.0f);
  knit::Vec3 t, b, n;
  f.frame(0.3f, 0.6f, t, b, n);
  EXPECT_NEAR(v3(t).x, -1.0f, 1e-6f);  // +u runs toward -x
  EXPECT_NEAR(v3(b).y, 1.0f, 1e-6f);   // +v runs toward +y
  EXPECT_NEAR(v3(n).z, 1.0f, 1e-6f);
}

TEST(MeshFrame, RejectsMeshesWithoutUvsAndBadScales) {
  const std::string dir = test::test_dir();
  auto no_uv = std::make_shared<const TriangleMesh>(
      load_mesh(test::write_file(dir, "n.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")));
  EXPECT_THROW(MeshFrame(no_uv, 1.0f), std::invalid_argument);
  auto quad = std::make_shared<const TriangleMesh>(load_mesh(test::mesh("quad.obj")));
  EXPECT_THROW(MeshFrame(quad, 0.0f), std::invalid_argument);
  EXPECT_THROW(MeshFrame(quad, NAN), std::invalid_argument);
}

TEST(BakeFrames, BakedLookupsAgreeWithExactOnes) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(test::mesh("half_cylinder.obj"));
  BakeSettings s;
  s.width = 256;
  s.height = 64;
  const BakeResult r = bake_frames(m, dir + "/frames.exr", s);
  EXPECT_NEAR(r.uv_min.x, 0.0f, 1e-6f);
  EXPECT_NEAR(r.uv_max.x, kPiF, 1e-5f);
  EXPECT_NEAR(r.uv_max.y, 2.0f, 1e-6f);
  EXPECT_EQ(r.covered, static_cast<size_t>(256 * 64));  // the chart fills its rectangle

  auto in = OIIO::ImageInput::open(dir + "/frames.exr");
  ASSERT_TRUE(in);
  EXPECT_EQ(in->spec().nchannels, 8);
  std::set<std::string> names;
  for (int c = 0; c < 8; ++c) names.insert(in->spec().channel_name(c));
  EXPECT_EQ(names, (std::set<std::string>{"A", "B.sign", "N.X", "N.Y", "N.Z", "T.X", "T.Y", "T.Z"}));
  in.reset();

  auto exact_mesh = std::make_shared<const TriangleMesh>(m);
  const MeshFrame exact(exact_mesh, 10.0f);
  const auto baked = MeshFrame::from_baked(dir + "/frames.exr", 10.0f);
  ASSERT_TRUE(baked->is_baked());
  float worst = 0;
  for (int i = 0; i < 50; ++i) {
    const float u = 0.05f + (kPiF - 0.1f) * i / 49.0f, v = 0.1f + 1.8f * ((i * 7) % 50) / 49.0f;
    Frame a, b;
    EXPECT_TRUE(exact.lookup({u, v}, a));
    EXPECT_TRUE(baked->lookup({u, v}, b));
    worst = std::max({worst, length(a.n - b.n), length(a.t - b.t), length(a.b - b.b)});
    knit::Vec3 t, bb, n;
    baked->frame(10.0f * u, 10.0f * v, t, bb, n);
    expect_orthonormal(v3(t), v3(bb), v3(n));
  }
  // Bilinear interpolation of 256 texels over a half circle: about 1e-4 error.
  EXPECT_LT(worst, 1e-3f);
}

TEST(BakeFrames, UncoveredTexelsAreMarkedAndDilated) {
  const std::string dir = test::test_dir();
  // A single triangle covers half of its UV rectangle.
  const std::string obj = test::write_file(dir, "tri.obj",
                                           "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n"
                                           "f 1/1/1 2/2/1 3/3/1\n");
  BakeSettings s;
  s.width = s.height = 16;
  s.dilate = 1;
  const BakeResult r = bake_frames(load_mesh(obj), dir + "/tri.exr", s);
  EXPECT_GT(r.covered, 100u);
  EXPECT_LT(r.covered, 140u);
  auto in = OIIO::ImageInput::open(dir + "/tri.exr");
  ASSERT_TRUE(in);
  std::vector<float> px(16 * 16 * 8);
  ASSERT_TRUE(in->read_image(0, 0, 0, 8, OIIO::TypeDesc::FLOAT, px.data()));
  int alpha = -1;
  for (int c = 0; c < 8; ++c)
    if (in->spec().channel_name(c) == "A") alpha = c;
  ASSERT_GE(alpha, 0);
  int covered = 0, dilated = 0, empty = 0;
  for (int i = 0; i < 256; ++i) {
    const float a = px[i * 8 + alpha];
    covered += a == 1.0f;
    dilated += a == 0.5f;
    empty += a == 0.0f;
  }
  EXPECT_EQ(static_cast<size_t>(covered), r.covered);
  EXPECT_GT(dilated, 10);
  EXPECT_GT(empty, 50);
  EXPECT_THROW(bake_frames(load_mesh(obj), dir + "/tri.png", s), std::runtime_error);
}

// A baked lookup between two charts, where no texel around it is covered,
// takes the first covered texel of the rings around it (rows from the top,
// left to right): checked against a scan of the whole image for each point
// of a row across the gap, which comes from the left chart on its left side
// and from the right chart on its right.
TEST(BakeFrames, LookupsBetweenChartsTakeTheNearestRingsTexel) {
  const std::string dir = test::test_dir();
  // Two triangles far apart in UV, facing about +z (left) and +x (right),
  // their normals varying over them so that each texel's is its own.
  const std::string obj = test::write_file(dir, "two.obj",
                                           "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv 0 0 1\nv 0 1 0\n"
                                           "vt 0 0\nvt 0.15 0\nvt 0 1\nvt 1 0\nvt 1 1\nvt 0.85 1\n"
                                           "vn 0 0 1\nvn 0.6 0 0.8\nvn 0 0.6 0.8\nvn 1 0 0\nvn 0.8 0.6 0\nvn 0.8 0 0.6\n"
                                           "f 1/1/1 2/2/2 3/3/3\nf 4/4/4 5/5/5 6/6/6\n");
  BakeSettings s;
  s.width = 96;
  s.height = 24;
  s.dilate = 0;
  const BakeResult r = bake_frames(load_mesh(obj), dir + "/two.exr", s);
  auto in = OIIO::ImageInput::open(dir + "/two.exr");
  ASSERT_TRUE(in);
  std::vector<float> px(size_t(s.width) * s.height * 8);
  ASSERT_TRUE(in->read_image(0, 0, 0, 8, OIIO::TypeDesc::FLOAT, px.data()));
  int alpha = -1, ch_n[3] = {-1, -1, -1};
  for (int c = 0; c < 8; ++c) {
    const std::string name = in->spec().channel_name(c);
    if (name == "A") alpha = c;
    for (int k = 0; k < 3; ++k)
      if (name == std::string("N.") + "XYZ"[k]) ch_n[k] = c;
  }
  ASSERT_GE(alpha, 0);
  ASSERT_TRUE(ch_n[0] >= 0 && ch_n[1] >= 0 && ch_n[2] >= 0);
  in.reset();
  const auto baked = MeshFrame::from_baked(dir + "/two.exr", 1.0f);
  int left = 0, right = 0;
  const int j = 6;  // a row in the upper part of the image, where the charts are apart
  auto covered = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < s.width && y < s.height && px[(size_t(y) * s.width + x) * 8 + alpha] > 0;
  };
  for (int i = 0; i < s.width; ++i) {
    // (texels whose bilinear neighbours are all uncovered: the ring search answers there)
    bool near_chart = false;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) near_chart = near_chart || covered(i + dx, j + dy);
    if (near_chart) continue;
    // the first covered texel in ring order from (i, j), by a scan of every texel
    int best_r = 1 << 30, bx = -1, by = -1;
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) {
        if (!covered(x, y)) continue;
        const int rr = std::max(std::abs(x - i), std::abs(y - j));
        if (rr < best_r || (rr == best_r && (y < by || (y == by && x < bx)))) {
          best_r = rr;
          bx = x;
          by = y;
        }
      }
    ASSERT_GE(bx, 0);
    // the texel centre (i, j) in UV (row 0 at the top, v = uv_max.y)
    const Vec2 uv{r.uv_min.x + (i + 0.5f) / s.width * (r.uv_max.x - r.uv_min.x),
                  r.uv_max.y - (j + 0.5f) / s.height * (r.uv_max.y - r.uv_min.y)};
    Frame f;
    baked->lookup(uv, f);
    const float* texel = &px[(size_t(by) * s.width + bx) * 8];
    const Vec3 want = normalize(Vec3(texel[ch_n[0]], texel[ch_n[1]], texel[ch_n[2]]));
    EXPECT_LT(length(f.n - want), 1e-5f) << "texel " << i << ": the covered texel found is not (" << bx << ", "
                                         << by << ")";
    (want.x > 0.5f ? right : left) += 1;
  }
  EXPECT_GT(left, 10);
  EXPECT_GT(right, 10);
}

}  // namespace
}  // namespace knit::render
