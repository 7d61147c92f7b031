// Tests of the polished material (renderer/material.h): furnace, reciprocity, sampling,
// stiff parameters and the parameter registry.
#include "renderer/error.h"
#include "renderer/material.h"
#include "renderer/rng.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

Vec3 direction(float mu, float phi) {
  const float s = std::sqrt(std::max(0.0f, 1 - mu * mu));
  return {s * std::cos(phi), s * std::sin(phi), mu};
}

TEST(CoatTransmittance, HornerFormIsExactAndStableForSmallMu) {
  for (double mu = 0; mu <= 1.0; mu += 1.0 / 64) EXPECT_NEAR(coat_transmittance_g(mu), 1 - std::pow(1 - mu, 5), 1e-15);
  // In float the direct form cancels to 0 for mu = 1e-8; g(mu) ~ 5 mu there.
  for (float mu : {1e-8f, 1e-6f, 1e-4f}) {
    const double exact = 1 - std::pow(1 - double(mu), 5);
    EXPECT_NEAR(coat_transmittance_g(mu), exact, 1e-6 * exact) << mu;
  }
  EXPECT_EQ(coat_transmittance_g(-0.5f), 0.0f);  // clamped below the horizon
  EXPECT_EQ(coat_transmittance_g(1.5f), 1.0f);
}

TEST(Material, WhiteFurnaceByHemisphereQuadrature) {
  // Midpoint rule in (theta_i, phi_i) over eval_diffuse, independent of the closed form.
  const int theta_steps = 400, phi_steps = 16;
  for (float R0 : {0.0f, 0.04f, 0.3f, 0.9f, 1.0f}) {
    for (float rd : {0.0f, 0.37f, 1.0f}) {
      const PolishedMaterial material(R0, RGB::Constant(rd));
      for (float mu_o : {1.0f, 0.8f, 0.4f, 0.1f, 0.01f}) {
        const Vec3 wo = direction(mu_o, 0.3f);
        double integral = 0;
        for (int t = 0; t < theta_steps; ++t) {
          const double theta = (t + 0.5) * (kPiD / 2) / theta_steps;
          for (int p = 0; p < phi_steps; ++p) {
            const double phi = (p + 0.5) * 2 * kPiD / phi_steps;
            const Vec3 wi = direction(float(std::cos(theta)), float(phi));
            integral += material.eval_diffuse(wo, wi)[0] * std::cos(theta) * std::sin(theta) *
                        (kPiD / 2 / theta_steps) * (2 * kPiD / phi_steps);
          }
        }
        const double F = material.fresnel(mu_o);
        const double expected = F + rd * (1 - F);
        EXPECT_NEAR(F + integral, expected, 1e-4) << "R0 " << R0 << " Rd " << rd << " mu_o " << mu_o;
        EXPECT_NEAR(material.albedo(mu_o)[0], expected, 1e-6);
      }
    }
  }
}

TEST(Material, DoesNotUseThePapersMisprintedDiffuseFactor) {
  // The paper's 21/(20 pi (1 - R0)) would reflect F + Rd g(mu_o) / (1 - R0) > 1 in the
  // furnace. Quadrature of eval_diffuse must give 1 and stay clear of that value.
  const float R0 = 0.5f, mu_o = 0.5f;
  const PolishedMaterial white(R0, RGB::Ones());
  const Vec3 wo = direction(mu_o, 0.0f);
  const int steps = 2000;
  double integral = 0;
  for (int t = 0; t < steps; ++t) {
    const double theta = (t + 0.5) * (kPiD / 2) / steps;
    integral += white.eval_diffuse(wo, direction(float(std::cos(theta)), 0.0f))[0] * std::cos(theta) * std::sin(theta) *
                (kPiD / 2 / steps) * 2 * kPiD;
  }
  const double F = white.fresnel(mu_o);
  const double misprint = F + coat_transmittance_g(double(mu_o)) / (1 - R0);
  EXPECT_NEAR(F + integral, 1.0, 1e-4);
  EXPECT_GT(misprint, 1.4);
}

