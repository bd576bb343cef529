// The knit model in the renderer (material_knit.h) and its explicit-yarn
// ground truth (yarn_tubes.h, curve_shape.h, material_explicit_yarn.h):
// mesh tables, tube geometry, white furnaces, agreement of the sampling
// strategies through knit pass-through events, determinism, and the model
// against explicit yarns on the example scenes (docs/results.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "knit/yarns.h"
#include "render/curve_shape.h"
#include "render/frame_bake.h"
#include "render/image_compare.h"
#include "render/material_knit.h"
#include "render/mesh_frame.h"
#include "render/report.h"
#include "render/triangle_shape.h"
#include "render/yarn_tubes.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

using test::mesh;

std::shared_ptr<const knit::KnitMaterial> knit_model(const std::string& pattern_rows, float uv_scale,
                                                      knit::KnitMode mode = knit::KnitMode::NearField,
                                                      bool table_bsdf = true) {
  knit::KnitMaterialParams p;
  p.uv_scale = uv_scale;
  p.mode = mode;
  p.table_bsdf = table_bsdf;
  std::vector<std::vector<int>> rows;
  for (char c : pattern_rows) {
    if (c == '/') {
      rows.emplace_back();
      continue;
    }
    if (rows.empty()) rows.emplace_back();
    rows.back().push_back(c == 'K' ? 0 : 1);
  }
  return std::make_shared<const knit::KnitMaterial>(knit::Pattern::from_rows(rows), p);
}

// ---------------------------------------------------------------------------
// Mesh tables, MeshFrame curvature, tubes

TEST(KnitMesh, HalfCylinderScaleAndCurvature) {
  // u is the arc length (radius 1), v the height: |dP/du| = |dP/dv| = 1.
  const TriangleMesh m = load_mesh(mesh("half_cylinder.obj"));
  const KnitMeshTables t = knit_mesh_tables(m, 450.0f);
  EXPECT_FALSE(t.flat);
  EXPECT_EQ(t.stretched, 0u);
  double kx = 0, ky = 0;
  for (const KnitTriangle& tri : t.triangles) {
    EXPECT_NEAR(tri.pattern_per_world, 450.0f, 450.0f * 2e-3f);
    kx += tri.kx;
    ky += tri.ky;
  }
  kx /= double(t.triangles.size());
  ky /= double(t.triangles.size());
  EXPECT_NEAR(kx, 1.0, 2e-3);  // convex, 1 / radius
  EXPECT_NEAR(ky, 0.0, 1e-4);
  const MeshFrame frame(std::make_shared<const TriangleMesh>(m), 450.0f);
  const knit::Vec3 k = frame.curvature(450.0f * 1.3f, 450.0f * 0.7f);
  EXPECT_NEAR(k.x, 1.0f / 450.0f, 2e-6f);  // per pattern unit
  EXPECT_NEAR(k.y, 0.0f, 1e-7f);
}

TEST(KnitMesh, FlatQuadAndAStretchedMesh) {
  const TriangleMesh quad = load_mesh(mesh("quad.obj"));
  const KnitMeshTables t = knit_mesh_tables(quad, 40.0f);
  EXPECT_TRUE(t.flat);
  EXPECT_NEAR(t.triangles[0].pattern_per_world, 40.0f, 1e-3f);
  // Stretch the quad by 2 along x: S is the geometric mean, and the stretch is reported.
  TriangleMesh wide = quad;
  for (Vec3& p : wide.positions) p.x *= 2;
  const KnitMeshTables w = knit_mesh_tables(wide, 40.0f);
  EXPECT_EQ(w.stretched, 2u);
  EXPECT_NEAR(w.stretched_area, 1.0, 1e-6);
  EXPECT_NEAR(w.worst_ratio, 2.0f, 1e-4f);
  EXPECT_NEAR(w.triangles[1].pattern_per_world, 40.0f / std::sqrt(2.0f), 1e-3f);
}

// The UV-stretch warnings of a render of `mesh` (in dir) as one knit object
// "w", the camera 3 units in front of (cx, cy, 0).
std::vector<std::string> stretch_warnings(const std::string& dir, const std::string& mesh, float cx, float cy) {
  char scene[1024];
  std::snprintf(scene, sizeof scene, R"({
    "film": {"width": 8, "height": 8, "spp": 1},
    "camera": {"position": [%g, %g, 3], "look_at": [%g, %g, 0]},
    "lights": [{"type": "environment", "color": [1, 1, 1]}],
    "materials": {"wool": {"type": "knit", "pattern": ["K"], "uv_scale": 30, "yarn_colors": [[0.5, 0.5, 0.5]]}},
    "objects": [{"name": "w", "mesh": "%s", "material": "wool"}]})",
                cx, cy, cx, cy, mesh.c_str());
  std::vector<std::string> out;
  for (const std::string& m : test::render_text(dir, scene).warnings.messages)
    if (m.find("differing by more than 10%") != std::string::npos) out.push_back(m);
  return out;
}

