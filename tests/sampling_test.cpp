// Tests of the quadrature rules and the piecewise-constant distributions.
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
