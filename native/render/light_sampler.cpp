#include "render/light.h"

#include <cmath>

namespace knit::render {

LightSampler::LightSampler(const std::vector<const Light*>& lights, float scene_radius) : lights_(lights) {
  if (lights_.empty()) return;
  // Half in proportion to power, half uniformly ("defensive" mixture): power
  // alone starves small lights next to an environment or a directional light
  // whose power grows with the scene's bounding sphere (a large ground plane),
  // which shows as fireflies; the uniform half bounds that to a factor 2N.
  const size_t n = lights_.size();
  std::vector<double> power(n);
  double total = 0;
  for (size_t i = 0; i < n; ++i) {
    const double p = lights_[i]->power(scene_radius);
    power[i] = std::isfinite(p) && p > 0 ? p : 0.0;
    total += power[i];
  }
  std::vector<float> weight(n);
  for (size_t i = 0; i < n; ++i) {
    // A light with no power is never picked; an all-dark scene picks uniformly.
    const double share = total > 0 ? power[i] / total : 1.0 / static_cast<double>(n);
    weight[i] = power[i] > 0 || total == 0 ? static_cast<float>(0.5 * share + 0.5 / static_cast<double>(n)) : 0.0f;
  }
  dist_ = Distribution1D(weight);
}

const Light* LightSampler::pick(float u, float& prob, size_t& index) const {
  if (lights_.empty()) return nullptr;
  index = dist_.sample_discrete(u, prob);
  return prob > 0 ? lights_[index] : nullptr;
}

float LightSampler::probability(size_t index) const {
  return lights_.empty() ? 0.0f : dist_.discrete_pdf(index);
}

}  // namespace knit::render
