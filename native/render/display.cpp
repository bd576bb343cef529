#include "render/display.h"

#include <OpenColorIO/OpenColorIO.h>

#include <cstdlib>
#include <stdexcept>

namespace knit::render {

namespace OCIO = OCIO_NAMESPACE;

struct DisplayTransform::Impl {
  OCIO::ConstCPUProcessorRcPtr cpu;
};

static OCIO::ConstConfigRcPtr builtin_config() {
  OCIO::ConfigRcPtr config = OCIO::Config::CreateRaw()->createEditableCopy();
  OCIO::ColorSpaceRcPtr linear = OCIO::ColorSpace::Create();
  linear->setName("Linear Rec.709");
  linear->setFamily("linear");
  linear->setDescription("scene-linear Rec.709 primaries, D65 (the renderer's working space)");
  config->addColorSpace(linear);

  // sRGB encoding: ExponentWithLinearTransform (gamma 2.4, offset 0.055) in
  // its forward direction decodes (display -> linear), so the colour space
  // is defined by its to-reference transform.
  OCIO::ExponentWithLinearTransformRcPtr curve = OCIO::ExponentWithLinearTransform::Create();
  const double gamma[4] = {2.4, 2.4, 2.4, 1.0};
  const double offset[4] = {0.055, 0.055, 0.055, 0.0};
  curve->setGamma(gamma);
  curve->setOffset(offset);
  OCIO::ColorSpaceRcPtr srgb = OCIO::ColorSpace::Create();
  srgb->setName("sRGB");
  srgb->setFamily("display");
  srgb->setDescription("sRGB transfer function on Rec.709 primaries");
  srgb->setTransform(curve, OCIO::COLORSPACE_DIR_TO_REFERENCE);
  config->addColorSpace(srgb);

  config->setRole(OCIO::ROLE_SCENE_LINEAR, "Linear Rec.709");
  config->setRole(OCIO::ROLE_DEFAULT, "Linear Rec.709");
  config->addDisplayView("sRGB", "Standard", "sRGB", "");
  config->setActiveDisplays("sRGB");
  config->setActiveViews("Standard");
  config->validate();
  return config;
}

static std::string list_displays(const OCIO::ConstConfigRcPtr& c) {
  std::string s;
  for (int i = 0; i < c->getNumDisplays(); ++i) s += (s.empty() ? "" : ", ") + std::string(c->getDisplay(i));
  return s;
}

static std::string list_views(const OCIO::ConstConfigRcPtr& c, const std::string& display) {
  std::string s;
  for (int i = 0; i < c->getNumViews(display.c_str()); ++i)
    s += (s.empty() ? "" : ", ") + std::string(c->getView(display.c_str(), i));
  return s;
}

DisplayTransform::DisplayTransform(const DisplaySettings& settings) : impl_(std::make_unique<Impl>()) {
  const char* env = settings.use_env ? std::getenv("OCIO") : nullptr;
  const bool from_env = env && *env;
  const std::string config_name = from_env ? std::string("$OCIO=") + env : "built-in sRGB config";
  try {
    OCIO::ConstConfigRcPtr config = from_env ? OCIO::Config::CreateFromEnv() : builtin_config();
    std::string display = settings.display, view = settings.view;
    // --view "display/view" names both.
    const size_t slash = view.find('/');
    if (slash != std::string::npos) {
      display = view.substr(0, slash);
      view = view.substr(slash + 1);
    }
    if (display.empty()) display = config->getDefaultDisplay();
    bool display_ok = false;
    for (int i = 0; i < config->getNumDisplays(); ++i)
      if (display == config->getDisplay(i)) display_ok = true;
    if (!display_ok)
      throw std::runtime_error("unknown display '" + display + "' (available: " + list_displays(config) + ")");
    if (view.empty()) view = config->getDefaultView(display.c_str());
    bool view_ok = false;
    for (int i = 0; i < config->getNumViews(display.c_str()); ++i)
      if (view == config->getView(display.c_str(), i)) view_ok = true;
    if (!view_ok)
      throw std::runtime_error("unknown view '" + view + "' for display '" + display +
                               "' (available: " + list_views(config, display) + ")");
    if (!config->getColorSpace(OCIO::ROLE_SCENE_LINEAR))
      throw std::runtime_error("the config has no scene_linear role");
    OCIO::ConstProcessorRcPtr proc =
        config->getProcessor(OCIO::ROLE_SCENE_LINEAR, display.c_str(), view.c_str(), OCIO::TRANSFORM_DIR_FORWARD);
    impl_->cpu = proc->getDefaultCPUProcessor();
    description_ = config_name + ": " + display + " / " + view;
  } catch (const OCIO::Exception& e) {
    throw std::runtime_error(config_name + ": " + e.what());
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(config_name + ": " + e.what());
  }
}

DisplayTransform::~DisplayTransform() = default;
DisplayTransform::DisplayTransform(DisplayTransform&&) noexcept = default;

void DisplayTransform::apply(std::vector<float>& rgb) const {
  if (rgb.empty()) return;
  OCIO::PackedImageDesc desc(rgb.data(), static_cast<long>(rgb.size() / 3), 1, 3);
  impl_->cpu->apply(desc);
}

}  // namespace knit::render
