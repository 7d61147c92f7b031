// Tests of the quadrature rules, the alias table and the low-discrepancy points.
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

// Draws from an alias table with the generator the environment sampler uses.
int draw(const AliasTable& table, Pcg32& rng, float* pmf) {
  const uint64_t bits = uint64_t(rng.next_uint()) << 32 | rng.next_uint();
  return table.sample(table.slot(bits), rng.next_float(), pmf);
}

TEST(AliasTable, SamplesFollowWeightsAndSkipEmptyOutcomes) {
  const std::vector<float> weights = {0.0f, 1.0f, 3.0f, 0.0f, 4.0f, 0.0f};
  const AliasTable table(weights);
  std::vector<double> observed(6, 0.0), expected(6, 0.0);
  Pcg32 rng(1);
  const int n = 80000;
  for (int k = 0; k < n; ++k) {
    float pmf = 0;
    const int i = draw(table, rng, &pmf);
    ASSERT_GT(weights[i], 0.0f);
    ASSERT_EQ(pmf, table.pmf(i));
    observed[i] += 1;
  }
  for (int i = 0; i < 6; ++i) {
    expected[i] = n * weights[i] / 8.0;
    EXPECT_FLOAT_EQ(table.pmf(i), weights[i] / 8.0f);
  }
  EXPECT_GT(testing::chi_square_p_value(observed, expected), 1e-3);
  // The extreme coins and entries reach no empty outcome.
  for (int slot = 0; slot < 6; ++slot)
    for (float coin : {0.0f, 0x1.fffffep-1f}) EXPECT_GT(weights[table.sample(slot, coin, nullptr)], 0.0f);
  EXPECT_EQ(table.slot(0), 0);
  EXPECT_EQ(table.slot(~uint64_t(0)), 5);
}

TEST(AliasTable, AllZeroWeightsBecomeUniform) {
  const std::vector<float> zeros(4, 0.0f);
  const AliasTable table(zeros);
  for (int i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(table.pmf(i), 0.25f);
    EXPECT_NEAR(table.selection_probability(i), 0.25, 1e-12);
  }
}

TEST(AliasTable, TableSelectsEachOutcomeWithItsPmfEvenForExtremeWeights) {
  // Weights spanning 1e-38..1e3 with zeros between: the probability the table gives
  // each outcome, summed over its entries, is the pmf it reports (to float rounding of
  // the thresholds), the pmfs sum to 1, and no zero weight is ever selectable.
  Pcg32 rng(11);
  for (int n : {1, 7, 361, 1450, 4096}) {
    std::vector<float> weights(n);
    double total = 0;
    for (int i = 0; i < n; ++i) {
      const uint32_t kind = rng.next_uint() % 4;
      weights[i] = kind == 0   ? 0.0f
                   : kind == 1 ? 1e-38f * rng.next_float()
                               : std::ldexp(rng.next_float(), int(rng.next_uint() % 10));
      total += weights[i];
    }
    if (total == 0) weights[0] = 1.0f, total = 1.0;
    const AliasTable table(weights);
    double pmf_sum = 0;
    for (int i = 0; i < n; ++i) {
      const double p = table.selection_probability(i);
      pmf_sum += table.pmf(i);
      ASSERT_NEAR(p, weights[i] / total, 1e-6 * weights[i] / total + 1e-12) << "n " << n << " i " << i;
      ASSERT_NEAR(table.pmf(i), weights[i] / total, 1e-6 * weights[i] / total + 1e-30) << "n " << n << " i " << i;
      if (weights[i] == 0.0f) {
        ASSERT_EQ(p, 0.0) << "n " << n << " i " << i;
      }
    }
    EXPECT_NEAR(pmf_sum, 1.0, 1e-5) << "n " << n;
  }
}

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
    for (int t = 0; t < trials; ++t)
      mean += scrambled_sobol_2d(i, rng.next_uint(), rng.next_uint()).cast<double>() / trials;
    EXPECT_NEAR(mean.x(), 0.5, 0.01);
    EXPECT_NEAR(mean.y(), 0.5, 0.01);
  }
}

}  // namespace
}  // namespace glaze
