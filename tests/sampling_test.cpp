// Tests of the quadrature rules and the piecewise-constant distributions.
#include "renderer/low_discrepancy.h"
#include "renderer/quadrature.h"
#include "renderer/rng.h"
#include "renderer/sampling.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

TEST(GaussLegendre, IntegratesPolynomialsExactly) {
  for (int n : {1, 2, 5, 12, 40}) {
    const QuadratureRule rule = gauss_legendre(n, 0.0, 2.0);
    for (int degree = 0; degree <= 2 * n - 1; ++degree) {
      double sum = 0;
      for (int k = 0; k < n; ++k) sum += rule.weights[k] * std::pow(rule.nodes[k], degree);
      const double exact = std::pow(2.0, degree + 1) / (degree + 1);
      EXPECT_NEAR(sum, exact, 1e-12 * exact) << "n " << n << " degree " << degree;
    }
  }
}

TEST(Distribution1D, SamplesFollowWeightsAndSkipEmptyBins) {
  const std::vector<float> weights = {0.0f, 1.0f, 3.0f, 0.0f, 4.0f, 0.0f};
  const Distribution1D distribution(weights);
  EXPECT_NEAR(distribution.integral(), 8.0 / 6.0, 1e-12);
  std::vector<double> observed(6, 0.0), expected(6, 0.0);
  Pcg32 rng(1);
  const int n = 80000;
  for (int k = 0; k < n; ++k) {
    float pdf = 0;
    int bin = -1;
    const float x = distribution.sample(rng.next_float(), &pdf, &bin);
    ASSERT_GE(x, 0.0f);
    ASSERT_LT(x, 1.0f);
    ASSERT_EQ(bin, int(x * 6));
    ASSERT_GT(weights[bin], 0.0f);
    ASSERT_FLOAT_EQ(pdf, distribution.pdf(x));
    observed[bin] += 1;
  }
  for (int i = 0; i < 6; ++i) expected[i] = n * weights[i] / 8.0;
  EXPECT_GT(testing::chi_square_p_value(observed, expected), 1e-3);
  // Edge values of u land in non-empty bins.
  int bin = -1;
  distribution.sample(0.0f, nullptr, &bin);
  EXPECT_EQ(bin, 1);
  distribution.sample(0x1.fffffep-1f, nullptr, &bin);
  EXPECT_EQ(bin, 4);
}

TEST(Distribution1D, AllZeroWeightsBecomeUniform) {
  const std::vector<float> zeros(4, 0.0f);
  const Distribution1D distribution(zeros);
  EXPECT_FLOAT_EQ(distribution.pdf(0.3f), 1.0f);
  float pdf = 0;
  EXPECT_NEAR(distribution.sample(0.6f, &pdf, nullptr), 0.6f, 1e-6f);
}

TEST(Distribution1D, LongRowsWithExtremeWeightsStayConsistent) {
  // Weights spanning 1e-38..1e3 (subnormal CDF widths) over many bins: every sample must
  // be finite, land in a bin of non-zero weight, and pdf(x) must report the density the
  // sample was drawn with, even where (i + du) / n rounds onto the next bin.
  Pcg32 rng(11);
  for (int n : {361, 1450, 4096}) {
    std::vector<float> weights(n);
    for (int i = 0; i < n; ++i) {
      const uint32_t kind = rng.next_uint() % 4;
      weights[i] = kind == 0 ? 0.0f : kind == 1 ? 1e-38f * rng.next_float() : std::ldexp(rng.next_float(), int(rng.next_uint() % 10));
    }
    const Distribution1D distribution(weights);
    for (int k = 0; k < 200000; ++k) {
      const float u = k < 3 ? (k == 0 ? 0.0f : k == 1 ? 0x1.fffffep-1f : 0.5f) : rng.next_float();
      float pdf = 0;
      int bin = -1;
      const float x = distribution.sample(u, &pdf, &bin);
      ASSERT_TRUE(std::isfinite(x) && x >= 0.0f && x < 1.0f) << "n " << n << " u " << u;
      ASSERT_GT(weights[bin], 0.0f);
      ASSERT_EQ(int(x * n), bin) << "n " << n << " u " << u;
      ASSERT_EQ(distribution.pdf(x), pdf);
    }
  }
}

TEST(Distribution2D, PdfIntegratesToOneAndMatchesSamples) {
  const int w = 5, h = 3;
  std::vector<float> weights(w * h);
  for (int i = 0; i < w * h; ++i) weights[i] = float((i * 7) % 5);
  const Distribution2D distribution(weights, w, h);
  double integral = 0;
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) integral += distribution.pdf(Vec2((i + 0.5f) / w, (j + 0.5f) / h)) / (w * h);
  EXPECT_NEAR(integral, 1.0, 1e-6);
  std::vector<double> observed(w * h, 0), expected(w * h, 0);
  double total = 0;
  for (float v : weights) total += v;
  Pcg32 rng(2);
  const int n = 60000;
  for (int k = 0; k < n; ++k) {
    float pdf = 0;
    const Vec2 p = distribution.sample(Vec2(rng.next_float(), rng.next_float()), &pdf);
    ASSERT_FLOAT_EQ(pdf, distribution.pdf(p));
    observed[int(p.y() * h) * w + int(p.x() * w)] += 1;
  }
  for (int i = 0; i < w * h; ++i) expected[i] = n * weights[i] / total;
  EXPECT_GT(testing::chi_square_p_value(observed, expected), 1e-3);
}

}  // namespace
}  // namespace glaze

namespace glaze {
namespace {

TEST(ScrambledSobol, FirstPowerOfTwoPointsFormA02Net) {
  // For N = 2^m points and every split a + b = m, each of the 2^a x 2^b equal rectangles
  // of the unit square holds exactly one point, with or without scrambling.
  Pcg32 rng(5);
  for (int m : {0, 1, 4, 7, 10}) {
    const uint32_t n = 1u << m;
    for (int trial = 0; trial < 3; ++trial) {
      const uint32_t sx = trial == 0 ? 0 : rng.next_uint(), sy = trial == 0 ? 0 : rng.next_uint();
      for (int a = 0; a <= m; ++a) {
        std::vector<int> count(n, 0);
        for (uint32_t i = 0; i < n; ++i) {
          const Vec2 p = scrambled_sobol_2d(i, sx, sy);
          ASSERT_TRUE(p.x() >= 0.0f && p.x() < 1.0f && p.y() >= 0.0f && p.y() < 1.0f);
          const uint32_t cell = (uint32_t(p.x() * (1u << a)) << (m - a)) | uint32_t(p.y() * (1u << (m - a)));
          ++count[cell];
        }
        for (uint32_t c = 0; c < n; ++c) ASSERT_EQ(count[c], 1) << "m " << m << " a " << a << " cell " << c;
      }
    }
  }
}

TEST(ScrambledSobol, RandomScramblesAreUniformOnAverage) {
  // Each point of a randomly scrambled sequence is uniform: the mean of point i over
  // many scrambles approaches (1/2, 1/2).
  Pcg32 rng(6);
  for (uint32_t i : {0u, 1u, 5u, 100u}) {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    const int trials = 20000;
    for (int t = 0; t < trials; ++t) mean += scrambled_sobol_2d(i, rng.next_uint(), rng.next_uint()).cast<double>() / trials;
    EXPECT_NEAR(mean.x(), 0.5, 0.01);
    EXPECT_NEAR(mean.y(), 0.5, 0.01);
  }
}

}  // namespace
}  // namespace glaze