TEST(KnitMesh, StretchedMeshWarnsOnce) {
  const std::string dir = test::test_dir();
  test::write_file(dir, "wide.obj",
                   "v -1 -0.5 0\nv 1 -0.5 0\nv 1 0.5 0\nv -1 0.5 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                   "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n");
  const std::vector<std::string> w = stretch_warnings(dir, "wide.obj", 0, 0);
  ASSERT_EQ(w.size(), 1u);
  EXPECT_NE(w[0].find("objects[0] (w)"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("2 of 2 triangles (100.0% of the UV area)"), std::string::npos) << w[0];
  EXPECT_NE(w[0].find("materials.wool"), std::string::npos) << w[0];
}

// Below 1% of the UV area and a ratio of 1.5 the stretch goes unmentioned;
// a strong stretch of the same small patch warns. The mesh: a unit quad and
// a 0.1 x 0.1 UV patch beside it (0.99% of the UV area), stretched along x.
TEST(KnitMesh, SmallMildStretchesDoNotWarnStrongOnesDo) {
  const std::string dir = test::test_dir();
  auto count_warnings = [&](float stretch) {
    char obj[512];
    std::snprintf(obj, sizeof obj,
                  "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                  "v 2 0 0\nv %g 0 0\nv %g 0.1 0\nv 2 0.1 0\n"
                  "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 2 0\nvt 2.1 0\nvt 2.1 0.1\nvt 2 0.1\n"
                  "f 1/1 2/2 3/3\nf 1/1 3/3 4/4\nf 5/5 6/6 7/7\nf 5/5 7/7 8/8\n",
                  2 + 0.1 * stretch, 2 + 0.1 * stretch);
    test::write_file(dir, "patch.obj", obj);
    const KnitMeshTables t = knit_mesh_tables(load_mesh(dir + "/patch.obj"), 30.0f);
    EXPECT_EQ(t.stretched, 2u) << stretch;  // the counts still see both triangles
    EXPECT_NEAR(t.worst_ratio, stretch, 1e-3f);
    EXPECT_NEAR(t.stretched_area, 0.01 / 1.01, 1e-6);
    return stretch_warnings(dir, "patch.obj", 1, 0.5f).size();
  };
  EXPECT_EQ(count_warnings(1.2f), 0u);
  EXPECT_EQ(count_warnings(1.6f), 1u);
}

TEST(YarnTubes, FlatQuadPlacesTheExactCurvesBelowTheMesh) {
  // quad.obj: 1 x 1 in the xy plane facing +z, UV = position + 0.5.
  const TriangleMesh quad = load_mesh(mesh("quad.obj"));
  const auto model = knit_model("KP/PK", 40.0f);
  const YarnTubes y = build_yarn_tubes(quad, *model, 16);
  ASSERT_GT(y.segments.size(), 100u);
  const float S = 40.0f, top = model->surface().shell_top(), r = model->params().stitch.r;
  // Every point lies over the quad and at most 2 shell_top / S below it.
  for (size_t i = 0; i < y.num_points(); ++i) {
    const Vec3 p = y.point(i);
    EXPECT_LE(std::fabs(p.x), 0.5f + 1e-5f);
    EXPECT_LE(std::fabs(p.y), 0.5f + 1e-5f);
    EXPECT_LE(p.z, 1e-6f);
    EXPECT_GE(p.z, -2 * top / S - 1e-6f);
    EXPECT_NEAR(y.radius(i), r / S, 1e-7f);
  }
  // Point 37 (of 16 per stitch) of the exact curve of row 3, mapped: x / S - 0.5, y / S - 0.5, (z - top) / S.
  const knit::CurvePoint c =
      knit::yarn_curve_exact(model->surface().pattern(), model->params().stitch, 3, 6.283185307179586 * 37 / 16);
  const Vec3 want(float(c.p[0] / S - 0.5), float(c.p[1] / S - 0.5), float((c.p[2] - top) / S));
  float best = 1e9f;
  for (size_t i = 0; i < y.num_points(); ++i) best = std::min(best, length(y.point(i) - want));
  EXPECT_LT(best, 1e-5f);
  // Polylines are split where they leave the UV square: segments never jump.
  for (size_t j = 0; j < y.segments.size(); ++j) {
    const uint32_t k = y.segments[j];
    EXPECT_LT(length(y.point(k + 1) - y.point(k)), 2.0f / S);
  }
  EXPECT_GT(y.curves, size_t(40 / model->surface().cell_height()));
  EXPECT_EQ(y.geometry_bytes(), y.num_points() * 16 + y.segments.size() * 5);
}

// The tubes' ply coordinate is the model's (KnitMaterial::ply_arc: the
// curve parameter times the mean arc length per unit of it over a knit
// stitch, plus the row's phase), checked against that definition computed
// here in double precision, and it does not depend on the polyline's
// density. (It was the polyline's summed length, which drifts along a row
// with the density: 12% of a 512-pixel half cylinder's pixels' values,
// docs/results.md.)
TEST(YarnTubes, PlyCoordinateIsTheModelsAtEveryDensity) {
  const TriangleMesh quad = load_mesh(mesh("quad.obj"));  // UV = position + 0.5
  const auto model = knit_model("KP/PK", 40.0f);
  const YarnTubes coarse = build_yarn_tubes(quad, *model, 16), fine = build_yarn_tubes(quad, *model, 64);
  // Mean |dY/dt| over a knit stitch, midpoint rule on 20,000 points.
  const knit::Pattern knit_only = knit::Pattern::from_rows({{0}});
  double len = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const knit::CurvePoint c = knit::yarn_curve_exact(knit_only, model->params().stitch, 0, 6.283185307179586 * (i + 0.5) / n);
    len += std::sqrt(c.dp[0] * c.dp[0] + c.dp[1] * c.dp[1] + c.dp[2] * c.dp[2]);
  }
  const double per_t = len / n;
  const float S = 40.0f, top = model->surface().shell_top();
  const knit::Pattern& pat = model->surface().pattern();
  const double cell_h = model->surface().cell_height(), a = model->params().stitch.a;
  // The curve parameter of a tube point: where the exact curve passes
  // through it (pattern space), found by a scan of the rows and of t around
  // its x (a loop strays at most about a from t in x), then refined by
  // halving steps on the squared distance.
  const auto t_of = [&](Vec3 w) {
    const double px = S * (w.x + 0.5), py = S * (w.y + 0.5), pz = w.z * S + top;
    const auto dist2 = [&](int row, double t) {
      const knit::CurvePoint c = knit::yarn_curve_exact(pat, model->params().stitch, row, t);
      return (c.p[0] - px) * (c.p[0] - px) + (c.p[1] - py) * (c.p[1] - py) + (c.p[2] - pz) * (c.p[2] - pz);
    };
    double best_d = 1e30, best_t = 0;
    int best_row = 0;
    const int k0 = int(std::floor(py / cell_h));
    for (int row = k0 - 3; row <= k0 + 3; ++row)
      for (double t = px - 2 * a - 1; t <= px + 2 * a + 1; t += 0.005)
        if (const double d = dist2(row, t); d < best_d) best_d = d, best_t = t, best_row = row;
    for (double h = 0.005; h > 1e-9; h *= 0.5)
      for (const double step : {-h, h})
        if (const double d = dist2(best_row, best_t + step); d < best_d) {
          best_t += step;
          best_d = d;
          break;
        }
    EXPECT_LT(best_d, 1e-8) << "no exact curve point at the tube point";
    return std::make_pair(best_t, best_row);
  };
  size_t checked = 0;
  std::set<int> rows_seen;
  for (size_t i = 0; i < coarse.num_points(); i += 7) {
    const Vec3 p = coarse.point(i);
    // The same point among the fine tubes' (every fourth of theirs).
    size_t best = 0;
    float d = 1e9f;
    for (size_t j = 0; j < fine.num_points(); ++j)
      if (length(fine.point(j) - p) < d) d = length(fine.point(j) - p), best = j;
    ASSERT_LT(d, 1e-6f) << "point " << i;
    EXPECT_EQ(coarse.arc[i], fine.arc[best]) << "point " << i;
    // Against the definition: the rows' phases are the golden-ratio
    // sequence times a stitch's length.
    const auto [t, row] = t_of(p);
    const double g = row * 0.6180339887498949, want = t * per_t + (g - std::floor(g)) * 2 * M_PI * per_t;
    EXPECT_NEAR(coarse.arc[i], want, 2e-5 * std::fabs(want) + 1e-4) << "point " << i << ", t " << t << ", row " << row;
    rows_seen.insert(row);
    ++checked;
  }
  EXPECT_GT(checked, 100u);
  EXPECT_GE(rows_seen.size(), 6u);
}

TEST(YarnTubes, TooManyPointsIsAClearError) {
  const TriangleMesh quad = load_mesh(mesh("quad.obj"));
  const auto model = knit_model("K", 4000.0f);
  try {
    build_yarn_tubes(quad, *model, 32, 1'000'000);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("curve points"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("quad.obj"), std::string::npos) << e.what();
  }
}

TEST(CurveShape, HitsFromInsideAndOutsideAreToldApart) {
  Accel accel;
  auto tubes = std::make_shared<YarnTubes>();
  // One straight tube along x, radius 0.1, five points.
  for (int i = 0; i < 5; ++i) {
    tubes->vertices.insert(tubes->vertices.end(), {float(i) * 0.25f - 0.5f, 0, 0, 0.1f});
    tubes->color.push_back(0);
    tubes->arc.push_back(float(i));
    tubes->fabric_normal.push_back({0, 0, 1});
  }
  for (uint32_t k = 0; k < 4; ++k) tubes->segments.push_back(k);
  tubes->flags = {RTC_CURVE_FLAG_NEIGHBOR_RIGHT, RTC_CURVE_FLAG_NEIGHBOR_LEFT | RTC_CURVE_FLAG_NEIGHBOR_RIGHT,
                  RTC_CURVE_FLAG_NEIGHBOR_LEFT | RTC_CURVE_FLAG_NEIGHBOR_RIGHT, RTC_CURVE_FLAG_NEIGHBOR_LEFT};
  accel.add(std::make_unique<CurveShape>(tubes), 0, -1);
  accel.commit();
  // From outside toward the axis: the front of the tube, normal against the ray.
  RayDifferential out;
  out.o = {0.05f, 0, 1};
  out.d = {0, 0, -1};
  SurfaceInteraction si;
  ASSERT_TRUE(accel.intersect(out, si));
  EXPECT_NEAR(si.t, 0.9f, 1e-4f);
  EXPECT_LT(dot(out.d, si.ng), -0.99f);
  EXPECT_NEAR(std::fabs(si.shading.t.x), 1.0f, 1e-4f);
  // From the axis outward (a transmitted ray): the exit, seen from inside.
  RayDifferential in;
  in.o = {0.1f, 0, 0};
  in.d = normalize(Vec3(0, 1, 1));
  ASSERT_TRUE(accel.intersect(in, si));
  EXPECT_NEAR(si.t, 0.1f, 1e-4f);
  EXPECT_GT(dot(in.d, si.ng), 0.99f);
  // Across the joint between two segments, from inside: no inner surface is met.
  RayDifferential along;
  along.o = {-0.3f, 0, 0};
  along.d = normalize(Vec3(1, 0.2f, 0));  // leaves the tube at x = 0.2, past the joints at -0.25 and 0
  ASSERT_TRUE(accel.intersect(along, si));
  EXPECT_GT(dot(along.d, si.ng), 0.0f);
  EXPECT_NEAR(si.p.y, 0.1f, 2e-3f);
  EXPECT_NEAR(si.p.x, 0.2f, 1e-2f);
}

// ---------------------------------------------------------------------------
// Energy and sampling

std::string furnace_scene(const std::string& mode, bool explicit_yarns, const std::string& bsdf_model = "exact") {
  return R"({
    "film": {"width": 24, "height": 24, "spp": 48, "seed": 5},
    "camera": {"position": [0, 0.3, 1.25], "look_at": [0, 0, 0.3], "fov": 30},
    "integrator": {"max_depth": 256, "rr_depth": 64, "explicit_yarns": )" +
         std::string(explicit_yarns ? "true" : "false") + R"(},
    "lights": [{"type": "environment", "color": [1, 1, 1]}],
    "materials": {"wool": {"type": "knit", "pattern": ["KKPP", "PPKK"], "uv_scale": 40, "yarn_colors": [[1, 1, 1]],
                           "bsdf": {"eta": 1, "body_energy": 1, "body_reflect": 0, "optical_depth": 0},
                           "ply": {"enabled": false}, "mode": ")" + mode + R"(", "bsdf_model": ")" + bsdf_model + R"("}},
    "objects": [{"mesh": ")" + mesh("half_cylinder.obj") + R"(", "material": "wool", "transform": {"scale": 0.5}}]
  })";
}

// All colours 1, B = 1, eta = 1, r = 0, no attenuation and no ply shadow: the
// yarn BSDF is a lossless diffuse transmitter, so a uniform white sky seen
// through and around the fabric (curved, so rays also meet it from behind)
// stays exactly white: pass-through events, transmission and the tubes'
// null events must conserve energy.
void expect_white_furnace(const RgbImage& img, const char* what) {
  const double mean = test::mean_channel_value(img);
  double worst_block = 0;
  for (int by = 0; by < img.height; by += 8)
    for (int bx = 0; bx < img.width; bx += 8) {
      double s = 0;
      for (int y = by; y < by + 8; ++y)
        for (int x = bx; x < bx + 8; ++x) s += img.at(x, y).mean();
      worst_block = std::max(worst_block, std::fabs(s / 64 - 1));
    }
  std::printf("[furnace] %s: mean %.5f (error %.3f%%), worst 8x8 block %.3f%%\n", what, mean, 100 * (mean - 1),
              100 * worst_block);
  EXPECT_NEAR(mean, 1.0, 0.01) << what;
  EXPECT_LT(worst_block, 0.03) << what;
}

