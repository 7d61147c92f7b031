#include "renderer/sampling.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace glaze {

Distribution1D::Distribution1D(std::span<const float> weights) {
  const int n = static_cast<int>(weights.size());
  if (n == 0) throw std::invalid_argument("Distribution1D: no weights");
  // Accumulate in double so that long rows of tiny weights keep their relative order.
  std::vector<double> func(n), running(n + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    func[i] = weights[i] > 0.0f ? weights[i] : 0.0;  // also maps NaN to 0
    running[i + 1] = running[i] + func[i];
  }
  if (running[n] <= 0.0) {  // nothing to prefer: uniform
    std::fill(func.begin(), func.end(), 1.0);
    for (int i = 0; i <= n; ++i) running[i] = i;
  }
  integral_ = running[n] / n;
  bins_.resize(n + 1);
  for (int i = 0; i <= n; ++i) bins_[i].cdf = static_cast<float>(running[i] / running[n]);
  bins_[n] = {1.0f, 0.0f, 0.0f, n - 1};
  for (int i = 0; i < n; ++i) {
    bins_[i].pdf = static_cast<float>(func[i] / integral_);
    const float width = bins_[i + 1].cdf - bins_[i].cdf;
    const float inverse_width = width > 0.0f ? 1.0f / width : 0.0f;
    bins_[i].inverse_width = std::isfinite(inverse_width) ? inverse_width : 0.0f;  // subnormal widths
  }
  inverse_size_ = 1.0f / n;
  int bin = 0;
  for (int k = 0; k < n; ++k) {
    const float start = static_cast<float>(k) / n;
    while (bin < n - 1 && bins_[bin + 1].cdf <= start) ++bin;
    bins_[k].guide = bin;
  }
}

float Distribution1D::sample_from(float u, int start, float* pdf, int* bin) const {
  const int n = size();
  // The bin i with cdf_i <= u < cdf_i+1 (so of non-zero width): start from the guide
  // entry, at or before it, and walk forward.
  int i = start;
  while (i < n - 1 && bins_[i + 1].cdf <= u) ++i;
  while (i > 0 && bins_[i].cdf > u) --i;        // u * n may round up onto the next guide entry
  while (i > 0 && bins_[i].pdf == 0.0f) --i;    // only reachable for u rounding onto 1
  const Bin& chosen = bins_[i];
  const float du = std::clamp((u - chosen.cdf) * chosen.inverse_width, 0.0f, 1.0f);
  if (pdf) *pdf = chosen.pdf;
  if (bin) *bin = i;
  // (i + du) / n can round into the next bin when du is near 1; keep x inside bin i so
  // that pdf(x) reports the density the sample was drawn with.
  float x = std::min((i + du) * inverse_size_, 0x1.fffffep-1f);
  while (x > 0.0f && static_cast<int>(x * n) > i) x = std::nextafter(x, 0.0f);
  while (static_cast<int>(x * n) < i) x = std::nextafter(x, 1.0f);
  return x;
}

float Distribution1D::pdf(float x) const { return bins_[bin_of(x)].pdf; }

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
  density_.resize(size_t(width) * height);
  for (int y = 0; y < height; ++y) {
    const float row_density = marginal_.pdf((y + 0.5f) / height);
    for (int x = 0; x < width; ++x) density_[size_t(y) * width + x] = row_density * rows_[y].pdf((x + 0.5f) / width);
  }
}

Vec2 Distribution2D::sample(const Vec2& u, float* pdf) const {
  float pdf_row = 0.0f, pdf_column = 0.0f;
  int row = 0;
  const float y = sample_row(u.y(), &pdf_row, &row);
  const float x = rows_[row].sample(u.x(), &pdf_column, nullptr);
  if (pdf) *pdf = pdf_row * pdf_column;
  return {x, y};
}

float Distribution2D::pdf(const Vec2& p) const { return density_[cell_of(p)]; }

}  // namespace glaze
