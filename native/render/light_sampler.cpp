#include "render/light.h"

#include <cmath>

namespace knit::render {

LightSampler::LightSampler(const std::vector<const Light*>& lights, float scene_radius) : lights_(lights) {
  if (lights_.empty()) return;
  std::vector<float> power(lights_.size());
  for (size_t i = 0; i < lights_.size(); ++i) {
    const float p = lights_[i]->power(scene_radius);
    power[i] = std::isfinite(p) && p > 0 ? p : 0.0f;
  }
  // An all-dark scene picks uniformly (Distribution1D's fallback).
  dist_ = Distribution1D(power);
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