TEST(Material, DiffuseIsReciprocal) {
  const PolishedMaterial material(0.05f, RGB(0.9f, 0.5f, 0.1f));
  Pcg32 rng(3);
  for (int k = 0; k < 100; ++k) {
    const Vec3 a = direction(rng.next_float(), 6.28f * rng.next_float());
    const Vec3 b = direction(rng.next_float(), 6.28f * rng.next_float());
    EXPECT_LT((material.eval_diffuse(a, b) - material.eval_diffuse(b, a)).abs().maxCoeff(), 1e-7f);
  }
}

TEST(DiffuseLobe, PdfIntegratesToOne) {
  const int steps = 20000;
  double integral = 0;
  for (int t = 0; t < steps; ++t) {
    const double theta = (t + 0.5) * (kPiD / 2) / steps;
    integral += diffuse_lobe_pdf(float(std::cos(theta))) * std::sin(theta) * (kPiD / 2 / steps) * 2 * kPiD;
  }
  EXPECT_NEAR(integral, 1.0, 1e-6);
  EXPECT_EQ(diffuse_lobe_pdf(-0.2f), 0.0f);
}

// The SIMD inverse CDF (three Newton steps per lane, scalar where they did not converge)
// gives the one-at-a-time solver's cos(theta) to float rounding, and the CDF of the
// result is the input: at the ends, in the first table interval (where C ~ 3.5 mu^3 and
// lanes fall back) and at random, in a batch whose length is not a multiple of 16.
TEST(DiffuseLobe, BatchedInverseCdfMatchesTheScalarSolver) {
  std::vector<float> u = {0.0f, 1e-9f, 1e-6f, 0.001f, 0.0039f, 0.0040f, 0.5f, 0.999f, 0x1.fffffep-1f, 1.0f};
  Pcg32 rng(9);
  while (u.size() < 1000 + 3) u.push_back(rng.next_float());
  std::vector<float> cos_theta(u.size(), -1.0f);
  diffuse_lobe_cos_theta(u, cos_theta);
  for (size_t k = 0; k < u.size(); ++k) {
    const float expected = diffuse_lobe_cos_theta(u[k]);
    ASSERT_NEAR(cos_theta[k], expected, 2e-7f * std::max(expected, 1e-3f)) << "u = " << u[k];
    // C(mu) = u, from the pdf's integral (midpoint rule in mu; the pdf is per solid angle).
    const int steps = 4000;
    double cdf = 0.0;
    for (int s = 0; s < steps; ++s) {
      const double mu = (s + 0.5) / steps * cos_theta[k];
      cdf += 2.0 * kPiD * diffuse_lobe_pdf(float(mu)) * cos_theta[k] / steps;
    }
    ASSERT_NEAR(cdf, u[k], 2e-6) << "u = " << u[k];
  }
}

TEST(DiffuseLobe, SamplesMatchThePdfByChiSquare) {
  // Histogram over (cos theta, phi) cells; expected counts from integrating the PDF.
  const int mu_bins = 20, phi_bins = 8, samples = 200000;
  std::vector<double> observed(mu_bins * phi_bins, 0), expected(mu_bins * phi_bins, 0);
  Pcg32 rng(42);
  for (int k = 0; k < samples; ++k) {
    const Vec3 w = sample_diffuse_lobe(Vec2(rng.next_float(), rng.next_float()));
    ASSERT_NEAR(w.norm(), 1.0f, 1e-5f);
    ASSERT_GE(w.z(), 0.0f);
    float phi = std::atan2(w.y(), w.x());
    if (phi < 0) phi += 2 * kPi;
    const int i = std::min(int(w.z() * mu_bins), mu_bins - 1),
              j = std::min(int(phi / (2 * kPi) * phi_bins), phi_bins - 1);
    observed[i * phi_bins + j] += 1;
  }
  for (int i = 0; i < mu_bins; ++i) {
    double mass = 0;  // int pdf dmu dphi over the cell; pdf(w) dw = pdf dmu dphi
    const int sub = 200;
    for (int s = 0; s < sub; ++s) mass += diffuse_lobe_pdf(float((i + (s + 0.5) / sub) / mu_bins)) / (sub * mu_bins);
    for (int j = 0; j < phi_bins; ++j) expected[i * phi_bins + j] = samples * mass * 2 * kPiD / phi_bins;
  }
  EXPECT_GT(testing::chi_square_p_value(observed, expected), 1e-3);
}

