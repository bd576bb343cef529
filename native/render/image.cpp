#include "render/image.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <stdexcept>

namespace knit::render {

namespace OIIO = OIIO_NAMESPACE;

RgbImage read_rgb_image(const std::string& path) {
  auto in = OIIO::ImageInput::open(path);
  if (!in) throw std::runtime_error(path + ": cannot read image: " + OIIO::geterror());
  const OIIO::ImageSpec& spec = in->spec();
  const int w = spec.width, h = spec.height, nc = spec.nchannels;
  if (w <= 0 || h <= 0) throw std::runtime_error(path + ": image has no pixels");
  if (nc == 2) throw std::runtime_error(path + ": 2-channel images are not supported (need 1, 3 or 4)");
  if (static_cast<int64_t>(w) * h > (int64_t(1) << 28))
    throw std::runtime_error(path + ": image is too large (" + std::to_string(w) + "x" + std::to_string(h) + ")");
  std::vector<float> data(static_cast<size_t>(w) * h * nc);
  if (!in->read_image(0, 0, 0, nc, OIIO::TypeDesc::FLOAT, data.data()))
    throw std::runtime_error(path + ": cannot read image: " + in->geterror());
  in->close();
  RgbImage img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const float* p = &data[(static_cast<size_t>(y) * w + x) * nc];
      const Rgb c = nc == 1 ? Rgb(p[0]) : Rgb(p[0], p[1], p[2]);
      if (!c.is_finite() || c.has_negative())
        throw std::runtime_error(path + ": pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                                 ") is negative or not finite");
      img.at(x, y) = c;
    }
  return img;
}

void write_float_image(const std::string& path, const RgbImage& img) {
  auto out = OIIO::ImageOutput::create(path);
  if (!out) throw std::runtime_error(path + ": cannot create image writer: " + OIIO::geterror());
  OIIO::ImageSpec spec(img.width, img.height, 3, OIIO::TypeDesc::FLOAT);
  spec.attribute("compression", "zip");
  if (!out->open(path, spec)) throw std::runtime_error(path + ": cannot open for writing: " + out->geterror());
  if (!out->write_image(OIIO::TypeDesc::FLOAT, img.pixels.data()))
    throw std::runtime_error(path + ": cannot write image: " + out->geterror());
  if (!out->close()) throw std::runtime_error(path + ": cannot close image: " + out->geterror());
}

}  // namespace knit::render
