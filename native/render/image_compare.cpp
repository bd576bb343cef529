#include "render/image_compare.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace knit::render {

RgbImage block_average(const RgbImage& a, int block) {
  if (block <= 1) return a;
  RgbImage out(a.width / block, a.height / block);
  const float inv = 1.0f / float(block * block);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      double r = 0, g = 0, b = 0;
      for (int j = 0; j < block; ++j)
        for (int i = 0; i < block; ++i) {
          const Rgb& p = a.at(x * block + i, y * block + j);
          r += p.r;
          g += p.g;
          b += p.b;
        }
      out.at(x, y) = Rgb(float(r), float(g), float(b)) * inv;
    }
  return out;
}

namespace {
std::string size_text(const RgbImage& i) { return std::to_string(i.width) + "x" + std::to_string(i.height); }
}  // namespace

ImageStats compare_images(const RgbImage& a0, const RgbImage& b0, int block, const RgbImage* mask0) {
  if (a0.width != b0.width || a0.height != b0.height)
    throw std::invalid_argument("compare_images: sizes differ (" + size_text(a0) + " vs " + size_text(b0) + ")");
  if (mask0 && (mask0->width != a0.width || mask0->height != a0.height))
    throw std::invalid_argument("compare_images: the mask is " + size_text(*mask0) + ", the images " + size_text(a0));
  const RgbImage a = block_average(a0, block), b = block_average(b0, block);
  RgbImage mask;
  if (mask0) mask = block_average(*mask0, block);
  ImageStats s;
  s.width = a.width;
  s.height = a.height;
  double se = 0, ae = 0, sa = 0, sb = 0;
  long counted = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    if (mask0 && !(mask.pixels[i].r >= 0.5f)) continue;
    ++counted;
    const float pa[3] = {a.pixels[i].r, a.pixels[i].g, a.pixels[i].b};
    const float pb[3] = {b.pixels[i].r, b.pixels[i].g, b.pixels[i].b};
    for (int c = 0; c < 3; ++c) {
      const double d = double(pa[c]) - double(pb[c]);
      se += d * d;
      ae += std::fabs(d);
      sa += pa[c];
      sb += pb[c];
    }
  }
  s.pixels = counted;
  if (mask0 && counted == 0) throw std::invalid_argument("compare_images: the mask selects no pixel (none >= 0.5)");
  const double n = 3.0 * double(counted);
  if (n == 0) return s;
  s.rmse = std::sqrt(se / n);
  s.mae = ae / n;
  s.mean_a = sa / n;
  s.mean_b = sb / n;
  s.bias = s.mean_a - s.mean_b;
  if (s.mean_b > 0) {
    s.rel_rmse = s.rmse / s.mean_b;
    s.rel_mae = s.mae / s.mean_b;
    s.rel_bias = s.bias / s.mean_b;
  }
  return s;
}

std::string ImageStats::to_json() const {
  nlohmann::ordered_json j;
  j["width"] = width;
  j["height"] = height;
  j["pixels"] = pixels;
  j["rmse"] = rmse;
  j["mae"] = mae;
  j["mean_a"] = mean_a;
  j["mean_b"] = mean_b;
  j["bias"] = bias;
  j["rel_rmse"] = rel_rmse;
  j["rel_mae"] = rel_mae;
  j["rel_bias"] = rel_bias;
  return j.dump(2) + "\n";
}

}  // namespace knit::render
