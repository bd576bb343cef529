// `knitshade compare A.exr B.exr`: linear-space error statistics of two
// renders (RMSE, mean absolute error, bias), as JSON on stdout.
#ifdef KNIT_HAVE_RENDER

#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "render/image_compare.h"

namespace knit::cli {
namespace {

const char* kUsage =
    "usage: knitshade compare A.exr B.exr [--block N]\n"
    "\n"
    "Prints linear-space statistics of A against B as JSON: rmse, mae (mean\n"
    "absolute error), mean_a, mean_b, bias = mean_a - mean_b, and the same\n"
    "relative to mean_b. --block N averages N x N pixel blocks first.\n";

int run(const std::vector<std::string>& args) {
  using namespace knit::render;
  std::vector<std::string> files;
  int block = 1;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "--block") {
      block = static_cast<int>(parse_int_option(a, option_value(args, i), 1, 4096));
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else {
      files.push_back(a);
    }
  }
  if (files.size() != 2) throw UsageError{"compare needs two images"};
  try {
    const RgbImage a = read_rgb_image(files[0]), b = read_rgb_image(files[1]);
    std::printf("%s", compare_images(a, b, block).to_json().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "knitshade compare: error: %s\n", e.what());
  }
  return 1;
}

const bool registered = register_command({"compare", "error statistics (RMSE, MAE, bias) of two images", &run});

}  // namespace
}  // namespace knit::cli

#endif  // KNIT_HAVE_RENDER
