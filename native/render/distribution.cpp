#include "render/distribution.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace knit::render {

Distribution1D::Distribution1D(const std::vector<float>& f) : func_(f) {
  const size_t n = func_.size();
  if (n == 0) throw std::invalid_argument("Distribution1D: empty function");
  cdf_.assign(n + 1, 0.0);
  for (size_t i = 0; i < n; ++i) {
    const float v = func_[i];
    if (!(v >= 0) || !std::isfinite(v))
      throw std::invalid_argument("Distribution1D: values must be finite and >= 0");
    cdf_[i + 1] = cdf_[i] + static_cast<double>(v) / static_cast<double>(n);
  }
  integral_ = cdf_[n];
  if (!(integral_ > 0)) {
    uniform_ = true;
    for (size_t i = 0; i <= n; ++i) cdf_[i] = static_cast<double>(i) / static_cast<double>(n);
  } else {
    for (size_t i = 1; i <= n; ++i) cdf_[i] /= integral_;
  }
  cdf_[n] = 1.0;
  if (n > 0xffffffffu) throw std::invalid_argument("Distribution1D: more than 2^32 steps");
  guide_.resize(n);
  size_t i = 0;
  for (size_t b = 0; b < n; ++b) {
    const double u = static_cast<double>(b) / static_cast<double>(n);
    while (i + 1 < n && cdf_[i + 1] <= u) ++i;
    guide_[b] = static_cast<uint32_t>(i);
  }
}

size_t Distribution1D::find(double u) const {
  const size_t n = func_.size();
  const double g = u * static_cast<double>(n);
  size_t i = g > 0 ? guide_[std::min(static_cast<size_t>(g), n - 1)] : 0;
  while (i > 0 && cdf_[i] > u) --i;  // (u * n rounded up onto the next bucket)
  while (i + 1 < n && cdf_[i + 1] <= u) ++i;
  return i;
}

float Distribution1D::pdf(size_t index) const {
  if (uniform_) return 1.0f;
  return static_cast<float>(func_[index] / integral_);
}

float Distribution1D::discrete_pdf(size_t index) const {
  return static_cast<float>(cdf_[index + 1] - cdf_[index]);
}

float Distribution1D::sample(float u, float& pdf_out, size_t& index) const {
  // Skip zero-probability steps: the last step whose cdf start is <= u
  // always has positive probability when u < 1.
  index = find(u);
  const double width = cdf_[index + 1] - cdf_[index];
  double du = width > 0 ? (u - cdf_[index]) / width : 0.5;
  du = std::min(std::max(du, 0.0), 1.0);
  pdf_out = pdf(index);
  const double n = static_cast<double>(func_.size());
  const float x = static_cast<float>((static_cast<double>(index) + du) / n);
  return std::min(x, 1.0f - 0x1p-24f);
}

size_t Distribution1D::sample_discrete(float u, float& prob) const {
  const size_t i = find(u);
  prob = discrete_pdf(i);
  return i;
}

Distribution2D::Distribution2D(const std::vector<float>& f, size_t nu, size_t nv) : nu_(nu), nv_(nv) {
  if (nu == 0 || nv == 0 || f.size() != nu * nv)
    throw std::invalid_argument("Distribution2D: table size does not match nu * nv");
  conditional_.reserve(nv);
  std::vector<float> row_integrals(nv);
  for (size_t v = 0; v < nv; ++v) {
    std::vector<float> row(f.begin() + static_cast<std::ptrdiff_t>(v * nu),
                           f.begin() + static_cast<std::ptrdiff_t>((v + 1) * nu));
    conditional_.emplace_back(row);
    row_integrals[v] = static_cast<float>(conditional_.back().integral());
  }
  marginal_ = Distribution1D(row_integrals);
}

Vec2 Distribution2D::sample(Vec2 u, float& pdf_out) const {
  float pdf_v = 0, pdf_u = 0;
  size_t iv = 0, iu = 0;
  const float v = marginal_.sample(u.y, pdf_v, iv);
  const float x = conditional_[iv].sample(u.x, pdf_u, iu);
  pdf_out = pdf_v * pdf_u;
  return {x, v};
}

float Distribution2D::pdf(Vec2 p) const {
  const size_t iu = std::min(static_cast<size_t>(std::max(0.0f, p.x) * static_cast<float>(nu_)), nu_ - 1);
  const size_t iv = std::min(static_cast<size_t>(std::max(0.0f, p.y) * static_cast<float>(nv_)), nv_ - 1);
  return marginal_.pdf(iv) * conditional_[iv].pdf(iu);
}

}  // namespace knit::render
