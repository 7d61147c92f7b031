#include "renderer/sampling.h"

#include <algorithm>
#include <stdexcept>

namespace glaze {

Distribution1D::Distribution1D(std::span<const float> weights)
    : func_(weights.begin(), weights.end()), cdf_(weights.size() + 1) {
  if (func_.empty()) throw std::invalid_argument("Distribution1D: no weights");
  const int n = size();
  // Accumulate in double so that long rows of tiny weights keep their relative order.
  std::vector<double> running(n + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    const double w = func_[i] > 0.0f ? func_[i] : 0.0;  // also maps NaN to 0
    func_[i] = static_cast<float>(w);
    running[i + 1] = running[i] + w;
  }
  integral_ = running[n] / n;
  if (running[n] <= 0.0) {
    std::fill(func_.begin(), func_.end(), 1.0f);
    for (int i = 0; i <= n; ++i) running[i] = i;
    integral_ = 1.0;
  }
  for (int i = 0; i <= n; ++i) cdf_[i] = static_cast<float>(running[i] / running[n]);
  cdf_[n] = 1.0f;
}

float Distribution1D::sample(float u, float* pdf, int* bin) const {
  const int n = size();
  // First cdf entry > u; its predecessor opens a bin of non-zero width containing u.
  const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), u);
  int i = static_cast<int>(it - cdf_.begin()) - 1;
  i = std::clamp(i, 0, n - 1);
  while (i > 0 && func_[i] == 0.0f) --i;  // only reachable for u rounding onto cdf_[n]
  const float width = cdf_[i + 1] - cdf_[i];
  float du = width > 0.0f ? (u - cdf_[i]) / width : 0.5f;
  du = std::clamp(du, 0.0f, 1.0f);
  if (pdf) *pdf = static_cast<float>(func_[i] / integral_);
  if (bin) *bin = i;
  return std::min((i + du) / n, 0x1.fffffep-1f);
}

float Distribution1D::pdf(float x) const {
  const int i = std::clamp(static_cast<int>(x * size()), 0, size() - 1);
  return static_cast<float>(func_[i] / integral_);
}

Distribution2D::Distribution2D(std::span<const float> weights, int width, int height)
    : width_(width), height_(height), marginal_([&] {
        if (width <= 0 || height <= 0 || weights.size() != size_t(width) * size_t(height))
          throw std::invalid_argument("Distribution2D: weights do not match width x height");
        std::vector<float> row_integrals(height);
        for (int y = 0; y < height; ++y) {
          double sum = 0.0;
          for (int x = 0; x < width; ++x) sum += std::max(weights[size_t(y) * width + x], 0.0f);
          row_integrals[y] = static_cast<float>(sum / width);
        }
        return Distribution1D(row_integrals);
      }()) {
  rows_.reserve(height);
  for (int y = 0; y < height; ++y) rows_.emplace_back(weights.subspan(size_t(y) * width, width));
}

Vec2 Distribution2D::sample(const Vec2& u, float* pdf) const {
  float pdf_row = 0.0f, pdf_column = 0.0f;
  int row = 0;
  const float y = marginal_.sample(u.y(), &pdf_row, &row);
  const float x = rows_[row].sample(u.x(), &pdf_column, nullptr);
  if (pdf) *pdf = pdf_row * pdf_column;
  return {x, y};
}

float Distribution2D::pdf(const Vec2& p) const {
  const int row = std::clamp(static_cast<int>(p.y() * height_), 0, height_ - 1);
  return marginal_.pdf(p.y()) * rows_[row].pdf(p.x());
}

}  // namespace glaze
