// Scene-linear -> display transform for 8-bit output, through OpenColorIO:
// the config named by $OCIO when it is set (its scene_linear role, and the
// display/view asked for or the config's defaults), otherwise a built-in
// config whose only display "sRGB" has the view "Standard": the sRGB transfer
// function (IEC 61966-2-1) on linear Rec.709 primaries. (OCIO 2.1 has no
// Config::CreateFromBuiltinConfig; the built-in config is made in code.)
#pragma once

#include <memory>
#include <string>
#include <vector>

namespace knit::render {

struct DisplaySettings {
  std::string display;  // empty: the config's default display
  std::string view;     // empty: the display's default view
  bool use_env = true;  // honour $OCIO (tests turn it off)
};

class DisplayTransform {
 public:
  // Throws std::runtime_error naming the config and the unknown display/view
  // (listing the available ones).
  explicit DisplayTransform(const DisplaySettings& settings);
  ~DisplayTransform();
  DisplayTransform(DisplayTransform&&) noexcept;

  // In place on packed RGB floats.
  void apply(std::vector<float>& rgb) const;
  // "built-in sRGB config: sRGB / Standard" or "$OCIO=...: display / view".
  const std::string& description() const { return description_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string description_;
};

}  // namespace knit::render
