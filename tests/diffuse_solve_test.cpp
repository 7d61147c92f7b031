// Tests of the inner closed-form solve for Rd (inverse/diffuse_solve.h) on samples made
// by the renderer's own shading model.
#include "inverse/diffuse_solve.h"
#include "renderer/error.h"
#include "renderer/environment.h"
#include "renderer/procedural_environment.h"
#include "renderer/rng.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

struct Samples {
  std::vector<RGB> observed, specular, basis;
};

// Points on a sphere seen from +Z, shaded in the office by the SH model (docs/design.md §2).
Samples shade_sphere(const PolishedMaterial& material, float noise, uint64_t seed) {
  const Environment office(make_procedural_environment("office", 128, 64), {});
  const ShDiffuseSum diffuse_sum(office.sh(4));
  Samples samples;
  Pcg32 rng(seed);
  const Vec3 v(0, 0, 1);
  for (int k = 0; k < 500; ++k) {
    const Vec3 n = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() + 0.2f).normalized();
    const float mu = n.dot(v);
    const RGB specular = material.fresnel(mu) * office.eval(reflect(v, n));
    RGB basis;
    const RGB E = diffuse_sum(n);
    const RGB L = office.eval(reflect(v, n));
    const ShadingCoefficients<float> per_unit_Rd(material.R0());
    for (int c = 0; c < 3; ++c) basis[c] = per_unit_Rd.diffuse_radiance(ShadingBasis<float>(mu, L[c], E[c]));
    const RGB exact = polished_radiance(material, mu, office.eval(reflect(v, n)), E);
    samples.observed.push_back(exact * (1.0f + noise * (2 * rng.next_float() - 1)));
    samples.specular.push_back(specular);
    samples.basis.push_back(basis);
  }
  return samples;
}

TEST(DiffuseSolve, RecoversRdExactlyFromNoiseFreeSamples) {
  const PolishedMaterial red(0.0452f, RGB(0.9765f, 0.0186f, 0.0f));
  const Samples s = shade_sphere(red, 0.0f, 1);
  const DiffuseSolve solve = solve_diffuse_reflectance(s.observed, s.specular, s.basis);
  EXPECT_LT((solve.Rd - red.Rd()).abs().maxCoeff(), 1e-5f);
  EXPECT_LT(solve.weighted_squared_error.maxCoeff(), 1e-8);
}

TEST(DiffuseSolve, MatchesABruteForceSearchAndClampsToTheBounds) {
  const PolishedMaterial white(0.0385f, RGB(0.6242f, 0.6210f, 0.4083f));
  Samples s = shade_sphere(white, 0.05f, 2);
  for (RGB& o : s.observed) o[2] *= 3.0f;  // push the blue optimum above 1
  std::vector<float> weights(s.observed.size());
  for (size_t k = 0; k < weights.size(); ++k) weights[k] = 0.5f + (k % 3);
  const DiffuseSolve solve = solve_diffuse_reflectance(s.observed, s.specular, s.basis, weights);
  EXPECT_GT(solve.unclamped[2], 1.0f);
  EXPECT_EQ(solve.Rd[2], 1.0f);
  for (int c = 0; c < 2; ++c) {
    double best = 0, best_error = 1e300;
    for (int step = 0; step <= 100000; ++step) {
      const double rd = step / 100000.0;
      double error = 0;
      for (size_t k = 0; k < weights.size(); ++k)
        error += weights[k] * std::pow(s.observed[k][c] - s.specular[k][c] - rd * s.basis[k][c], 2);
      if (error < best_error) best_error = error, best = rd;
    }
    EXPECT_NEAR(solve.Rd[c], best, 2e-5) << "channel " << c;
    EXPECT_NEAR(solve.weighted_squared_error[c], best_error, 1e-6 * best_error + 1e-9);
    EXPECT_NEAR(solve.Rd[c], white.Rd()[c], 0.01f);  // 5% noise keeps it close
  }
}

TEST(DiffuseSolve, UnconstrainedChannelAndBadInput) {
  const std::vector<RGB> observed = {RGB(0.2f, 0.2f, 0.2f)}, specular = {RGB::Zero()}, basis = {RGB(0.5f, 0.0f, 0.5f)};
  const DiffuseSolve solve = solve_diffuse_reflectance(observed, specular, basis);
  EXPECT_FLOAT_EQ(solve.Rd[0], 0.4f);
  EXPECT_EQ(solve.Rd[1], 0.0f);  // nothing constrains green
  const std::vector<RGB> two(2, RGB::Zero());
  EXPECT_THROW(solve_diffuse_reflectance(observed, two, basis), Error);
  const std::vector<RGB> not_finite = {RGB(std::nanf(""), 0.2f, 0.2f)};
  EXPECT_THROW(solve_diffuse_reflectance(not_finite, specular, basis), Error);
  const std::vector<float> negative = {-1.0f};
  EXPECT_THROW(solve_diffuse_reflectance(observed, specular, basis, negative), Error);
}

}  // namespace
}  // namespace glaze
