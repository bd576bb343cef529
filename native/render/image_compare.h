// Linear-space error statistics between two renders of the same size: what
// the model-versus-explicit-yarn tests and benchmarks report, and
// `knitshade compare` prints.
#pragma once

#include <string>

#include "render/image.h"

namespace knit::render {

struct ImageStats {
  double rmse = 0;       // root-mean-square difference over all channel values
  double mae = 0;        // mean absolute difference
  double mean_a = 0;     // mean channel value of a
  double mean_b = 0;     // ... and of b
  double bias = 0;       // mean_a - mean_b
  double rel_rmse = 0;   // rmse / mean_b
  double rel_mae = 0;    // mae / mean_b
  double rel_bias = 0;   // bias / mean_b
  int width = 0, height = 0;  // of the compared (block-averaged) images
  long pixels = 0;            // (block) pixels counted: all, or those the mask selects
  std::string to_json() const;
};

// a and b must have the same size (std::invalid_argument otherwise). With
// block > 1, both are first averaged over block x block pixel blocks (partial
// blocks at the right and bottom edges are dropped): a comparison of
// structure at a coarser scale, less sensitive to per-pixel noise. With a
// mask (same size; `knitshade render --mask-object`), only the (block)
// pixels whose mask value, averaged over the block in its first channel, is
// at least 0.5 count: the error over one object, without the noise of the
// rest of the image. A mask that selects nothing is an error.
ImageStats compare_images(const RgbImage& a, const RgbImage& b, int block = 1, const RgbImage* mask = nullptr);

// a averaged over block x block pixel blocks.
RgbImage block_average(const RgbImage& a, int block);

}  // namespace knit::render
