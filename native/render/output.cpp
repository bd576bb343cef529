#include "render/output.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace knit::render {

namespace OIIO = OIIO_NAMESPACE;

OutputFormat output_format_for(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".exr") return OutputFormat::Exr;
  if (ext == ".png") return OutputFormat::Png;
  throw std::runtime_error(path + ": unsupported output format '" + ext + "' (use .exr or .png)");
}

void write_output(const std::string& path, const RgbImage& linear, float exposure, const DisplaySettings& display) {
  const OutputFormat fmt = output_format_for(path);
  const float scale = std::exp2(exposure);
  if (fmt == OutputFormat::Exr) {
    if (scale == 1.0f) {
      write_float_image(path, linear);
    } else {
      RgbImage scaled = linear;
      for (Rgb& p : scaled.pixels) p = p * scale;
      write_float_image(path, scaled);
    }
    return;
  }
  const DisplayTransform transform(display);
  std::vector<float> rgb(linear.pixels.size() * 3);
  for (size_t i = 0; i < linear.pixels.size(); ++i) {
    rgb[3 * i] = linear.pixels[i].r * scale;
    rgb[3 * i + 1] = linear.pixels[i].g * scale;
    rgb[3 * i + 2] = linear.pixels[i].b * scale;
  }
  transform.apply(rgb);
  std::vector<unsigned char> bytes(rgb.size());
  for (size_t i = 0; i < rgb.size(); ++i) {
    const float v = std::isfinite(rgb[i]) ? std::clamp(rgb[i], 0.0f, 1.0f) : 0.0f;
    bytes[i] = static_cast<unsigned char>(std::lround(v * 255.0f));
  }
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(path + ": cannot create image writer: " + OIIO::geterror());
  OIIO::ImageSpec spec(linear.width, linear.height, 3, OIIO::TypeDesc::UINT8);
  if (!out->open(path, spec)) throw std::runtime_error(path + ": cannot open for writing: " + out->geterror());
  if (!out->write_image(OIIO::TypeDesc::UINT8, bytes.data()))
    throw std::runtime_error(path + ": cannot write image: " + out->geterror());
  if (!out->close()) throw std::runtime_error(path + ": cannot close image: " + out->geterror());
}

}  // namespace knit::render
