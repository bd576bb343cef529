// Ray differentials (Igehy 1999): the camera footprint on a plane, and the
// transfer through specular reflection and refraction on a curved surface,
// against offset rays traced exactly.
#include <gtest/gtest.h>

#include <cmath>

#include "render/differentials.h"
#include "render/fresnel.h"
#include "render/scene.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

TEST(Differentials, CameraFootprintOnAPlaneMatchesTheNeighbouringPixel) {
  const std::string dir = test::test_dir();
  const std::string text = R"({
    "film": {"width": 64, "height": 48, "spp": 1},
    "camera": {"position": [0.3, 0.2, 4], "look_at": [0, 0, 0], "fov": 30},
    "lights": [{"type": "point", "position": [0, 0, 3], "intensity": [1, 1, 1]}],
    "materials": {"m": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]}},
    "objects": [{"mesh": ")" + test::mesh("quad.obj") + R"(", "material": "m", "transform": {"scale": 4, "rotate": [10, 20, 0]}}]
  })";
  Warnings w;
  const Scene scene(parse_scene(text, "scene.json", dir), BuildOptions{}, w);
  for (float px : {20.5f, 32.0f, 41.25f}) {
    const float py = 24.5f;
    const RayDifferential ray = scene.camera().generate(px, py);
    SurfaceInteraction si, sx, sy;
    ASSERT_TRUE(scene.accel().intersect(ray, si));
    ASSERT_TRUE(si.footprint.valid);
    ASSERT_TRUE(scene.accel().intersect(scene.camera().generate(px + 1, py), sx));
    ASSERT_TRUE(scene.accel().intersect(scene.camera().generate(px, py + 1), sy));
    // On a plane the offset-ray construction is exact.
    EXPECT_LT(length(si.footprint.dpdx - (sx.p - si.p)), 1e-4f * length(sx.p - si.p) + 1e-6f);
    EXPECT_LT(length(si.footprint.dpdy - (sy.p - si.p)), 1e-4f * length(sy.p - si.p) + 1e-6f);
    EXPECT_NEAR(si.footprint.dudx, sx.uv.x - si.uv.x, 1e-4f * std::fabs(sx.uv.x - si.uv.x) + 1e-6f);
    EXPECT_NEAR(si.footprint.dvdy, sy.uv.y - si.uv.y, 1e-4f * std::fabs(sy.uv.y - si.uv.y) + 1e-6f);
    // Quad UVs span 4 scene units: a texel-per-pixel sanity check.
    EXPECT_GT(std::fabs(si.footprint.dudx), 1e-4f);
  }
  // Scaled offsets: max(1/8, 1/sqrt(spp)) of a pixel.
  const RayDifferential r4 = scene.camera().generate(10, 10, 0.25f);
  const RayDifferential r1 = scene.camera().generate(10, 10, 1.0f);
  EXPECT_LT(length((r4.rx_d - r4.d) * 4.0f - (r1.rx_d - r1.d)), 1e-6f);
}

// A sphere of radius R at the origin, hit at p by a ray from `o`; the offset
// ray leaves `o` with direction d + delta. The interaction carries the exact
// first-order footprint of a sphere (dn = dp / R).
struct SphereCase {
  float radius = 1.0f;
  Vec3 o{0.2f, 0.3f, 4.0f};
  Vec3 d;
  SurfaceInteraction si;
  RayDifferential ray;

  SphereCase(Vec3 target, Vec3 delta, Vec3 origin = {0.2f, 0.3f, 4.0f}) : o(origin) {
    d = normalize(target - o);
    ray.o = o;
    ray.d = d;
    ray.has_differentials = true;
    ray.rx_o = o;
    ray.rx_d = normalize(d + delta);
    ray.ry_o = o;
    ray.ry_d = normalize(d - delta);
    const float t = hit(o, d);
    si.p = o + d * t;
    const Vec3 n = si.p / radius;
    si.ng = n;
    si.shading = Frame::from_normal(n);
    Footprint& f = si.footprint;
    f.valid = true;
    const Vec3 offs[2] = {ray.rx_d, ray.ry_d};
    Vec3 dp[2];
    for (int k = 0; k < 2; ++k) {
      const float tk = dot(n, si.p - o) / dot(n, offs[k]);
      dp[k] = o + offs[k] * tk - si.p;
    }
    f.dpdx = dp[0];
    f.dpdy = dp[1];
    f.dndx = dp[0] / radius;
    f.dndy = dp[1] / radius;
  }

