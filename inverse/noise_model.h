// noise_model.h: how much of each observation is the captures' noise, estimated from the
// captures themselves (docs/design.md §5). Both uses of the observations that weigh them by
// their reliability read it: the views' comparison (cross_view.h) and the lighting map's
// splat (lighting_fit.h).
#pragma once

#include "inverse/samples.h"

#include <cstddef>
#include <cstdint>
#include <vector>

namespace glaze {

// The noise model's floor, relative to a sample's level, and noise-free captures' whole
// model: residuals that small are the pixel grids' interpolation error, not noise.
constexpr double kNoiseFloor = 0.005;

// One view's pixel samples by pixel: which sample, if any, each pixel of its film gave.
class PixelGrid {
 public:
  // `members`: the view's samples (pixel samples: one per pixel).
  PixelGrid(const SampleSet& set, const std::vector<uint32_t>& members);

  // The sample at pixel (i, j) of the film, -1 where none.
  int64_t sample_at(int i, int j) const {
    i -= x0_, j -= y0_;
    if (i < 0 || i >= width_ || j < 0 || j >= height_) return -1;
    return grid_[size_t(j) * width_ + i];
  }

  // The samples at the four pixels beside film point `film`.
  template <typename Visit>
  void for_each_neighbour(const Vec2& film, Visit&& visit) const {
    const int i = int(film.x()), j = int(film.y());
    for (const auto& [di, dj] : {std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1)})
      if (const int64_t k = sample_at(i + di, j + dj); k >= 0) visit(uint32_t(k));
  }

  // The pixels' box that holds the view's samples (empty for a view without any).
  int x0() const { return x0_; }
  int y0() const { return y0_; }
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  int x0_ = 0, y0_ = 0, width_ = 0, height_ = 0;
  std::vector<int64_t> grid_;  // pixel -> sample, -1 where none
};

// The median (the element of rank n / 2, from 0) of v[0 .. n - 1], n > 0, exactly; v is
// followed by kMedianPadding NaNs (which no comparison counts: it is read in whole SIMD
// lanes). `guess`, a value likely near the median (estimate_noise passes the last
// window's: neighbouring windows share most of their pixels), only decides how fast it
// is found.
inline constexpr size_t kMedianPadding = 8;
double median_near(const double* v, size_t n, double guess);

// One grid per frame of the set (pixel samples).
std::vector<PixelGrid> pixel_grids(const SampleSet& samples);

// Per sample and channel, the variance of the noise in `observed` (the samples'
// observations, as captured), estimated from the pixels' residuals around it
// (noise_model.cpp). `noise_free` captures (glaze's deterministic sh integrator), and
// point samples, which have no pixel grid, take the floor: kNoiseFloor of their level.
std::vector<RGB> estimate_noise(const std::vector<RGB>& observed, const SampleSet& samples, bool noise_free);

}  // namespace glaze
