// Tests of the shading model's affine form (renderer/shading.h) against the material's
// BRDF (renderer/material.h) evaluated directly, for one ray and under Ceres's Jets.
#include "renderer/material.h"
#include "renderer/quadrature.h"
#include "renderer/rng.h"
#include "renderer/shading.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>

namespace glaze {
namespace {

// Light about the normal L(wi) = a + b cos(theta_i), with the mirror seeing L_mirror.
struct Light {
  double L_mirror, a, b;
  // E(n) = integral of g(mu) mu L over the hemisphere, in closed form: with
  // int_0^1 g(mu) mu dmu = 1/2 - 1/42 = 10/21 and int_0^1 g(mu) mu^2 dmu = 1/3 - 1/168 = 55/168.
  double E() const { return 2 * kPiD * (10 * a / 21 + 55 * b / 168); }
};

Light random_light(Pcg32& rng) {
  const double a = rng.next_float();
  return {3.0 * rng.next_float(), a, (1.0 + a) * rng.next_float() - a};  // L >= 0 on the hemisphere
}

Vec3 direction(float mu, float phi) {
  const float s = std::sqrt(std::max(0.0f, 1 - mu * mu));
  return {s * std::cos(phi), s * std::sin(phi), mu};
}

// The material's reflected radiance towards wo, evaluated directly: the mirror's Fresnel
// weight times L_mirror, plus f_d L cos integrated over the hemisphere (f_d does not depend
// on the azimuth here, and the integrand is a polynomial of degree 7 in mu_i, which an
// 8-point Gauss-Legendre rule integrates exactly).
RGBd reflected(const PolishedMaterial& material, const Vec3& wo, const Light& light) {
  const QuadratureRule rule = gauss_legendre(8, 0.0, 1.0);
  RGBd diffuse = RGBd::Zero();
  for (size_t k = 0; k < rule.nodes.size(); ++k) {
    const double mu = rule.nodes[k];
    diffuse += 2 * kPiD * rule.weights[k] * (light.a + light.b * mu) * mu *
               material.eval_diffuse(wo, direction(float(mu), 0.7f)).cast<double>();
  }
  return double(material.fresnel(wo.z())) * light.L_mirror + diffuse;
}

TEST(ShadingCoefficients, AffineFormIsTheMaterialsReflectance) {
  Pcg32 rng(11);
  for (int trial = 0; trial < 500; ++trial) {
    const float R0 = trial == 0 ? 0.0f : trial == 1 ? 1.0f : rng.next_float();
    const RGB Rd(rng.next_float(), rng.next_float(), rng.next_float());
    const PolishedMaterial material(R0, Rd);
    const float mu_o = std::max(rng.next_float(), 1e-3f);
    const Vec3 wo = direction(mu_o, 2 * kPi * rng.next_float());
    const Light light = random_light(rng);
    const RGBd expected = reflected(material, wo, light);
    const ShadingBasis<double> basis(mu_o, light.L_mirror, light.E());
    for (int c = 0; c < 3; ++c) {
      const ShadingCoefficients<double> coefficients(R0, Rd[c]);
      const double specular = coefficients.specular_radiance(basis), diffuse = coefficients.diffuse_radiance(basis);
      EXPECT_NEAR(specular, material.fresnel(mu_o) * light.L_mirror, 1e-6 * (1 + light.L_mirror)) << "trial " << trial;
      EXPECT_NEAR(coefficients.radiance(basis), expected[c], 1e-5 * (1 + expected[c])) << "trial " << trial;
      EXPECT_DOUBLE_EQ(coefficients.radiance(basis), specular + diffuse);
      // Per unit of Rd (the fits that solve for Rd after R0): the same s, up to rounding.
      EXPECT_NEAR(ShadingCoefficients<double>(R0).diffuse * Rd[c], coefficients.diffuse, 1e-15);
    }
    // The RGB routine of one ray (the sh integrator's) is the same form, in float.
    const RGB one_ray =
        polished_radiance(material, mu_o, RGB::Constant(float(light.L_mirror)), RGB::Constant(float(light.E())));
    EXPECT_LT((one_ray.cast<double>() - expected).abs().maxCoeff(), 1e-5 * (1 + expected.maxCoeff()))
        << "trial " << trial;
  }
}

// Through Ceres's Jets, the derivatives are those of Lo = L - (1 - R0) gL + K Rd (1 - R0) gE:
// dLo/dR0 = gL - K Rd gE and dLo/dRd = K (1 - R0) gE.
TEST(ShadingCoefficients, JetsCarryTheModelsDerivatives) {
  using Jet = ceres::Jet<double, 2>;
  const double K = 21.0 / (20.0 * kPiD);
  Pcg32 rng(12);
  for (int trial = 0; trial < 100; ++trial) {
    const double R0 = rng.next_float(), Rd = rng.next_float();
    const ShadingBasis<float> basis(rng.next_float(), 2 * rng.next_float(), 3 * rng.next_float());
    const Jet Lo = ShadingCoefficients<Jet>(Jet(R0, 0), Jet(Rd, 1)).radiance(basis);
    EXPECT_NEAR(Lo.a, basis.L - (1 - R0) * basis.gL + K * Rd * (1 - R0) * basis.gE, 1e-12);
    EXPECT_NEAR(Lo.v[0], basis.gL - K * Rd * basis.gE, 1e-12);
    EXPECT_NEAR(Lo.v[1], K * (1 - R0) * basis.gE, 1e-12);
  }
}

}  // namespace
}  // namespace glaze