TEST(Material, SampleWeightsArePdfConsistentAndUnbiased) {
  // The estimator sum(weight) of the directional albedo (furnace) must converge to the
  // closed form; each diffuse weight must equal f cos / pdf.
  for (float R0 : {0.0452f, 0.5f}) {
    const PolishedMaterial material(R0, RGB(0.9765f, 0.0186f, 0.4f));
    for (float mu_o : {0.95f, 0.3f}) {
      const Vec3 wo = direction(mu_o, 1.0f);
      Pcg32 rng(9);
      RGBd sum = RGBd::Zero(), sum_squares = RGBd::Zero();
      int specular_count = 0;
      const int n = 100000;
      for (int k = 0; k < n; ++k) {
        const auto s = material.sample(wo, rng.next_float(), Vec2(rng.next_float(), rng.next_float()));
        ASSERT_TRUE(s.has_value());
        if (s->is_specular) {
          ++specular_count;
          EXPECT_NEAR(s->wi.z(), wo.z(), 1e-6f);
        } else {
          const RGB direct = material.eval_diffuse(wo, s->wi) * s->wi.z() / s->pdf;
          EXPECT_LT((direct - s->weight).abs().maxCoeff(), 1e-4f * (1 + direct.abs().maxCoeff()));
          EXPECT_NEAR(material.pdf_diffuse(wo, s->wi), s->pdf, 1e-5f * s->pdf);
        }
        sum += s->weight.cast<double>();
        sum_squares += (s->weight * s->weight).cast<double>();
      }
      const RGBd mean = sum / n, variance = sum_squares / n - mean * mean;
      const RGB expected = material.albedo(mu_o);
      for (int c = 0; c < 3; ++c)
        EXPECT_LT(std::abs(mean[c] - expected[c]), 4 * std::sqrt(variance[c] / n) + 1e-6) << "channel " << c;
      EXPECT_NEAR(double(specular_count) / n, material.specular_probability(wo), 0.005);
    }
  }
}

// The lobe's weight that the path tracer's estimators take (material.h) against f_d cos /
// pdf evaluated from the BRDF and the lobe's density at random directions.
TEST(DiffuseLobe, WeightIsTheBrdfTimesCosineOverThePdf) {
  Pcg32 rng(10);
  for (int trial = 0; trial < 1000; ++trial) {
    const float R0 = rng.next_float();
    const PolishedMaterial material(R0, RGB(rng.next_float(), rng.next_float(), rng.next_float()));
    const Vec3 wo = direction(std::max(rng.next_float(), 1e-3f), 2 * kPi * rng.next_float());
    const Vec3 wi = direction(std::max(rng.next_float(), 1e-3f), 2 * kPi * rng.next_float());
    const RGB direct = material.eval_diffuse(wo, wi) * wi.z() / diffuse_lobe_pdf(wi.z());
    const RGB weight = material.Rd() * diffuse_lobe_weight(R0, wo.z());
    EXPECT_LT((direct - weight).abs().maxCoeff(), 1e-5f * (1 + direct.abs().maxCoeff())) << "trial " << trial;
    const auto sample = material.sample_diffuse(wo, Vec2(rng.next_float(), rng.next_float()));
    ASSERT_TRUE(sample.has_value());
    // The same formula, to rounding: this file may be compiled with other optimisations
    // than the library (CMakeLists.txt, glaze_orchestration_code), which contract
    // multiply-adds differently.
    EXPECT_LE((sample->weight - weight).abs().maxCoeff(), 1e-6f * weight.abs().maxCoeff());
  }
}