// A furnace where the renderer is meant to lose light, but never to make
// it: Cycles' side test (knit::k::yarn_cycles_side_ok) drops the light a
// yarn normal tilted against the mesh's would take from the mesh's other
// side. The mean stays within [min_mean, 1.01], no 8x8 block above 1.03.
void expect_lossy_furnace(const RgbImage& img, const char* what, double min_mean) {
  const double mean = test::mean_channel_value(img);
  double brightest = 0;
  for (int by = 0; by < img.height; by += 8)
    for (int bx = 0; bx < img.width; bx += 8) {
      double s = 0;
      for (int y = by; y < by + 8; ++y)
        for (int x = bx; x < bx + 8; ++x) s += img.at(x, y).mean();
      brightest = std::max(brightest, s / 64);
    }
  std::printf("[furnace] %s: mean %.5f (error %.3f%%), brightest 8x8 block %.5f\n", what, mean, 100 * (mean - 1),
              brightest);
  EXPECT_GT(mean, min_mean) << what;
  EXPECT_LT(mean, 1.01) << what;
  EXPECT_LT(brightest, 1.03) << what;
}

// Multi-scale past a diffuse bounce (no differentials): the ray's cone
// (RayDifferential::cone_width) gives the footprint; a cone covering stitch
// cells is shaded from the class table, a narrow one (or none) as a point.
TEST(KnitModelHits, BounceRaysUseTheClassTableWhenTheirConeCoversCells) {
  KnitDesc desc;
  // (the table's footprints shaded at their mean normal, whose lobes the
  // slopes widen: table_bsdf false)
  desc.model = knit_model("K", 40.0f, knit::KnitMode::MultiScale, false);
  ASSERT_NE(desc.model->footprint_table(), nullptr);
  auto quad = std::make_shared<const TriangleMesh>(load_mesh(mesh("quad.obj")));
  Warnings warnings;
  const KnitModelMaterial m(desc, quad, "scene.json", "materials.wool", "objects[0]", "quad", warnings);
  const Vec3 d = normalize(Vec3(0.3f, 0.2f, -1.0f));
  auto shade = [&](float cone_width, float cone_spread, int seed, bool& passed) {
    SurfaceInteraction si;
    si.p = Vec3(0.05f, 0.1f, 0.0f);
    si.ng = Vec3(0, 0, 1);
    si.shading = Frame::from_normal_tangent(Vec3(0, 0, 1), Vec3(1, 0, 0));
    // points spread over many cells (40 pattern units per UV unit)
    const float fu = 0.618034f * float(seed), fv = 0.754878f * float(seed);
    si.uv = Vec2(0.3f + 0.4f * (fu - std::floor(fu)), 0.3f + 0.4f * (fv - std::floor(fv)));
    si.has_uv = true;
    si.prim_id = 0;
    si.t = 2.0f;
    RayDifferential ray;
    ray.o = si.p - d * si.t;
    ray.d = d;
    ray.cone_width = cone_width;
    ray.cone_spread = cone_spread;
    si.cone_width = cone_width + si.t * cone_spread;  // as the integrator sets it
    Sampler sampler(7, 0, static_cast<uint64_t>(seed));
    passed = m.resolve(si, ray, sampler).pass;
    return si;
  };
  const float base_alpha = desc.model->params().bsdf.roughness_x;
  int table_passes = 0, point_passes = 0;
  double table_alpha = 0, point_alpha = 0;
  int table_hits = 0, point_hits = 0;
  for (int i = 0; i < 400; ++i) {
    bool pass = false;
    // A cone 0.2 wide at the hit: 8 pattern units (40 per world unit), more
    // than a cell (2 pi x 4.5) both ways.
    const SurfaceInteraction wide = shade(0.0f, 0.1f, i, pass);
    table_passes += pass;
    if (!pass) {
      ++table_hits;
      table_alpha += wide.yarn.bsdf.spec_r.alpha_x;
      EXPECT_FALSE(wide.yarn.in_shell);  // an aggregate, not a point in the shell
    }
    const SurfaceInteraction narrow = shade(0.0f, 1e-4f, i, pass);
    point_passes += pass;
    if (!pass) {
      ++point_hits;
      point_alpha += narrow.yarn.bsdf.spec_r.alpha_x;
      EXPECT_TRUE(narrow.yarn.in_shell);
    }
  }
  ASSERT_GT(table_hits, 100);
  ASSERT_GT(point_hits, 100);
  // The table's aggregate widens the specular lobe by the slopes it averages; a point does not.
  EXPECT_GT(table_alpha / table_hits, 1.5 * base_alpha);
  EXPECT_NEAR(point_alpha / point_hits, base_alpha, 1e-4);
  // Both let through about the fraction of rays that miss the yarn (p_delta).
  EXPECT_NEAR(double(table_passes) / 400, double(point_passes) / 400, 0.1);
  // No cone at all: a point.
  bool pass = false;
  for (int i = 0; i < 20; ++i) {
    const SurfaceInteraction none = shade(0.0f, 0.0f, i, pass);
    if (!pass) EXPECT_TRUE(none.yarn.in_shell);
  }
}

// A camera sample's multi-scale footprint is centred at its pixel's centre
// (KnitDesc::footprint_centre "pixel"): wherever the sample lies in the
// pixel, the footprint's centre is the UV where the ray through the pixel's
// centre meets the (slanted) quad, traced on its own; "sample" keeps the
// sample's own UV, and a footprint of half a pixel moves half the way.
TEST(KnitModelHits, FootprintIsCentredAtThePixelsCentre) {
  for (const char* centre : {"pixel", "sample"}) {
    for (float scale : {1.0f, 0.5f, 2.0f}) {
      SCOPED_TRACE(std::string(centre) + ", footprint_scale " + std::to_string(scale));
      const std::string text = R"({
        "film": {"width": 64, "height": 48, "spp": 16},
        "camera": {"position": [0.3, 0.2, 4], "look_at": [0, 0, 0], "fov": 30},
        "lights": [{"type": "point", "position": [0, 0, 3], "intensity": [1, 1, 1]}],
        "materials": {"wool": {"type": "knit", "pattern": [[0]], "uv_scale": 40, "yarn_colors": [[0.5, 0.4, 0.3]],
                               "mode": "multi_scale", "footprint_table": false,
                               "footprint_centre": ")" + std::string(centre) + R"(", "footprint_scale": )" +
                               std::to_string(scale) + R"(}},
        "objects": [{"mesh": ")" + mesh("quad.obj") + R"(", "material": "wool",
                     "transform": {"scale": 4, "rotate": [35, 20, 0]}}]
      })";
      Warnings w;
      const Scene scene(parse_scene(text, "scene.json", test::test_dir()), BuildOptions{}, w);
      const float diff_scale = 0.25f;  // 16 spp
      for (const Vec2 pixel : {Vec2(20, 24), Vec2(33, 11), Vec2(50, 40)}) {
        SurfaceInteraction c;
        ASSERT_TRUE(scene.accel().intersect(scene.camera().generate(pixel.x + 0.5f, pixel.y + 0.5f), c));
        for (const Vec2 j : {Vec2(0.02f, 0.97f), Vec2(0.9f, 0.75f), Vec2(0.5f, 0.5f), Vec2(0.3f, 0.1f)}) {
          RayDifferential ray = scene.camera().generate(pixel.x + j.x, pixel.y + j.y, diff_scale);
          SurfaceInteraction si;
          ASSERT_TRUE(scene.accel().intersect(ray, si));
          ASSERT_TRUE(si.footprint.valid);
          const auto* m = dynamic_cast<const KnitModelMaterial*>(&scene.material(si.material));
          ASSERT_NE(m, nullptr);
          const knit::BaseHit h = m->base_hit(si, diff_scale, {j.x - 0.5f, j.y - 0.5f});
          const float share = std::string(centre) == "pixel" ? std::min(scale, 1.0f) : 0.0f;
          const float du = c.uv.x - si.uv.x, dv = c.uv.y - si.uv.y;
          // The UV moves up to 0.006 from a pixel's corner to its centre here;
          // the differentials' first order misses the perspective's second
          // by about 0.5% of that.
          const float move = std::fabs(du) + std::fabs(dv);
          if (j.x != 0.5f) ASSERT_GT(move, 1e-3f);
          EXPECT_NEAR(h.u + h.box_du, si.uv.x + share * du, 0.02f * share * move + 1e-6f);
          EXPECT_NEAR(h.v + h.box_dv, si.uv.y + share * dv, 0.02f * share * move + 1e-6f);
          EXPECT_EQ(h.u, si.uv.x);  // the near field's point stays the sample's
        }
      }
    }
  }
}