  // Nearest positive root (from outside or from inside).
  float hit(Vec3 from, Vec3 dir) const {
    const float b = dot(from, dir), c = dot(from, from) - radius * radius;
    const float t0 = -b - std::sqrt(b * b - c);
    return t0 > 0 ? t0 : -b + std::sqrt(b * b - c);
  }
};

Vec3 reflect(Vec3 wo, Vec3 n) { return n * (2 * dot(wo, n)) - wo; }

TEST(Differentials, SpecularReflectionTransferIsFirstOrderAccurate) {
  for (float step : {1e-3f, 5e-4f}) {
    SphereCase c({0.35f, 0.1f, 0.0f}, Vec3(step, 0.3f * step, 0));
    BsdfSample bs;
    bs.flags = kReflection | kSpecular;
    RayDifferential out;
    out.o = c.si.p;
    out.d = reflect(-c.d, c.si.shading.n);
    differentials_specular(c.ray, c.si, bs, out);
    ASSERT_TRUE(out.has_differentials);
    // Exact: trace the offset ray to the sphere and reflect it there.
    const Vec3 q = c.o + c.ray.rx_d * c.hit(c.o, c.ray.rx_d);
    const Vec3 exact = reflect(-c.ray.rx_d, q / c.radius);
    const float change = length(exact - out.d);
    const float err = length(out.rx_d - exact);
    EXPECT_GT(change, 1e-4f);
    EXPECT_LT(err, 0.02f * change) << "step " << step;
    EXPECT_LT(length(out.rx_o - q), 0.02f * length(q - c.si.p));
  }
}

TEST(Differentials, SpecularRefractionTransferIsFirstOrderAccurate) {
  const float eta = 1.5f;
  SphereCase c({0.3f, -0.2f, 0.0f}, Vec3(8e-4f, -5e-4f, 0));
  const Vec3 n = c.si.shading.n;
  Vec3 wi;
  ASSERT_TRUE(refract(-c.d, n, eta, wi));
  BsdfSample bs;
  bs.flags = kTransmission | kSpecular;
  bs.eta = eta;
  RayDifferential out;
  out.o = c.si.p;
  out.d = wi;
  differentials_specular(c.ray, c.si, bs, out);
  ASSERT_TRUE(out.has_differentials);
  const Vec3 q = c.o + c.ray.rx_d * c.hit(c.o, c.ray.rx_d);
  Vec3 exact;
  ASSERT_TRUE(refract(-c.ray.rx_d, q / c.radius, eta, exact));
  const float change = length(exact - wi);
  EXPECT_GT(change, 1e-4f);
  EXPECT_LT(length(out.rx_d - exact), 0.02f * change);

  // Leaving the glass: a ray from inside refracts out (eta_rel = 1 / 1.5) and
  // the transfer flips the outward shading normal to the ray's side.
  SphereCase in({0.9f, 0.3f, 0.2f}, Vec3(4e-4f, 6e-4f, -3e-4f), {0.1f, -0.2f, 0.3f});
  ASSERT_LT(dot(-in.d, in.si.shading.n), 0.0f);
  Vec3 out_dir;
  ASSERT_TRUE(refract(-in.d, -in.si.shading.n, 1 / eta, out_dir));
  BsdfSample bs2;
  bs2.flags = kTransmission | kSpecular;
  bs2.eta = 1 / eta;
  RayDifferential out2;
  out2.o = in.si.p;
  out2.d = out_dir;
  differentials_specular(in.ray, in.si, bs2, out2);
  ASSERT_TRUE(out2.has_differentials);
  const Vec3 q2 = in.o + in.ray.rx_d * in.hit(in.o, in.ray.rx_d);
  Vec3 exact2;
  ASSERT_TRUE(refract(-in.ray.rx_d, -q2 / in.radius, 1 / eta, exact2));
  const float change2 = length(exact2 - out_dir);
  EXPECT_GT(change2, 1e-4f);
  EXPECT_LT(length(out2.rx_d - exact2), 0.02f * change2);

  // Reversibility of the refraction helper itself.
  Vec3 back;
  const Vec3 wo_inside = wi;  // the reverse path: from inside back out through p
  ASSERT_TRUE(refract(wo_inside, -n, 1 / eta, back));
  EXPECT_NEAR(dot(back, -c.d), 1.0f, 1e-5f);  // reversibility of Snell's law
}

}  // namespace
}  // namespace knit::render