TEST(Material, StiffParametersGiveFiniteContinuousValues) {
  const float R0s[] = {0.0f, 1e-7f, 0.5f, 1.0f - 1e-7f, 1.0f};
  const float mus[] = {0.0f, 1e-8f, 1e-4f, 1.0f, -0.3f, -1.0f};
  for (float R0 : R0s) {
    for (float rd : {0.0f, 1.0f}) {
      const PolishedMaterial material(R0, RGB::Constant(rd));
      for (float mu_o : mus) {
        for (float mu_i : mus) {
          const Vec3 wo = direction(std::abs(mu_o), 0.1f) * (mu_o < 0 ? -1.0f : 1.0f);
          const Vec3 wi = direction(std::abs(mu_i), 2.0f) * (mu_i < 0 ? -1.0f : 1.0f);
          ASSERT_TRUE(material.eval_diffuse(wo, wi).allFinite());
          ASSERT_TRUE(std::isfinite(material.pdf_diffuse(wo, wi)));
          ASSERT_TRUE(material.albedo(mu_o).allFinite());
          ASSERT_TRUE(std::isfinite(material.fresnel(mu_o)));
          ASSERT_TRUE(std::isfinite(material.specular_probability(wo)));
          for (float u : {0.0f, 0.5f, 0.999999f}) {
            if (const auto s = material.sample(wo, u, Vec2(u, 1 - u))) {
              ASSERT_TRUE(s->wi.allFinite() && s->weight.allFinite() && std::isfinite(s->pdf));
              ASSERT_GT(s->pdf, 0.0f);
            }
          }
        }
      }
    }
  }
  // Continuity as R0 -> 1: values at 1 - 1e-7 are within 1e-6 of those at 1.
  const PolishedMaterial near_one(1.0f - 1e-7f, RGB::Ones()), one(1.0f, RGB::Ones());
  for (float mu : {1e-4f, 0.5f, 1.0f}) {
    const Vec3 w = direction(mu, 0.0f);
    EXPECT_NEAR(near_one.fresnel(mu), one.fresnel(mu), 1e-6f);
    EXPECT_NEAR(near_one.eval_diffuse(w, w)[0], one.eval_diffuse(w, w)[0], 1e-6f);
    EXPECT_NEAR(near_one.albedo(mu)[0], one.albedo(mu)[0], 1e-6f);
    EXPECT_NEAR(near_one.specular_probability(w), one.specular_probability(w), 1e-6f);
  }
}

TEST(MaterialParameters, RegistryListsBoundsAndConstructorEnforcesThem) {
  ASSERT_EQ(kMaterialParameters.size(), 2u);
  EXPECT_EQ(parameter_spec(MaterialParameter::R0).name, "R0");
  EXPECT_EQ(parameter_spec(MaterialParameter::Rd).dimension, 3);
  for (const ParameterSpec& spec : kMaterialParameters) {
    EXPECT_EQ(spec.lower, 0.0);
    EXPECT_EQ(spec.upper, 1.0);
    EXPECT_GE(spec.default_value, spec.lower);
    EXPECT_LE(spec.default_value, spec.upper);
  }
  EXPECT_THROW(PolishedMaterial(1.01f, RGB::Zero()), Error);
  EXPECT_THROW(PolishedMaterial(0.1f, RGB(0.5f, -0.1f, 0.5f)), Error);
  EXPECT_THROW(PolishedMaterial(std::nanf(""), RGB::Zero()), Error);
  try {
    PolishedMaterial(0.04f, RGB(0.5f, 2.0f, 0.5f));
    FAIL() << "Rd = 2 was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("Rd"), std::string::npos);
  }
}

}  // namespace
}  // namespace glaze
