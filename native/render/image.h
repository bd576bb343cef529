// Float RGB images and their file I/O through OpenImageIO.
#pragma once

#include <string>
#include <vector>

#include "render/vec.h"

namespace knit::render {

static_assert(sizeof(Rgb) == 3 * sizeof(float), "Rgb must be three packed floats");

struct RgbImage {
  int width = 0, height = 0;
  std::vector<Rgb> pixels;  // row-major, row 0 at the top
  RgbImage() = default;
  RgbImage(int w, int h) : width(w), height(h), pixels(static_cast<size_t>(w) * h) {}
  Rgb& at(int x, int y) { return pixels[static_cast<size_t>(y) * width + x]; }
  const Rgb& at(int x, int y) const { return pixels[static_cast<size_t>(y) * width + x]; }
};

// Reads the first three channels (one channel is read as grey) as linear
// float. Throws std::runtime_error "<path>: ..." when the file cannot be read,
// has 2 channels, or holds negative or non-finite values (naming the pixel).
RgbImage read_rgb_image(const std::string& path);

// Writes linear float RGB (EXR, or any float format OIIO knows by extension).
// Throws std::runtime_error on failure.
void write_float_image(const std::string& path, const RgbImage& img);

}  // namespace knit::render
