// Tests of the judgements in inverse/fit_diagnostics.h that the command-line round trips
// do not pin down: the rank correlation and the appearance comparison against values
// worked by hand, and where the warnings start.
#include "inverse/fit_diagnostics.h"
#include "renderer/error.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

TEST(FitDiagnostics, RankCorrelationIsSpearmansRho) {
  using Pairs = std::vector<std::pair<double, double>>;
  EXPECT_DOUBLE_EQ(rank_correlation(Pairs{{1, 2}, {2, 4}, {3, 6}}), 1.0);
  EXPECT_DOUBLE_EQ(rank_correlation(Pairs{{1, 6}, {2, 4}, {3, 2}}), -1.0);
  // Ranks (0 1 2 3 4) against (1 0 3 2 4): sum d^2 = 4, rho = 1 - 6 * 4 / (5 * 24).
  EXPECT_DOUBLE_EQ(rank_correlation(Pairs{{1, 2}, {2, 1}, {3, 4}, {4, 3}, {5, 5}}), 0.8);
  // Tied values share the lowest rank: (0 0 2) against (0 1 2), rho = 1 - 6 / (3 * 8).
  EXPECT_DOUBLE_EQ(rank_correlation(Pairs{{1, 1}, {1, 2}, {2, 3}}), 0.75);
  EXPECT_THROW(rank_correlation(Pairs{{1, 1}}), Error);
}

TEST(FitDiagnostics, AppearanceErrorComparesTheMaskedPixelsOnly) {
  Image truth(2, 1), rendered(2, 1);
  truth.set(0, 0, RGB(1.0f, 2.0f, 4.0f)), rendered.set(0, 0, RGB(1.0f, 1.0f, 5.0f));
  truth.set(1, 0, RGB(9.0f, 9.0f, 9.0f)), rendered.set(1, 0, RGB(0.0f, 0.0f, 0.0f));  // masked out
  const AppearanceError error = appearance_error(rendered, truth, std::vector<uint8_t>{1, 0});
  EXPECT_FLOAT_EQ(error.colour_ratio[0], 1.0f);
  EXPECT_FLOAT_EQ(error.colour_ratio[1], 0.5f);
  EXPECT_FLOAT_EQ(error.colour_ratio[2], 1.25f);
  EXPECT_GT(error.relative_rmse, 0.0);
  EXPECT_EQ(appearance_error(truth, truth, std::vector<uint8_t>{1, 1}).relative_rmse, 0.0);
}

TEST(FitDiagnostics, WarningsStartWhereTheyShould) {
  EXPECT_FALSE(reproduction_warning(0.1).has_value());  // a path tracer's noise is about 5%
  EXPECT_TRUE(reproduction_warning(0.11).has_value());
  MaterialFit fit;
  fit.R0 = 1.0f;
  fit.constraint = {RGBd(2.0, 0.0, 1e-13)};  // green unseen, blue under 1e-12 of the largest
  const MaterialDiagnostics diagnostics = diagnose_material(fit);
  EXPECT_EQ(diagnostics.Rd_constrained, (std::array<bool, 3>{true, false, false}));
  ASSERT_EQ(diagnostics.warnings.size(), 2u);
  EXPECT_NE(diagnostics.warnings[0].find("Rd G is not constrained"), std::string::npos) << diagnostics.warnings[0];
}

}  // namespace
}  // namespace glaze
