// The image is a pure function of (scene, spp, seed): identical with 1 and 2
// threads and across runs, different for another seed.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "render_test_util.h"

namespace knit::render {
namespace {

std::string scene(int seed) {
  const std::string m = test::meshes_dir();
  return R"({
    "film": {"width": 40, "height": 24, "spp": 8, "seed": )" + std::to_string(seed) + R"(},
    "camera": {"position": [0.4, 1.3, 3.5], "look_at": [0, 0.4, 0], "fov": 40},
    "integrator": {"max_depth": 8, "rr_depth": 2},
    "lights": [{"type": "environment", "file": ")" + test::source_dir() + R"(/examples/scenes/sky.hdr"},
               {"type": "quad", "corner": [-1.5, 1, 1], "edge_u": [0, 0, -1], "edge_v": [0, 1, 0], "emission": [5, 4, 3]},
               {"type": "point", "position": [1, 2, 1], "intensity": [2, 2, 2]}],
    "materials": {"floor": {"type": "diffuse", "albedo": [0.5, 0.5, 0.5]},
                  "glass": {"type": "dielectric", "eta": 1.5},
                  "sheet": {"type": "thin", "transmittance": [0.4, 0.4, 0.4], "albedo": [0.3, 0.2, 0.1]},
                  "cushion": {"type": "diffuse", "albedo": [0.7, 0.2, 0.1]}},
    "objects": [{"mesh": ")" + m + R"(/ground.obj", "material": "floor"},
                {"mesh": ")" + m + R"(/sphere.obj", "material": "glass", "transform": {"translate": [0.5, 0.35, 0.3], "scale": 0.35}},
                {"mesh": ")" + m + R"(/cushion.obj", "material": "cushion", "transform": {"translate": [-0.6, 0, 0], "scale": 0.5}},
                {"mesh": ")" + m + R"(/quad.obj", "material": "sheet", "transform": {"translate": [0, 0.6, -0.5]}}]
  })";
}

bool identical(const RgbImage& a, const RgbImage& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Rgb)) == 0;
}

TEST(Determinism, SameSeedSameImageWithOneAndTwoThreads) {
  const std::string dir = test::test_dir();
  const auto one = test::render_text(dir, scene(3), 1);
  const auto two = test::render_text(dir, scene(3), 2);
  const auto again = test::render_text(dir, scene(3), 2);
  EXPECT_EQ(one.result.threads, 1);
  EXPECT_EQ(two.result.threads, 2);
  EXPECT_TRUE(identical(one.image, two.image)) << "1 thread and 2 threads differ";
  EXPECT_TRUE(identical(two.image, again.image)) << "two runs differ";
  // The work counters are sums over pixels, so they do not depend on scheduling either.
  EXPECT_EQ(one.result.stats.total_rays(), two.result.stats.total_rays());
  EXPECT_GT(one.result.stats.shadow_rays, 0u);
}

TEST(Determinism, AnotherSeedGivesAnotherImage) {
  const std::string dir = test::test_dir();
  const auto a = test::render_text(dir, scene(3), 2);
  const auto b = test::render_text(dir, scene(4), 2);
  EXPECT_FALSE(identical(a.image, b.image));
}

// The tiles are visited in a fixed shuffled order (render_image's images do
// not depend on it: the tests above), so that the share of the work done
// tracks the share of tiles done, which is what the progress ETA assumes.
TEST(TileOrder, IsAFixedPermutationWhosePrefixesSampleTheFrameEvenly) {
  EXPECT_TRUE(tile_order(0).empty());
  EXPECT_EQ(tile_order(1), std::vector<int>{0});
  const int tx = 30, ty = 17, n = tx * ty;  // the demo's 480 x 270 in 16-pixel tiles
  const std::vector<int> order = tile_order(n);
  EXPECT_EQ(order, tile_order(n)) << "the order must not change between calls";
  std::vector<int> seen(size_t(n), 0);
  for (int t : order) {
    ASSERT_GE(t, 0);
    ASSERT_LT(t, n);
    ++seen[size_t(t)];
  }
  for (int c : seen) ASSERT_EQ(c, 1) << "not a permutation";
  // The demo's cost: its knits fill the lower half of the frame, the sky above
  // costs next to nothing. After each tenth of the tiles, the share of that
  // cost done must be near a tenth as well (in raster order it stays 0 until
  // half the tiles are done).
  double total = 0;
  for (int t = 0; t < n; ++t) total += (t / tx) >= ty / 2 ? 1.0 : 0.0;
  double done = 0;
  for (int i = 0; i < n; ++i) {
    done += (order[size_t(i)] / tx) >= ty / 2 ? 1.0 : 0.0;
    if ((i + 1) % (n / 10) == 0)
      EXPECT_NEAR(done / total, double(i + 1) / n, 0.1) << "after " << i + 1 << " of " << n << " tiles";
  }
}

}  // namespace
}  // namespace knit::render
