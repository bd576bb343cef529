// Piecewise-constant 1D and 2D distributions (inversion of a tabulated CDF),
// used to importance-sample environment maps and to pick lights.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "render/vec.h"

namespace knit::render {

// A density over [0, 1) proportional to a non-negative step function with
// n equal steps. An all-zero (or empty-integral) function samples uniformly so
// the distribution is always usable; `integral()` then reports 0.
class Distribution1D {
 public:
  Distribution1D() = default;
  explicit Distribution1D(const std::vector<float>& f);

  size_t size() const { return func_.size(); }
  double integral() const { return integral_; }  // of f over [0, 1)

  // Continuous sample in [0, 1); `pdf` is the density there and `index` the step.
  float sample(float u, float& pdf, size_t& index) const;
  // Discrete sample: index with probability `discrete_pdf(index)`.
  size_t sample_discrete(float u, float& prob) const;
  float discrete_pdf(size_t index) const;
  // Density of the continuous distribution at step `index`.
  float pdf(size_t index) const;

 private:
  std::vector<float> func_;
  std::vector<double> cdf_;  // size n + 1, cdf_[0] = 0, cdf_[n] = 1
  // guide_[b]: the step where u = b / n falls. A sample starts from its
  // bucket's and steps on (about one step for smooth functions), where a
  // binary search over the CDF took a dozen unpredictable branches.
  std::vector<uint32_t> guide_;
  double integral_ = 0;
  bool uniform_ = false;
  // Largest i in [0, n - 1] with cdf_[i] <= u.
  size_t find(double u) const;
};

// A density over [0, 1)^2 proportional to a non-negative nu x nv table
// (row-major, v rows of u columns): marginal in v, conditional in u.
class Distribution2D {
 public:
  Distribution2D() = default;
  Distribution2D(const std::vector<float>& f, size_t nu, size_t nv);

  double integral() const { return marginal_.integral(); }
  Vec2 sample(Vec2 u, float& pdf) const;
  float pdf(Vec2 p) const;

 private:
  size_t nu_ = 0, nv_ = 0;
  std::vector<Distribution1D> conditional_;
  Distribution1D marginal_;
};

}  // namespace knit::render
