// sampling.h: piecewise-constant distributions (pbrt's PiecewiseConstant1D/2D), each
// sampling routine next to its PDF. Used for environment importance sampling.
#pragma once

#include "renderer/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace glaze {

// Multiple importance sampling's power heuristic (Veach 1997, beta = 2): the weight of
// a sample drawn by strategy a that strategy b could also have drawn.
inline float power_heuristic(float pdf_a, float pdf_b) {
  const float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
  return a + b > 0.0f ? a / (a + b) : 0.0f;
}

// A piecewise-constant density on [0, 1) with n equal bins proportional to `weights`
// (non-negative; if all are zero the density is uniform). Sampling inverts the CDF
// exactly (monotone, so stratified inputs stay stratified) in expected O(1) time with a
// guide table (Chen and Asau's cutpoint method) instead of a binary search, whose
// mispredicted branches and scattered loads dominated the cost.
class Distribution1D {
 public:
  explicit Distribution1D(std::span<const float> weights);

  int size() const { return static_cast<int>(bins_.size()) - 1; }
  // Mean of the weights (the integral of the unnormalised function over [0, 1)).
  double integral() const { return integral_; }

  // Maps u in [0, 1) to x in [0, 1) with density pdf(x); never picks a zero-weight bin.
  float sample(float u, float* pdf, int* bin) const { return sample_from(u, search_start(u), pdf, bin); }

  // sample() in steps, for callers that interleave many samples so that their cache
  // misses overlap: the guide entry of u (prefetch_guide) names the bin where the search
  // starts (search_start), whose entries (prefetch_bin) the search then reads.
  void prefetch_guide(float u) const { __builtin_prefetch(&bins_[guide_index(u)]); }
  int search_start(float u) const { return bins_[guide_index(u)].guide; }
  void prefetch_bin(int i) const {
    __builtin_prefetch(&bins_[i]);
    __builtin_prefetch(&bins_[i + 1]);
  }
  float sample_from(float u, int start, float* pdf, int* bin) const;
  float pdf(float x) const;
  // Starts loading what pdf(x) reads.
  void prefetch(float x) const { __builtin_prefetch(&bins_[bin_of(x)]); }

 private:
  // Per bin: the CDF at its start, its normalised density and the guide entry of the
  // same index, side by side: the search starts at bins_[floor(u n)].guide, usually in
  // the same cache line, so a sample costs about one cache miss. n + 1 entries, the
  // last with cdf 1.
  struct Bin {
    float cdf;
    float pdf;
    float inverse_width;  // 1 / (cdf of the next bin - cdf), 0 for an empty bin
    int32_t guide;        // first bin whose cdf interval reaches (this index) / n
  };
  std::vector<Bin> bins_;
  double integral_ = 0.0;
  float inverse_size_ = 1.0f;

  int bin_of(float x) const { return std::clamp(static_cast<int>(x * size()), 0, size() - 1); }
  int guide_index(float u) const { return bin_of(u); }
};

// A piecewise-constant density on [0, 1)^2 over a width x height grid of weights (row
// major, row 0 at y = 0): a marginal over rows, then a conditional within the row.
class Distribution2D {
 public:
  Distribution2D(std::span<const float> weights, int width, int height);

  // Maps u in [0, 1)^2 to (x, y) in [0, 1)^2 with density pdf(x, y) (w.r.t. area).
  Vec2 sample(const Vec2& u, float* pdf) const;
  float pdf(const Vec2& p) const;
  void prefetch(const Vec2& p) const { __builtin_prefetch(&density_[cell_of(p)]); }

  // sample() in steps, for callers that interleave many samples: choose the row, then
  // the row's guide entry and the bins it points to load while other samples take the
  // same steps, then sample within the row (see Distribution1D).
  float sample_row(float u, float* pdf, int* row) const { return marginal_.sample(u, pdf, row); }
  const Distribution1D& row(int row) const { return rows_[row]; }

 private:
  int row_of(float y) const { return std::clamp(static_cast<int>(y * height_), 0, height_ - 1); }
  size_t cell_of(const Vec2& p) const {
    return size_t(row_of(p.y())) * width_ + std::clamp(static_cast<int>(p.x() * width_), 0, width_ - 1);
  }

  int width_, height_;
  std::vector<Distribution1D> rows_;
  Distribution1D marginal_;
  // pdf() of each cell, row-major: one load where the product of the marginal's and the
  // row's densities would be two, one behind a pointer.
  std::vector<float> density_;
};

}  // namespace glaze