// bsdf_model "cycles" builds a multi-scale footprint as the OSL shader does
// from Cycles' ray cone (knit_footprint_isotropic): the pixel's width across
// the view, stretched by 1 / cos along it. On a flat quad that is the same
// area as the exact ray differentials' parallelogram, which
// "exact" uses, to the perspective's second order, and it is stretched
// along the view's projection.
TEST(KnitModelHits, CyclesFootprintHasThePixelsArea) {
  for (const float tilt : {0.0f, 40.0f, 70.0f}) {
    const std::string text = R"({
      "film": {"width": 64, "height": 64, "spp": 1},
      "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "fov": 20},
      "materials": {"wool": {"type": "knit", "pattern": [[0]], "uv_scale": 400, "yarn_colors": [[0.5, 0.4, 0.3]],
                             "mode": "multi_scale", "bsdf_model": "cycles"}},
      "objects": [{"mesh": ")" + mesh("quad.obj") + R"(", "material": "wool",
                   "transform": {"rotate": [)" + std::to_string(tilt) + R"(, 0, 0]}}]
    })";
    Warnings w;
    const Scene scene(parse_scene(text, "scene.json", test::test_dir()), BuildOptions{}, w);
    for (const Vec2 pixel : {Vec2(20, 24), Vec2(33, 31), Vec2(45, 40)}) {
      const RayDifferential ray = scene.camera().generate(pixel.x, pixel.y, 1.0f);
      SurfaceInteraction si;
      ASSERT_TRUE(scene.accel().intersect(ray, si));
      si.cone_width = si.t * ray.cone_spread;
      const auto* m = dynamic_cast<const KnitModelMaterial*>(&scene.material(si.material));
      ASSERT_NE(m, nullptr);
      const knit::BaseHit exact = m->base_hit(si, 1.0f);
      knit::BaseHit h = exact;
      ASSERT_TRUE(m->cycles_footprint(si, ray.d, h));
      const double a_exact = std::fabs(double(exact.dudx) * exact.dvdy - double(exact.dvdx) * exact.dudy);
      const double a = std::fabs(double(h.dudx) * h.dvdy - double(h.dvdx) * h.dudy);
      std::printf("[cycles footprint] tilt %2.0f: area %.4g (exact differentials %.4g)\n", tilt, a, a_exact);
      EXPECT_NEAR(a / a_exact, 1.0, 0.03) << "tilt " << tilt;
      // The long side along the view's projection on the surface, 1 / cos longer.
      const Vec3 v = si.shading.to_local(ray.d);
      const double cosv = std::fabs(v.z);
      EXPECT_NEAR(std::hypot(h.dudx, h.dvdx) / std::hypot(h.dudy, h.dvdy), 1.0 / std::max(cosv, 0.1), 1e-4);
      EXPECT_NEAR(std::fabs(h.dudx * v.y - h.dvdx * v.x), 0.0, 1e-4 * std::hypot(h.dudx, h.dvdx));
    }
  }
}

// Explicit yarns do not depend on the scene's absolute scale: a black
// swatch seen straight down under a white sky lets through the same light
// whether its tubes have radius 0.02 or 2e-4 world units (Embree 3 alone
// gets the thin ones wrong; CurveShape::attach instances them scaled up),
// and as much as the model does.
TEST(YarnTubes, ThinTubesLetThroughWhatThickOnesDo) {
  auto scene = [](double scale) {
    char buf[1400];
    std::snprintf(buf, sizeof buf, R"({
      "film": {"width": 24, "height": 24, "spp": 16, "seed": 3},
      "camera": {"position": [%g, %g, %g], "look_at": [%g, %g, 0], "fov": 10},
      "lights": [{"type": "environment", "color": [1, 1, 1]}],
      "materials": {"m": {"type": "knit", "pattern": ["KP"], "uv_scale": 40, "yarn_colors": [[0, 0, 0]],
                          "bsdf": {"body_energy": 0.0001}, "ply": {"enabled": false}}},
      "objects": [{"mesh": "%s", "material": "m", "transform": {"scale": %g}}]})",
                  0.05 * scale, 0.1 * scale, scale, 0.05 * scale, 0.1 * scale, mesh("quad.obj").c_str(), scale);
    return std::string(buf);
  };
  BuildOptions tubes;
  tubes.explicit_yarns = true;
  const std::string dir = test::test_dir();
  const double thick = test::mean_channel_value(test::render_text(dir, scene(1.0), 0, tubes).image);
  const double thin = test::mean_channel_value(test::render_text(dir, scene(0.01), 0, tubes).image);
  const double model = test::mean_channel_value(test::render_text(dir, scene(0.01)).image);
  std::printf("[thin tubes] light through: radius 0.02 %.4f, radius 2e-4 %.4f, model %.4f\n", thick, thin, model);
  EXPECT_GT(thick, 0.3);
  EXPECT_NEAR(thin, thick, 0.02);
  EXPECT_NEAR(model, thick, 0.03);
}

TEST(KnitFurnace, NearField) {
  const auto r = test::render_text(test::test_dir(), furnace_scene("near_field", false));
  EXPECT_EQ(r.result.stats.invalid_samples, 0u);
  EXPECT_GT(r.result.stats.resolves, 24u * 24u * 48u / 2);
  EXPECT_GT(r.result.stats.resolve_passes, 0u);
  EXPECT_EQ(r.result.stats.table_resolves, 0u);
  expect_white_furnace(r.image, "near field");
}

TEST(KnitFurnace, MultiScale) {
  const auto r = test::render_text(test::test_dir(), furnace_scene("multi_scale", false));
  EXPECT_EQ(r.result.stats.invalid_samples, 0u);
  // The hits the class table served (footprints of a cell or more, camera
  // rays and ray cones after bounces; the report prints their share).
  std::printf("[furnace] multi-scale: %.1f%% of %llu knit hits from the class table\n",
              100.0 * double(r.result.stats.table_resolves) / double(r.result.stats.resolves),
              static_cast<unsigned long long>(r.result.stats.resolves));
  EXPECT_GT(r.result.stats.table_resolves, 0u);
  EXPECT_LE(r.result.stats.table_resolves, r.result.stats.resolves);
  expect_white_furnace(r.image, "multi-scale");
}

// As Cycles renders it (bsdf_model "cycles", docs/cycles.md): the same
// lossless yarn is a translucent() closure of weight 1 (the body
// transmission's albedo; no GGX, no transparent() weight), shaded at the
// base hit without self-shadowing; multi-scale footprints are all marched.
// Cycles' side test drops the light that yarn normals tilted against the
// mesh's take from the mesh's other side: 13% of the furnace's light in the
// near field (the mixture without the test conserves energy:
// tests/native/test_bsdf_cycles.cpp).
TEST(KnitFurnace, CyclesNearField) {
  const auto r = test::render_text(test::test_dir(), furnace_scene("near_field", false, "cycles"));
  EXPECT_EQ(r.result.stats.invalid_samples, 0u);
  EXPECT_GT(r.result.stats.resolve_passes, 0u);
  EXPECT_EQ(r.result.stats.shell_bounces, 0u);  // (no bounces inside the shell)
  expect_lossy_furnace(r.image, "cycles, near field", 0.8);
}

TEST(KnitFurnace, CyclesMultiScale) {
  const auto r = test::render_text(test::test_dir(), furnace_scene("multi_scale", false, "cycles"));
  EXPECT_EQ(r.result.stats.invalid_samples, 0u);
  EXPECT_EQ(r.result.stats.table_resolves, 0u);
  EXPECT_GT(r.result.stats.aggregate_resolves, r.result.stats.camera_resolves / 2);
  expect_lossy_furnace(r.image, "cycles, multi-scale", 0.8);
}

TEST(KnitFurnace, ExplicitYarns) {
  const auto r = test::render_text(test::test_dir(), furnace_scene("near_field", true));
  EXPECT_EQ(r.result.stats.invalid_samples, 0u);
  EXPECT_EQ(r.result.stats.pass_limit, 0u);
  expect_white_furnace(r.image, "explicit yarns");
}

// A knit swatch between a floor and an area light: light reaches the floor
// through the gaps (shadow rays use transmittance(), BSDF-sampled rays pass
// through), and the camera sees the floor through the swatch too. NEE only,
// BSDF sampling only and MIS must agree. (1024 samples: BSDF sampling alone
// finds the small light rarely, and at 256 the image mean of one seed
// still moves by 1-2% between seeds.)
std::string strategies_scene(const std::string& strategy, const std::string& mode, bool occluder = false,
                             const std::string& bsdf_model = "exact") {
  // occluder: an opaque board between the fabric and part of the light, so
  // that light samples from inside the yarn shell meet it (PathStats::
  // marches_spared) and NEE must still agree with BSDF sampling.
  const std::string board =
      occluder ? R"(, {"mesh": ")" + mesh("quad.obj") + R"(", "material": "floor",
                  "transform": {"translate": [0.3, 0.9, 0], "rotate": [90, 0, 0], "scale": 0.6}})"
               : std::string();
  return R"({
    "film": {"width": 16, "height": 16, "spp": 1024, "seed": 11},
    "camera": {"position": [0, 1.6, 0.9], "look_at": [0, 0, 0], "fov": 30},
    "integrator": {"max_depth": 4, "rr_depth": 4, "strategy": ")" + strategy + R"("},
    "lights": [{"type": "quad", "corner": [-0.6, 1.4, -0.6], "edge_u": [1.2, 0, 0], "edge_v": [0, 0, 1.2], "emission": [3, 3, 3],
                "two_sided": true}],
    "materials": {"floor": {"type": "diffuse", "albedo": [0.7, 0.7, 0.7]},
                  "wool": {"type": "knit", "pattern": ["KKPP", "PPKK"], "uv_scale": 30, "r": 0.5,
                           "yarn_colors": [[0.8, 0.5, 0.3]], "mode": ")" + mode + R"(", "footprint_points": 4,
                           "bsdf_model": ")" + bsdf_model + R"(")" +
         // (with Cycles' closures, a smooth thin-slab lobe, most of it on the
         // transparent() closure, so that its pass-through is tested)
         (bsdf_model == "cycles" ? R"(, "bsdf": {"trans_roughness_x": 0.04, "trans_roughness_y": 0.06})" : "") + R"(}},
    "objects": [{"mesh": ")" + mesh("quad.obj") + R"(", "material": "floor", "transform": {"rotate": [-90, 0, 0], "scale": 3}},
                {"mesh": ")" + mesh("quad.obj") + R"(", "material": "wool",
                 "transform": {"translate": [0, 0.5, 0], "rotate": [-90, 0, 0], "scale": 1.2}})" + board + R"(]
  })";
}

