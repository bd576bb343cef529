// `knitshade compare A.exr B.exr`: linear-space error statistics of two
// renders (RMSE, mean absolute error, bias), as JSON on stdout.
#ifdef KNIT_HAVE_RENDER

#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli.h"
#include "cli_args.h"
#include "render/image_compare.h"

namespace knit::cli {
namespace {

const char* kUsage =
    "usage: knitshade compare A.exr B.exr [--block N] [--mask MASK.exr]\n"
    "\n"
    "Prints linear-space statistics of A against B as JSON: rmse, mae (mean\n"
    "absolute error), mean_a, mean_b, bias = mean_a - mean_b, and the same\n"
    "relative to mean_b. --block N averages N x N pixel blocks first.\n"
    "--mask counts only the pixels whose mask value (first channel) is at\n"
    "least 0.5, e.g. a mask from `knitshade render --mask-object NAME`.\n";

int run(const std::vector<std::string>& args) {
  using namespace knit::render;
  std::vector<std::string> files;
  int block = 1;
  std::string mask_file;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "-h" || a == "--help") {
      std::printf("%s", kUsage);
      return 0;
    } else if (a == "--block") {
      block = static_cast<int>(parse_int_option(a, option_value(args, i), 1, 4096));
    } else if (a == "--mask") {
      mask_file = option_value(args, i);
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError{"unknown option " + a};
    } else {
      files.push_back(a);
    }
  }
  if (files.size() != 2) throw UsageError{"compare needs two images"};
  try {
    const RgbImage a = read_rgb_image(files[0]), b = read_rgb_image(files[1]);
    if (mask_file.empty()) {
      std::printf("%s", compare_images(a, b, block).to_json().c_str());
    } else {
      const RgbImage mask = read_rgb_image(mask_file);
      try {
        std::printf("%s", compare_images(a, b, block, &mask).to_json().c_str());
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(mask_file + ": " + e.what());
      }
    }
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
