// Visibility of every shipped example pattern: the fraction of vertical rays
// that hit yarn, from the analytic query and from ray casts of the explicit
// tubes at the same points, over one pattern repeat. Must agree within 1%.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "knit/surface.h"
#include "knit/yarns.h"
#include "tube_raycast.h"

namespace {

using namespace knit;
using namespace knit::test;

std::vector<std::string> example_patterns() {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(std::string(KNIT_SOURCE_DIR) + "/examples/patterns"))
    if (e.path().extension() == ".knit") files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(Visibility, EveryExamplePatternMatchesExplicitTubes) {
  const std::vector<std::string> files = example_patterns();
  ASSERT_GE(files.size(), 10u) << "examples/patterns must ship at least ten patterns";
  const StitchParams sp;
  for (const std::string& f : files) {
    const Pattern pat = Pattern::from_file(f);
    const KnitSurface surf(pat, sp);
    const double px = surf.period_x(), py = surf.period_y(), margin = 8;
    // Tiles covering [0, margin + period + margin] in both directions.
    const int tu = int(std::ceil((px + 2 * margin) / px)), tv = int(std::ceil((py + 2 * margin) / py));
    const ExplicitYarns y = explicit_yarns(pat, sp, tu, tv, 128);
    TubeScene tubes;
    for (const YarnCurve& c : y.curves) {
      std::vector<D3> pts(c.points.begin(), c.points.end());
      tubes.add_curve(std::move(pts), y.radius);
    }
    tubes.build();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(0, 1);
    const int n = 6000;
    int hit_model = 0, hit_truth = 0, disagree = 0;
    for (int i = 0; i < n; ++i) {
      const double x = margin + px * U(rng), yy = margin + py * U(rng);
      const bool m = surf.query(float(x), float(yy)).hit;
      const bool t = tubes.intersect({x, yy, surf.shell_top() + 1}, {0, 0, -1}, 0, 100).hit;
      hit_model += m;
      hit_truth += t;
      disagree += (m != t);
    }
    const double vm = double(hit_model) / n, vt = double(hit_truth) / n;
    std::printf("[ vis ] %-28s %3dx%-3d visibility model %.4f explicit %.4f (|diff| %.4f, %d of %d points differ)\n",
                std::filesystem::path(f).filename().c_str(), pat.rows(), pat.cols(), vm, vt, std::abs(vm - vt),
                disagree, n);
    EXPECT_LT(std::abs(vm - vt), 0.01) << f;
  }
}

}  // namespace