void expect_strategies_agree(const std::string& mode, bool occluder = false, const std::string& bsdf_model = "exact") {
  const std::string dir = test::test_dir();
  double mean[3], err[3];
  const char* names[3] = {"mis", "nee", "bsdf"};
  for (int s = 0; s < 3; ++s) {
    const auto r = test::render_text(dir, strategies_scene(names[s], mode, occluder, bsdf_model));
    EXPECT_EQ(r.result.stats.invalid_samples, 0u);
    // Standard error of the image mean from the spread of 4x4-pixel block means.
    const RgbImage b = block_average(r.image, 4);
    double m = 0, m2 = 0;
    for (const Rgb& p : b.pixels) {
      m += p.mean();
      m2 += double(p.mean()) * p.mean();
    }
    const double n = double(b.pixels.size());
    m /= n;
    mean[s] = m;
    err[s] = std::sqrt(std::max(m2 / n - m * m, 0.0) / n);
    if (s == 0) EXPECT_GT(r.result.stats.shadow_resolves, 0u);
    if (occluder && s < 2) EXPECT_GT(r.result.stats.marches_spared, 1000u) << names[s];  // the board was met
    if (s == 2) EXPECT_EQ(r.result.stats.marches_spared, 0u);                            // no light samples
  }
  for (int s = 1; s < 3; ++s) {
    const double z = (mean[s] - mean[0]) / std::sqrt(err[0] * err[0] + err[s] * err[s]);
    std::printf("[strategies] %s%s%s: mis %.5f, %s %.5f (z = %.2f)\n", mode.c_str(),
                bsdf_model == "exact" ? "" : (", " + bsdf_model).c_str(), occluder ? " under a board" : "", mean[0],
                names[s], mean[s], z);
    EXPECT_LT(std::fabs(z), 4.0) << names[s];
    EXPECT_NEAR(mean[s] / mean[0], 1.0, 0.03) << names[s];
  }
}

TEST(KnitStrategies, NearFieldAgree) { expect_strategies_agree("near_field"); }
TEST(KnitStrategies, MultiScaleAgree) { expect_strategies_agree("multi_scale"); }
// Cycles' closures: the transparent() weight passes camera and bounce rays
// (resolve) and attenuates shadow rays (transmittance) alike.
TEST(KnitStrategies, CyclesNearFieldAgree) { expect_strategies_agree("near_field", false, "cycles"); }
TEST(KnitStrategies, CyclesMultiScaleAgree) { expect_strategies_agree("multi_scale", false, "cycles"); }
// Light samples from inside the shell first ask whether an opaque object
// blocks the light (Accel::occluded_by_blockers) and skip the march if so: a
// wrong answer there would make NEE darker than BSDF sampling.
TEST(KnitStrategies, NearFieldAgreeUnderAnOpaqueBoard) { expect_strategies_agree("near_field", true); }

// Blocker-only rays see geometry that shadow rays cannot pass and nothing else.
TEST(Accel, BlockerOnlyRaysIgnorePassThroughGeometry) {
  auto quad_at = [](float z) {
    auto m = std::make_shared<TriangleMesh>();
    m->positions = {{-1, -1, z}, {1, -1, z}, {1, 1, z}, {-1, 1, z}};
    m->normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    m->indices = {0, 1, 2, 0, 2, 3};
    return m;
  };
  Accel accel;
  const unsigned glass = accel.add(std::make_unique<TriangleShape>(quad_at(1)), 0, -1);
  accel.set_pass_through(glass);
  accel.add(std::make_unique<TriangleShape>(quad_at(3)), 1, -1);  // opaque
  accel.commit();
  Ray through_both;  // from z = 0 upwards: meets the pass-through quad, then the opaque one
  through_both.o = {0, 0, 0};
  through_both.d = {0, 0, 1};
  Ray only_glass = through_both;
  only_glass.tmax = 2;
  EXPECT_TRUE(accel.occluded(only_glass));
  EXPECT_FALSE(accel.occluded_by_blockers(only_glass));
  EXPECT_TRUE(accel.occluded_by_blockers(through_both));
  // Ordinary rays still meet the pass-through quad first.
  RayDifferential probe;
  probe.o = through_both.o;
  probe.d = through_both.d;
  SurfaceInteraction si;
  ASSERT_TRUE(accel.intersect(probe, si));
  EXPECT_EQ(si.material, 0);
  EXPECT_NEAR(si.t, 1.0f, 1e-5f);
}

TEST(KnitDeterminism, SameSeedSameImageWithOneAndTwoThreads) {
  const std::string dir = test::test_dir();
  for (const char* mode : {"near_field", "multi_scale"}) {
    std::string s = strategies_scene("mis", mode);
    const std::string spp = "\"spp\": 1024";
    const size_t at = s.find(spp);
    ASSERT_NE(at, std::string::npos);
    s.replace(at, spp.size(), "\"spp\": 4");
    const auto one = test::render_text(dir, s, 1);
    const auto two = test::render_text(dir, s, 2);
    ASSERT_EQ(one.image.pixels.size(), two.image.pixels.size());
    EXPECT_EQ(std::memcmp(one.image.pixels.data(), two.image.pixels.data(), one.image.pixels.size() * sizeof(Rgb)), 0)
        << mode;
  }
}

TEST(KnitFrames, BakedFramesRenderLikeExactOnes) {
  const std::string dir = test::test_dir();
  const TriangleMesh m = load_mesh(mesh("half_cylinder.obj"));
  BakeSettings bs;
  bs.width = 512;
  bs.height = 256;
  bake_frames(m, dir + "/frames.exr", bs);
  auto scene = [&](const std::string& frames) {
    return R"({
      "film": {"width": 32, "height": 32, "spp": 32, "seed": 2},
      "camera": {"position": [0.9, 0, 1.6], "look_at": [0.5, 0, 0.6], "fov": 25},
      "lights": [{"type": "environment", "color": [0.2, 0.2, 0.2]}, {"type": "directional", "to_light": [1, 0.5, 1], "irradiance": [3, 3, 3]}],
      "materials": {"wool": {"type": "knit", "pattern": ["KP"], "uv_scale": 60, "yarn_colors": [[0.8, 0.6, 0.4]],
                             "frames": ")" + frames + R"("}},
      "objects": [{"mesh": ")" + mesh("half_cylinder.obj") + R"(", "material": "wool"}]})";
  };
  const auto exact = test::render_text(dir, scene("exact"));
  const auto baked = test::render_text(dir, scene("frames.exr"));
  const auto curv = test::render_text(dir, scene("curvature"));
  const ImageStats b = compare_images(baked.image, exact.image, 4);
  const ImageStats c = compare_images(curv.image, exact.image, 4);
  std::printf("[frames] baked vs exact: rel. bias %+.4f, rel. RMSE (4x4 blocks) %.4f; curvature vs exact: %+.4f, %.4f\n",
              b.rel_bias, b.rel_rmse, c.rel_bias, c.rel_rmse);
  EXPECT_LT(std::fabs(b.rel_bias), 0.02);
  EXPECT_LT(b.rel_rmse, 0.1);
  EXPECT_LT(std::fabs(c.rel_bias), 0.02);
  EXPECT_LT(c.rel_rmse, 0.1);
}

// ---------------------------------------------------------------------------
// The model against explicit yarns (docs/results.md#model-versus-explicit-yarns)

struct Comparison {
  ImageStats pixels, blocks;  // model vs explicit: per pixel and over 4x4 blocks
  double noise_rmse = 0;      // estimated RMSE of (model - explicit) due to noise alone
  double seconds_model = 0, seconds_explicit = 0;
};

// Renders `d` at its film's samples and seed, with the model or as explicit
// yarns; no sample may be invalid.
RenderResult render_desc(const SceneDesc& d, bool explicit_yarns) {
  BuildOptions o;
  o.explicit_yarns = explicit_yarns;
  Warnings w;
  const Scene sc(d, o, w);
  RenderSettings s;
  s.spp = d.film.spp;
  s.seed = d.film.seed;
  RenderResult r = render_image(sc, s);
  EXPECT_EQ(r.stats.invalid_samples, 0u);
  return r;
}

