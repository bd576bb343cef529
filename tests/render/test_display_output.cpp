// Output: the OpenColorIO display transform (built-in sRGB and $OCIO), PNG
// and EXR writing, exposure, and refusal of unknown formats.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdlib>

#include "render/display.h"
#include "render/output.h"
#include "render_test_util.h"

namespace knit::render {
namespace {

double srgb_encode(double x) { return x <= 0.0031308 ? 12.92 * x : 1.055 * std::pow(x, 1 / 2.4) - 0.055; }

DisplaySettings builtin() {
  DisplaySettings s;
  s.use_env = false;
  return s;
}

TEST(Display, BuiltinConfigIsTheSrgbTransferFunction) {
  const DisplayTransform t(builtin());
  EXPECT_NE(t.description().find("built-in sRGB config: sRGB / Standard"), std::string::npos) << t.description();
  std::vector<float> v = {0.0f, 0.001f, 0.0031308f, 0.18f, 0.5f, 0.75f, 1.0f, 0.02f, 0.3f};
  const std::vector<float> in = v;
  t.apply(v);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_NEAR(v[i], srgb_encode(in[i]), 2e-4) << "linear " << in[i];
}

TEST(Display, BuiltinConfigViewNames) {
  DisplaySettings s = builtin();
  s.view = "sRGB/Standard";
  EXPECT_NO_THROW(DisplayTransform{s});
  s.view = "Filmic";
  try {
    DisplayTransform t(s);
    ADD_FAILURE() << "unknown view accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("unknown view 'Filmic' for display 'sRGB' (available: Standard)"),
              std::string::npos)
        << e.what();
  }
  s.view = "";
  s.display = "P3";
  EXPECT_THROW(DisplayTransform{s}, std::runtime_error);
}

// A config from $OCIO: the view is looked up in it.
TEST(Display, ConfigFromOcioEnvironmentVariable) {
  const std::string dir = test::test_dir();
  const std::string cfg = test::write_file(dir, "config.ocio", R"(ocio_profile_version: 2
roles:
  scene_linear: lin
  default: lin
file_rules:
  - !<Rule> {name: Default, colorspace: lin}
displays:
  testdisp:
    - !<View> {name: raw, colorspace: lin}
    - !<View> {name: square-root, colorspace: sqrt}
active_displays: []
active_views: []
colorspaces:
  - !<ColorSpace>
    name: lin
    isdata: false
  - !<ColorSpace>
    name: sqrt
    isdata: false
    from_scene_reference: !<ExponentTransform> {value: [2, 2, 2, 1], direction: inverse}
)");
  const char* old = std::getenv("OCIO");
  const std::string saved = old ? old : "";
  setenv("OCIO", cfg.c_str(), 1);
  DisplaySettings s;
  s.view = "square-root";
  std::vector<float> v = {0.25f, 0.04f, 1.0f};
  try {
    const DisplayTransform t(s);
    EXPECT_NE(t.description().find("testdisp / square-root"), std::string::npos) << t.description();
    t.apply(v);
    EXPECT_NEAR(v[0], 0.5f, 1e-5f);
    EXPECT_NEAR(v[1], 0.2f, 1e-5f);
    s.view = "Standard";
    EXPECT_THROW(DisplayTransform{s}, std::runtime_error);
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  if (old) setenv("OCIO", saved.c_str(), 1); else unsetenv("OCIO");
}

TEST(Output, PngIsDisplayEncodedAndExrIsLinear) {
  const std::string dir = test::test_dir();
  RgbImage img(4, 2);
  const float values[4] = {0.0f, 0.18f, 0.5f, 4.0f};
  for (int x = 0; x < 4; ++x) {
    img.at(x, 0) = Rgb(values[x]);
    img.at(x, 1) = Rgb(values[x], 0.0f, 1.0f);
  }
  write_output(dir + "/a.png", img, 0.0f, builtin());
  write_output(dir + "/a.exr", img, 1.0f, builtin());  // +1 stop

  auto png = OIIO::ImageInput::open(dir + "/a.png");
  ASSERT_TRUE(png);
  EXPECT_EQ(png->spec().format, OIIO::TypeDesc::UINT8);
  std::vector<unsigned char> bytes(4 * 2 * 3);
  ASSERT_TRUE(png->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, bytes.data()));
  for (int x = 0; x < 4; ++x) {
    const int expected = static_cast<int>(std::lround(255 * std::min(1.0, srgb_encode(values[x]))));
    EXPECT_NEAR(bytes[x * 3], expected, 1) << "pixel " << x;
  }
  EXPECT_EQ(bytes[(4 + 3) * 3 + 1], 0);
  EXPECT_EQ(bytes[(4 + 3) * 3 + 2], 255);

  const RgbImage exr = read_rgb_image(dir + "/a.exr");
  ASSERT_EQ(exr.width, 4);
  for (int x = 0; x < 4; ++x) EXPECT_FLOAT_EQ(exr.at(x, 0).r, 2.0f * values[x]);  // 4.0 stays unclamped: 8.0
}

TEST(Output, UnknownExtensionIsRefused) {
  EXPECT_THROW(output_format_for("image.jpg"), std::runtime_error);
  EXPECT_THROW(output_format_for("image"), std::runtime_error);
  EXPECT_EQ(output_format_for("IMAGE.EXR"), OutputFormat::Exr);
  EXPECT_EQ(output_format_for("a.b.png"), OutputFormat::Png);
}

}  // namespace
}  // namespace knit::render
