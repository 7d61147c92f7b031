// sampling.h: piecewise-constant distributions (pbrt's PiecewiseConstant1D/2D), each
// sampling routine next to its PDF. Used for environment importance sampling.
#pragma once

#include "renderer/math.h"

#include <cstdint>
#include <span>
#include <vector>

namespace glaze {

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
  float sample(float u, float* pdf, int* bin) const;
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
};

// A piecewise-constant density on [0, 1)^2 over a width x height grid of weights (row
// major, row 0 at y = 0): a marginal over rows, then a conditional within the row.
class Distribution2D {
 public:
  Distribution2D(std::span<const float> weights, int width, int height);

  // Maps u in [0, 1)^2 to (x, y) in [0, 1)^2 with density pdf(x, y) (w.r.t. area).
  Vec2 sample(const Vec2& u, float* pdf) const;
  float pdf(const Vec2& p) const;
  void prefetch(const Vec2& p) const { rows_[row_of(p.y())].prefetch(p.x()); }

  // The two halves of sample(), for callers that interleave many samples: choose the
  // row, prefetch_in_row() so the row's table loads while other samples choose theirs,
  // then sample within the row. sample() is exactly these three steps.
  float sample_row(float u, float* pdf, int* row) const { return marginal_.sample(u, pdf, row); }
  void prefetch_in_row(int row, float u) const { rows_[row].prefetch(u); }
  float sample_in_row(int row, float u, float* pdf) const { return rows_[row].sample(u, pdf, nullptr); }

 private:
  int row_of(float y) const { return std::clamp(static_cast<int>(y * height_), 0, height_ - 1); }

  int width_, height_;
  std::vector<Distribution1D> rows_;
  Distribution1D marginal_;
};

}  // namespace glaze