// bsdf_model "cycles" (docs/cycles.md) against the exact near field, on the
// golden scenes: tests/render/golden/knit_cycles is knit_near_field with the
// option. Its render at the golden test's samples is compared with
// knit_near_field's reference (4,096 samples): the option renders what
// Cycles renders, without self-shadowing and with Cycles' closures, so it
// differs from the exact near field by what docs/cycles.md measures (the
// golden render against the exact reference: -10.3% bias, 28.5% RMSE over
// 4x4 blocks, Cycles' side test included), within the bounds below; and it
// is not the exact near field (the option switches).
TEST(KnitCycles, GoldenSceneIsNearTheExactNearFieldButNotIt) {
  const std::string g = test::source_dir() + "/tests/render/golden/";
  const SceneDesc cycles = load_scene_file(g + "knit_cycles/scene.json");
  const SceneDesc exact = load_scene_file(g + "knit_near_field/scene.json");
  ASSERT_EQ(cycles.materials.size(), exact.materials.size());
  const RenderResult c = render_desc(cycles, false);
  const RenderResult e = render_desc(exact, false);
  ASSERT_EQ(c.image.pixels.size(), e.image.pixels.size());
  EXPECT_NE(std::memcmp(c.image.pixels.data(), e.image.pixels.data(), c.image.pixels.size() * sizeof(Rgb)), 0)
      << "bsdf_model \"cycles\" rendered the exact near field's image";
  const RgbImage ref = read_rgb_image(g + "knit_near_field/reference.exr");
  const ImageStats px = compare_images(c.image, ref), bl = compare_images(c.image, ref, 4);
  const ImageStats epx = compare_images(e.image, ref), ebl = compare_images(e.image, ref, 4);
  std::printf("[cycles golden] against the exact near field's reference: bias %+.3f, RMSE %.3f per pixel, %.3f over "
              "4x4 blocks (the exact near field's own render: %+.3f, %.3f, %.3f)\n",
              px.rel_bias, px.rel_rmse, bl.rel_rmse, epx.rel_bias, epx.rel_rmse, ebl.rel_rmse);
  EXPECT_LT(std::fabs(px.rel_bias), 0.15);
  EXPECT_LT(bl.rel_rmse, 0.35);
  // ... and well beyond the noise of a render of the exact near field itself.
  EXPECT_GT(bl.rel_rmse, 2 * ebl.rel_rmse);
}

// A bent tube (a polyline around a circle of radius 1, 16 points to a
// quarter turn): the shading normal is perpendicular to the tangent
// interpolated along the segment, so it turns smoothly across a joint where
// the segments' own normals jump by the turn between them, and it is the
// circle's own normal (in the plane, pointing out of it) to second order in
// the segment's length (docs/renderer.md, "Tube density").
TEST(CurveShape, ShadingNormalsFollowTheCurveAcrossJoints) {
  Accel accel;
  auto tubes = std::make_shared<YarnTubes>();
  const int n = 17;
  const double step = 0.5 * M_PI / (n - 1);
  for (int i = 0; i < n; ++i) {
    const double a = step * i;
    tubes->vertices.insert(tubes->vertices.end(), {float(std::cos(a)), float(std::sin(a)), 0, 0.02f});
    tubes->color.push_back(0);
    tubes->arc.push_back(float(i));
    tubes->fabric_normal.push_back({0, 0, 1});
  }
  for (uint32_t k = 0; k + 1 < uint32_t(n); ++k) {
    tubes->segments.push_back(k);
    tubes->flags.push_back(uint8_t((k > 0 ? RTC_CURVE_FLAG_NEIGHBOR_LEFT : 0) |
                                   (k + 2 < uint32_t(n) ? RTC_CURVE_FLAG_NEIGHBOR_RIGHT : 0)));
  }
  accel.add(std::make_unique<CurveShape>(tubes), 0, -1);
  accel.commit();
  // Rays from far outside the circle straight at its centre meet the outer
  // side of the tube head on: the circle's normal there is the ray's reverse.
  double worst_shading = 0, worst_geometric = 0;
  int hits = 0;
  for (int j = 1; j < 200; ++j) {
    const double a = step * (2 + (n - 5) * j / 200.0);  // away from the ends
    const Vec3 out(float(std::cos(a)), float(std::sin(a)), 0);
    RayDifferential r;
    r.o = out * 3.0f;
    r.d = -out;
    SurfaceInteraction si;
    ASSERT_TRUE(accel.intersect(r, si));
    ++hits;
    worst_shading = std::max(worst_shading, std::acos(std::min(1.0, double(dot(si.shading.n, out)))));
    worst_geometric = std::max(worst_geometric, std::acos(std::min(1.0, double(dot(si.ng, out)))));
    EXPECT_NEAR(dot(si.shading.n, si.shading.t), 0.0f, 1e-5f);
    EXPECT_GT(dot(si.shading.n, si.ng), 0.99f);  // (the same side)
  }
  std::printf("[tubes] a quarter circle in 16 segments: worst normal error %.4f rad shaded, %.4f rad geometric "
              "(half a segment's turn: %.4f)\n",
              worst_shading, worst_geometric, step / 2);
  EXPECT_EQ(hits, 199);
  // The segments' own normals are off by up to half their turn; the shaded
  // ones by the tangents' interpolation error, a small fraction of it.
  EXPECT_GT(worst_geometric, 0.8 * step / 2);
  EXPECT_LT(worst_shading, 0.1 * step / 2);
}

// Camera hits on yarn tubes are counted by how many segments their pixel
// spans. On the half-cylinder close-up at 48 pixels the pixel's width at
// the surface is its distance times the pixel's angle; over the segments'
// median length (measured here from the tubes' points) that puts most hits
// in one bin, two bins lower at 32 points a stitch than at 128. The
// report's hint names the explicit_samples that would give nine tenths of
// the hits two segments a pixel or more (docs/renderer.md, "Tube
// density").
TEST(YarnTubes, CameraHitsAreCountedBySegmentsPerPixel) {
  SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/half_cylinder_closeup.json");
  d.film.width = d.film.height = 48;
  d.film.spp = 2;
  ASSERT_EQ(d.objects.size(), 1u);
  const TriangleMesh m = load_mesh(d.objects[0].mesh_file);
  const float distance = length(d.camera.look_at - d.camera.position);
  const float pixel = distance * 2 * std::tan(0.5f * d.camera.fov * 3.14159265f / 180) / float(d.film.height);
  int mode_bin[2] = {};
  const int samples[2] = {32, 128};
  for (int i = 0; i < 2; ++i) {
    for (MaterialDesc& md : d.materials)
      if (md.type == MaterialType::Knit) md.knit.explicit_samples = samples[i];
    const YarnTubes y = build_yarn_tubes(m, *d.materials[size_t(d.objects[0].material)].knit.model, samples[i]);
    std::vector<float> len;
    for (uint32_t k : y.segments) len.push_back(length(y.point(k + 1) - y.point(k)));
    std::nth_element(len.begin(), len.begin() + long(len.size() / 2), len.end());
    const float span = pixel / len[len.size() / 2];
    const RenderResult r = render_desc(d, true);
    uint64_t all = 0;
    for (int b = 0; b < kTubeBins; ++b) {
      all += r.stats.tube_spans[size_t(b)];
      if (r.stats.tube_spans[size_t(b)] > r.stats.tube_spans[size_t(mode_bin[i])]) mode_bin[i] = b;
    }
    std::printf("[tubes] %d points a stitch: a pixel spans %.2f median segments; %llu camera hits on tubes, "
                "%.0f%% in the bin of spans %.2f-%.2f\n",
                samples[i], span, static_cast<unsigned long long>(all),
                100.0 * double(r.stats.tube_spans[size_t(mode_bin[i])]) / double(std::max<uint64_t>(all, 1)),
                mode_bin[i] > 0 ? kTubeSpanEdges[size_t(mode_bin[i] - 1)] : 0.0f,
                mode_bin[i] < kTubeBins - 1 ? kTubeSpanEdges[size_t(mode_bin[i])] : 1e9f);
    ASSERT_GT(all, 48u * 48u);  // every pixel sees yarn, twice
    EXPECT_GT(r.stats.tube_spans[size_t(mode_bin[i])], all / 2);
    // The median segment's span lies in the mode's bin (or on its edge).
    if (mode_bin[i] > 0) EXPECT_GT(span, 0.9f * kTubeSpanEdges[size_t(mode_bin[i] - 1)]);
    if (mode_bin[i] < kTubeBins - 1) EXPECT_LT(span, 1.1f * kTubeSpanEdges[size_t(mode_bin[i])]);
    RenderReport rep;
    rep.explicit_yarns = true;
    rep.knit_materials = 1;
    rep.resolves = r.stats.resolves;
    rep.tube_spans = r.stats.tube_spans;
    rep.yarn_samples_min = rep.yarn_samples_max = samples[i];
    const std::string text = rep.to_text();
    if (i == 0)
      EXPECT_NE(text.find("\"explicit_samples\": 128 (now 32)"), std::string::npos) << text;
    else
      EXPECT_EQ(text.find("explicit_samples"), std::string::npos) << text;
  }
  EXPECT_EQ(mode_bin[1], mode_bin[0] + 2);  // four times the points: two octaves
}

// The report's reading of the counts, on counts made up for it.
TEST(YarnTubes, TubeDensityHintReadsTheCounts) {
  RenderReport rep;
  rep.explicit_yarns = true;
  rep.knit_materials = 1;
  rep.resolves = 1000;
  rep.yarn_samples_min = rep.yarn_samples_max = 64;
  const auto hint = [&] {
    const std::string t = rep.to_text();
    return t.find("explicit_samples") != std::string::npos ? t.substr(t.find("hint")) : std::string();
  };
  // bins: < 0.25, 0.5, 1, 2, 4, 8, and 8 or more
  rep.tube_spans = {0, 0, 0, 0, 500, 500, 0};
  EXPECT_EQ(rep.coarse_tube_share(), 0.0);
  EXPECT_EQ(rep.tube_samples_factor(), 1);
  EXPECT_EQ(hint(), "");
  rep.tube_spans = {0, 0, 0, 90, 910, 0, 0};  // 9% below two segments: no hint
  EXPECT_NEAR(rep.coarse_tube_share(), 0.09, 1e-12);
  EXPECT_EQ(hint(), "");
  rep.tube_spans = {0, 0, 0, 200, 800, 0, 0};  // a fifth at 1-2 segments: twice the points
  EXPECT_EQ(rep.tube_samples_factor(), 2);
  EXPECT_NE(hint().find("20% of the camera's hits"), std::string::npos) << hint();
  EXPECT_NE(hint().find("\"explicit_samples\": 128 (now 64)"), std::string::npos) << hint();
  rep.tube_spans = {0, 50, 60, 890, 0, 0, 0};  // the tenth reached at 0.5-1: four times
  EXPECT_EQ(rep.tube_samples_factor(), 4);
  EXPECT_NE(hint().find("\"explicit_samples\": 256 (now 64)"), std::string::npos) << hint();
  rep.yarn_samples_max = 128;  // two materials
  EXPECT_NE(hint().find("256 (now 64 to 128)"), std::string::npos) << hint();
  rep.yarn_samples_max = 64;
  rep.tube_spans = {100, 0, 0, 900, 0, 0, 0};  // a tenth below a quarter segment: at least 16 times
  EXPECT_EQ(rep.tube_samples_factor(), 16);
  EXPECT_NE(hint().find("\"explicit_samples\": at least 1024 (now 64)"), std::string::npos) << hint();
  rep.yarn_samples_min = rep.yarn_samples_max = 128;
  EXPECT_NE(hint().find("of 2048 or more (now 128), above its limit of 1024"), std::string::npos) << hint();
  rep.explicit_yarns = false;  // the model's hits: never
  EXPECT_EQ(hint(), "");
}

// Renders examples/scenes/<scene> at size x size with the model and as
// explicit yarns, each as two half-sample renders with different seeds (their
// difference estimates the noise; their mean is the full-sample image). The
// explicit yarns' seeds are not the model's: renders of one seed share their
// pixel jitter, and that correlated noise made the near field's RMSE against
// the tubes about 13% smaller than independent noise would (measured on the
// half cylinder at 128 pixels, 2026-12-05).
Comparison compare_model_and_explicit(const std::string& scene, int size, int spp,
                                      const std::function<void(SceneDesc&)>& edit = {}) {
  Comparison c;
  RgbImage img[2];
  double noise2 = 0;
  for (int e = 0; e < 2; ++e) {
    RgbImage half[2];
    for (int h = 0; h < 2; ++h) {
      SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/" + scene);
      d.film.width = d.film.height = size;
      d.film.spp = spp / 2;
      d.film.seed = 100 + 2 * e + h;
      if (edit) edit(d);
      const RenderResult r = render_desc(d, e == 1);
      (e ? c.seconds_explicit : c.seconds_model) += r.seconds;
      half[h] = r.image;
    }
    // rmse(a - b) of two independent half renders is sqrt(2) x the noise of
    // one half, and 2 x the noise of their mean.
    const double n = compare_images(half[0], half[1]).rmse / 2;
    noise2 += n * n;
    img[e] = RgbImage(size, size);
    for (size_t i = 0; i < img[e].pixels.size(); ++i) img[e].pixels[i] = (half[0].pixels[i] + half[1].pixels[i]) * 0.5f;
  }
  c.noise_rmse = std::sqrt(noise2);
  c.pixels = compare_images(img[0], img[1]);
  c.blocks = compare_images(img[0], img[1], 4);
  const std::string out = test::test_dir();
  write_float_image(out + "/model.exr", img[0]);
  write_float_image(out + "/explicit.exr", img[1]);
  std::printf("[model-vs-explicit] %s %dx%d %d spp: RMSE %.4f (rel %.3f), MAE %.4f (rel %.3f), bias %+.4f (rel %+.3f); "
              "4x4 blocks: RMSE %.4f (rel %.3f); noise RMSE %.4f; mean %.4f; %.1f s model, %.1f s explicit\n",
              scene.c_str(), size, size, spp, c.pixels.rmse, c.pixels.rel_rmse, c.pixels.mae, c.pixels.rel_mae,
              c.pixels.bias, c.pixels.rel_bias, c.blocks.rmse, c.blocks.rel_rmse, c.noise_rmse, c.pixels.mean_b,
              c.seconds_model, c.seconds_explicit);
  return c;
}

// Both lights of the close-up (front and back) for the far views too.
void front_and_back_light(SceneDesc& d) {
  LightDesc back = d.lights.back();
  back.to_light = normalize(Vec3(-0.25f, 0.3f, -1.0f));
  back.irradiance = Rgb(2.4f, 2.35f, 2.3f);
  back.path = "lights[2]";
  d.lights.push_back(back);
}

// Near field. Before self-shadowing and bounces inside the shell (light
// and bounces from a yarn hit crossing the rest of the shell) the model was
// 18% too bright here, 5% in the close-up and 23% on the swatch close-up;
// now within 3% (docs/results.md).
//
// Per pixel, the near field and the tubes differ by no more than their
// noise since 2026-12-05 (docs/results.md): the tubes take the model's ply
// coordinate (before, the polyline's summed length, whose drift along the
// rows put the ply's grooves and glints on other pixels), and the close-up
// examples' tubes have 128 points a stitch (`explicit_samples`; at 32 their
// facets put the glints elsewhere, 12.7% of the close-up's pixels' values).
// The RMSE is asserted below 1.3x the RMSE the two images' noise alone
// gives: measured 0.98x here, 1.06x in the half cylinder's close-up, 0.94x
// in the swatch's, 1.02x multi-scale, with the tubes' seeds their own and
// their normals smooth (0.86x, 1.06x, 0.87x, 0.95x with shared seeds; it
// was 1.00x, 2.62x, 2.14x and 1.69x before the shared ply coordinate).
void expect_within_noise(const Comparison& c) {
  EXPECT_LT(c.pixels.rmse, 1.3 * c.noise_rmse) << "the model and the tubes differ per pixel beyond their noise";
}

TEST(KnitVsExplicit, HalfCylinderFarView) {
  const Comparison c = compare_model_and_explicit("half_cylinder_front.json", 48, 256, front_and_back_light);
  // Measured +0.4%, 0.110, 0.043 (+0.4%, 0.134, 0.057 before the shared
  // ply coordinate).
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.05);
  EXPECT_LT(c.pixels.rel_mae, 0.16);
  EXPECT_LT(c.blocks.rel_rmse, 0.08);
  expect_within_noise(c);
}

// The same in multi-scale mode: at 48x48 a pixel covers several stitches,
// so every footprint comes from the class table (docs/multiscale.md).
TEST(KnitVsExplicit, HalfCylinderFarViewMultiScale) {
  const Comparison c = compare_model_and_explicit("half_cylinder_front.json", 48, 64, [](SceneDesc& d) {
    front_and_back_light(d);
    for (MaterialDesc& m : d.materials) {
      if (m.type != MaterialType::Knit) continue;
      knit::KnitMaterialParams p = m.knit.model->params();
      p.mode = knit::KnitMode::MultiScale;
      m.knit.model = std::make_shared<const knit::KnitMaterial>(m.knit.model->surface().pattern(), p);
      ASSERT_NE(m.knit.model->footprint_table(), nullptr);
    }
  });
  // Measured +3.0%, 0.224, 0.190 when the bounds were set, +4.0%, 0.200,
  // 0.184 on 2026-11-23 (at 64 spp the MAE and the block error are mostly
  // the two images' noise: noise RMSE 0.028 of RMSE 0.032); -0.6%, 0.153,
  // 0.086 with the tabulated BSDF (2026-11-24); -0.7%, 0.167, 0.105 against
  // the corrected ground truth, 0.0%, 0.162, 0.093 with its 64-point tubes
  // (2026-12-05; the table's means are within
  // 0.2% of the tubes' at 128 to 512 pixels, docs/multiscale.md, "Against
  // the corrected ground truth").
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.03);
  EXPECT_LT(c.pixels.rel_mae, 0.3);
  EXPECT_LT(c.blocks.rel_rmse, 0.25);
}

TEST(KnitVsExplicit, HalfCylinderCloseUp) {
  const Comparison c = compare_model_and_explicit("half_cylinder_closeup.json", 48, 256);
  // Measured +0.2%, 0.056, 0.038 (-1.2%, 0.135, 0.069 before the shared ply
  // coordinate and the denser tubes).
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.02);
  EXPECT_LT(c.pixels.rel_mae, 0.1);
  EXPECT_LT(c.blocks.rel_rmse, 0.07);
  expect_within_noise(c);
}

TEST(KnitVsExplicit, SwatchFarViewMultiScale) {
  const Comparison c = compare_model_and_explicit("swatch_far.json", 48, 64);
  // Measured -2.4%, 0.069, 0.042; -0.6%, 0.048, 0.024 with the tabulated
  // BSDF (2026-11-24); -0.7%, 0.047, 0.023 (2026-12-05); -0.2%, 0.047,
  // 0.023 with 64-point tubes.
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.03);
  EXPECT_LT(c.pixels.rel_mae, 0.12);
  EXPECT_LT(c.blocks.rel_rmse, 0.08);
}

// The distant swatch example: stitches a third the size, every footprint of
// the default render a cell or more (test_examples.cpp), so all of it comes
// from the class table; 96 x 96 gives about 6 x 6 stitches a pixel.
TEST(KnitVsExplicit, SwatchDistantMultiScale) {
  const Comparison c = compare_model_and_explicit("swatch_distant.json", 96, 64);
  // Measured -1.9%, 0.051, 0.037 (2026-11-23); -0.2%, 0.048, 0.020 with
  // the tabulated BSDF (2026-11-24); -0.4%, 0.047, 0.021 (2026-12-05);
  // 0.0%, 0.047, 0.022 with 64-point tubes.
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.03);
  EXPECT_LT(c.pixels.rel_mae, 0.12);
  EXPECT_LT(c.blocks.rel_rmse, 0.08);
}

TEST(KnitVsExplicit, SwatchCloseUp) {
  const Comparison c = compare_model_and_explicit("swatch_closeup.json", 48, 256);
  // Measured -0.1%, 0.039, 0.018 (-1.6%, 0.099, 0.052 before; the tubes of
  // 32 points a stitch were 1.9% brighter).
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.02);
  EXPECT_LT(c.pixels.rel_mae, 0.08);
  EXPECT_LT(c.blocks.rel_rmse, 0.04);
  expect_within_noise(c);
}

// Multi-scale in close-up: footprints below a stitch cell are shaded as the
// near field (near_field_below_cell), self-shadowing included. Their marched
// aggregate (near_field_below_cell false), which averages the normals of its
// points and has no self-shadowing, was 13.8% too bright here (MAE 0.27).
TEST(KnitVsExplicit, SwatchCloseUpMultiScale) {
  const Comparison c = compare_model_and_explicit("swatch_closeup.json", 48, 128, [](SceneDesc& d) {
    for (MaterialDesc& m : d.materials) {
      if (m.type != MaterialType::Knit) continue;
      knit::KnitMaterialParams p = m.knit.model->params();
      p.mode = knit::KnitMode::MultiScale;
      ASSERT_TRUE(p.near_field_below_cell);
      m.knit.model = std::make_shared<const knit::KnitMaterial>(m.knit.model->surface().pattern(), p);
    }
  });
  // Measured -0.2%, 0.058, 0.027 (-1.6%, 0.109, 0.052 before).
  EXPECT_LT(std::fabs(c.pixels.rel_bias), 0.02);
  EXPECT_LT(c.pixels.rel_mae, 0.1);
  EXPECT_LT(c.blocks.rel_rmse, 0.05);
  expect_within_noise(c);
}

// Footprints centred at their pixel's centre (footprint_centre "pixel")
// against each sample's own hit ("sample"): the far swatch example seen at
// its own pixel size (a third of a stitch cell), a 96 x 96 window of its
// 480 x 360, with the table's quarter cells (table_min_cells 0.25) serving
// every footprint. Each sample's box spread over the pixel averaged the
// pixel twice and added noise; one box per pixel makes the image closer to
// explicit yarns with less noise (docs/multiscale.md, "A footprint per
// pixel"), and lets the pixel's samples share it ("One box a pixel, kept").
TEST(KnitVsExplicit, SwatchFarQuarterCellsCentredAtPixels) {
  const int size = 96;
  const auto render = [&](int method, int seed) {  // 0: explicit, 1: pixel, 2: sample
    SceneDesc d = load_scene_file(test::source_dir() + "/examples/scenes/swatch_far.json");
    const float half = 0.5f * d.camera.fov * 3.14159265f / 180;
    d.camera.fov = 2 * std::atan(std::tan(half) * float(size) / float(d.film.height)) * 180 / 3.14159265f;
    d.film.width = d.film.height = size;
    d.film.spp = 64;
    d.film.seed = seed;
    for (MaterialDesc& m : d.materials) {
      if (m.type != MaterialType::Knit) continue;
      knit::KnitMaterialParams p = m.knit.model->params();
      p.mode = knit::KnitMode::MultiScale;
      p.table_min_cells = 0.25f;
      m.knit.model = std::make_shared<const knit::KnitMaterial>(m.knit.model->surface().pattern(), p);
      m.knit.footprint_centre = method == 2 ? FootprintCentre::Sample : FootprintCentre::Pixel;
    }
    const RenderResult r = render_desc(d, method == 0);
    if (method > 0) EXPECT_GT(r.stats.sub_cell_resolves, r.stats.resolves * 9 / 10) << "from the quarter cells";
    // One box a pixel: its later camera samples take it from the pixel's
    // memo (knit::FootprintMemo), which a box per sample never matches.
    if (method == 1) EXPECT_GT(r.stats.sub_boxes_reused, r.stats.sub_cell_resolves * 8 / 10);
    if (method == 2) EXPECT_EQ(r.stats.sub_boxes_reused, 0u);
    return r.image;
  };
  const RgbImage truth = render(0, 3);  // (a seed of its own: see compare_model_and_explicit)
  double noise[3] = {}, error[3] = {};
  for (int method = 1; method <= 2; ++method) {
    const RgbImage a = render(method, 1), b = render(method, 2);
    noise[method] = compare_images(a, b).rmse / std::sqrt(2.0);  // one render's
    error[method] = compare_images(a, truth).rmse;
  }
  std::printf("[pixel-centre] RMSE against explicit yarns: pixel %.5f, sample %.5f; noise %.5f, %.5f\n", error[1],
              error[2], noise[1], noise[2]);
  EXPECT_LT(noise[1], 0.8 * noise[2]);
  EXPECT_LT(error[1], 0.95 * error[2]);
}

// The class table's shading under one light (docs/multiscale.md, "The
// table's shading: a tabulated BSDF"): a flat swatch of seed stitch seen 30
// degrees from its normal, far enough for every footprint to be a cell or
// more, lit by one directional light from the front, at a grazing angle and
// from behind. Per channel, the tabulated BSDF against explicit yarns, and
// the yarn BSDF at the footprint's mean normal (table_bsdf false) beside it.
TEST(KnitVsExplicit, SwatchUnderOneLightTableBsdf) {
  const std::string dir = test::test_dir();
  struct Light {
    const char* name;
    float theta, phi;  // degrees from the front normal, azimuth
  };
  const Light lights[] = {{"front 45", 45, 60}, {"grazing 70", 70, 150}, {"behind 135", 135, 60}};
  double worst_table = 0, sum_table = 0, sum_lean = 0;
  int n = 0;
  for (const Light& l : lights) {
    const float th = l.theta * 3.14159265f / 180, ph = l.phi * 3.14159265f / 180;
    char light[160];
    std::snprintf(light, sizeof light, "[%.6f, %.6f, %.6f]", std::sin(th) * std::cos(ph),
                  std::sin(th) * std::sin(ph), std::cos(th));
    const auto scene = [&](const char* knit_keys) {
      return std::string(R"({"version": 1, "film": {"width": 32, "height": 32, "spp": 64, "seed": 3},
        "camera": {"position": [0, -1, 1.7320508], "look_at": [0, 0, 0], "fov": 6},
        "integrator": {"max_depth": 12},
        "lights": [{"type": "directional", "to_light": )") +
             light + R"(, "irradiance": [3, 3, 3]}],
        "materials": {"wool": {"type": "knit", "pattern": ")" + test::source_dir() +
             R"(/examples/patterns/seed.knit", "uv_scale": 600, "yarn_colors": [[0.72, 0.18, 0.14]],
          "bsdf": {"body_energy": 0.85, "body_reflect": 0.7}, "mode": "multi_scale")" + knit_keys + R"(}},
        "objects": [{"mesh": ")" + mesh("quad.obj") + R"(", "material": "wool",
                     "transform": {"scale": [0.3, 0.3, 1]}}]})";
    };
    BuildOptions ex;
    ex.explicit_yarns = true;
    const test::Rendered table = test::render_text(dir, scene(""));
    const test::Rendered lean = test::render_text(dir, scene(R"(, "table_bsdf": false)"));
    const test::Rendered truth = test::render_text(dir, scene(""), 0, ex);
    EXPECT_EQ(table.result.stats.table_resolves, table.result.stats.resolves) << "all of it from the table";
    const auto mean = [](const RgbImage& img, int c) {
      double s = 0;
      for (const Rgb& p : img.pixels) s += c == 0 ? p.r : (c == 1 ? p.g : p.b);
      return s / double(img.pixels.size());
    };
    for (int c = 0; c < 3; ++c) {
      const double e = mean(truth.image, c);
      const double bt = mean(table.image, c) / e - 1, bl = mean(lean.image, c) / e - 1;
      std::printf("[table-bsdf] %s, channel %d: tabulated %+.3f, mean normal %+.3f against explicit yarns\n", l.name,
                  c, bt, bl);
      worst_table = std::max(worst_table, std::fabs(bt));
      sum_table += std::fabs(bt);
      sum_lean += std::fabs(bl);
      ++n;
    }
  }
  std::printf("[table-bsdf] mean |bias| tabulated %.3f, mean normal %.3f; worst tabulated %.3f\n", sum_table / n,
              sum_lean / n, worst_table);
  // Measured (2026-11-24): tabulated -6.1% .. +5.8% (mean 3.5%; with 256
  // rays per table node, 5.1% and +12.2% at worst), the mean normal's
  // -20% .. -64% (mean 48%).
  EXPECT_LT(worst_table, 0.2);
  EXPECT_LT(sum_table / n, 0.12);
  EXPECT_GT(sum_lean / n, 2.5 * (sum_table / n));
}

}  // namespace
}  // namespace knit::render
