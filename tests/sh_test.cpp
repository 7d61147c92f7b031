// Tests of the SH basis, kernel, projection, rotation and diffuse sum (renderer/sh.h)
// against closed forms and independent quadratures.
#include "renderer/environment.h"
#include "renderer/latlong.h"
#include "renderer/material.h"
#include "renderer/procedural_environment.h"
#include "renderer/quadrature.h"
#include "renderer/sh.h"
#include "renderer/rng.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

std::vector<double> basis(int lmax, const Vec3d& d) {
  std::vector<double> values(sh_count(lmax));
  sh_eval<double>(lmax, d, values);
  return values;
}

TEST(ShBasis, MatchesClosedFormsUpToBandTwo) {
  // Cartesian closed forms (Ramamoorthi-Hanrahan, no Condon-Shortley phase).
  Pcg32 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    Vec3d d(rng.next_float() - 0.5, rng.next_float() - 0.5, rng.next_float() - 0.5);
    d.normalize();
    const double x = d.x(), y = d.y(), z = d.z();
    const std::vector<double> y_lm = basis(2, d);
    EXPECT_NEAR(y_lm[sh_index(0, 0)], 0.282094791773878, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(1, -1)], 0.488602511902920 * y, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(1, 0)], 0.488602511902920 * z, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(1, 1)], 0.488602511902920 * x, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(2, -2)], 1.092548430592079 * x * y, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(2, -1)], 1.092548430592079 * y * z, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(2, 0)], 0.315391565252520 * (3 * z * z - 1), 1e-14);
    EXPECT_NEAR(y_lm[sh_index(2, 1)], 1.092548430592079 * x * z, 1e-14);
    EXPECT_NEAR(y_lm[sh_index(2, 2)], 0.546274215296040 * (x * x - y * y), 1e-14);
  }
}

TEST(ShBasis, BandThreeMatchesClosedForm) {
  const Vec3d d = Vec3d(0.3, -0.5, 0.7).normalized();
  const double x = d.x(), y = d.y(), z = d.z();
  const std::vector<double> y_lm = basis(3, d);
  EXPECT_NEAR(y_lm[sh_index(3, -3)], 0.590043589926644 * y * (3 * x * x - y * y), 1e-14);
  EXPECT_NEAR(y_lm[sh_index(3, 0)], 0.373176332590115 * z * (5 * z * z - 3), 1e-14);
  EXPECT_NEAR(y_lm[sh_index(3, 3)], 0.590043589926644 * x * (x * x - 3 * y * y), 1e-14);
}

TEST(ShBasis, OrthonormalByQuadratureUpToBand16) {
  // Gauss-Legendre in cos(theta) x trapezoid in phi: exact for these band limits.
  const int lmax = 16, n = sh_count(lmax);
  const QuadratureRule rule = gauss_legendre(2 * lmax + 2);
  const int phi_steps = 4 * lmax + 4;
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(n, n);
  for (size_t k = 0; k < rule.nodes.size(); ++k) {
    const double z = rule.nodes[k], r = std::sqrt(1 - z * z);
    for (int p = 0; p < phi_steps; ++p) {
      const double phi = 2 * kPiD * p / phi_steps;
      const std::vector<double> y = basis(lmax, Vec3d(r * std::cos(phi), r * std::sin(phi), z));
      const Eigen::Map<const Eigen::VectorXd> v(y.data(), n);
      gram += rule.weights[k] * (2 * kPiD / phi_steps) * v * v.transpose();
    }
  }
  EXPECT_LT((gram - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff(), 1e-10);
}

TEST(ShBasis, HighBandsStayFiniteAndNormalised) {
  // Addition theorem: sum_m Y_lm(d)^2 = (2l+1)/(4 pi) for every direction.
  for (const Vec3d& d : {Vec3d(0, 0, 1), Vec3d(1, 0, 0), Vec3d(0.6, 0.0, 0.8), Vec3d(-0.36, 0.48, 0.8)}) {
    const std::vector<double> y = basis(kShMaxLmax, d);
    for (int l = 0; l <= kShMaxLmax; l += 7) {
      double sum = 0;
      for (int m = -l; m <= l; ++m) sum += y[sh_index(l, m)] * y[sh_index(l, m)];
      EXPECT_NEAR(sum, (2 * l + 1) / (4 * kPiD), 1e-9 * (2 * l + 1)) << "l = " << l;
    }
  }
}

TEST(ShKernel, CoefficientsMatchDesignValuesAndClosedForms) {
  const double design[] = {0.8440, 1.0051, 0.5308, 0.0326, -0.1271};
  const double sqrt_pi = std::sqrt(kPiD);
  const double closed[] = {10 * sqrt_pi / 21, 55 * std::sqrt(3 * kPiD) / 168, 15 * std::sqrt(5 * kPiD) / 112,
                           std::sqrt(7 * kPiD) / 144, -265 * sqrt_pi / 3696};
  for (int l = 0; l <= 4; ++l) {
    EXPECT_NEAR(sh_kernel_coefficient(l), design[l], 1e-4) << "l = " << l;
    EXPECT_NEAR(sh_kernel_coefficient(l), closed[l], 1e-13) << "l = " << l;
  }
}

TEST(ShKernel, HigherCoefficientsMatchBruteForceIntegral) {
  // Independent: composite Simpson on the raw integrand, not Gauss-Legendre.
  for (int l : {5, 8, 13, 16, 30}) {
    const int steps = 20000;
    double sum = 0;
    for (int i = 0; i <= steps; ++i) {
      const double mu = double(i) / steps;
      const double weight = (i == 0 || i == steps) ? 1 : (i % 2 ? 4 : 2);
      sum += weight * coat_transmittance_g(mu) * mu * basis(l, Vec3d(std::sqrt(1 - mu * mu), 0, mu))[sh_index(l, 0)];
    }
    const double simpson = 2 * kPiD * sum / (3.0 * steps);
    EXPECT_NEAR(sh_kernel_coefficient(l), simpson, 1e-9) << "l = " << l;
  }
}

TEST(ShKernel, EnergyKeptAtBandFourIs9973Percent) {
  EXPECT_NEAR(sh_kernel_energy_fraction(4), 0.9973, 5e-5);
  double previous = 0;
  for (int lmax = 0; lmax <= 20; ++lmax) {
    const double fraction = sh_kernel_energy_fraction(lmax);
    EXPECT_GE(fraction, previous);
    EXPECT_LT(fraction, 1.0);  // the clamped kernel is not band-limited
    previous = fraction;
  }
  EXPECT_GT(previous, 0.99999);
}

TEST(ShProjection, ConstantMapIsExactAtAnyResolutionAndOrientation) {
  const Mat3 tilted = Eigen::AngleAxisf(0.7f, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  for (auto [w, h] : {std::pair{1024, 512}, {64, 32}, {1, 1}, {7, 5}}) {
    for (const Mat3& frame : {Mat3(Mat3::Identity()), tilted}) {
      Image map(w, h);
      std::fill(map.pixels.begin(), map.pixels.end(), 1.0f);
      const ShCoefficients sh = sh_project_latlong(map, frame, 8);
      EXPECT_NEAR(sh(0, 0)[0], 2 * std::sqrt(kPiD), 1e-9) << w << "x" << h;
      for (int i = 1; i < sh_count(8); ++i)
        for (int c = 0; c < 3; ++c) EXPECT_LT(std::abs(sh.values[i][c]), 1e-6) << w << "x" << h << " i=" << i;
    }
  }
}

// A lat-long map whose texel centres sample sum_lm c_lm Y_lm in world space.
Image synthesise(const ShCoefficients& coefficients, const Mat3& local_to_world, int width, int height) {
  Image map(width, height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      const Vec3 d = local_to_world * latlong_to_direction(Vec2((i + 0.5f) / width, (j + 0.5f) / height));
      map.set(i, j, coefficients.eval(d));
    }
  return map;
}

ShCoefficients random_coefficients(int lmax, uint64_t seed) {
  Pcg32 rng(seed);
  ShCoefficients c(lmax);
  for (RGBd& value : c.values) value = RGBd(rng.next_float(), rng.next_float(), rng.next_float()) - 0.5;
  c(0, 0) += 3.0;  // keep the function positive-ish, like radiance
  return c;
}

TEST(ShProjection, SynthesisedMapProjectsBackToItsCoefficients) {
  const Mat3 frame = Eigen::AngleAxisf(-1.1f, Vec3(0.2f, 1, -0.4f).normalized()).toRotationMatrix();
  for (const Mat3& local_to_world : {Mat3(Mat3::Identity()), frame}) {
    const ShCoefficients truth = random_coefficients(4, 11);
    const ShCoefficients projected =
        sh_project_latlong(synthesise(truth, local_to_world, 1024, 512), local_to_world, 4);
    double scale = 0;
    for (const RGBd& v : truth.values) scale = std::max(scale, v.abs().maxCoeff());
    for (int i = 0; i < sh_count(4); ++i)
      EXPECT_LT((projected.values[i] - truth.values[i]).abs().maxCoeff(), 1e-4 * scale) << "i = " << i;
  }
}

TEST(ShRotation, MatchesProjectionOfTheRotatedFunction) {
  const ShCoefficients c = random_coefficients(6, 3);
  const Mat3d rotation = Eigen::AngleAxisd(2.0, Vec3d(-1, 0.5, 0.25).normalized()).toRotationMatrix();
  const ShCoefficients rotated = sh_rotate(c, rotation);
  // f_rotated(w) = f(R^T w), checked pointwise.
  Pcg32 rng(5);
  for (int k = 0; k < 20; ++k) {
    const Vec3 w = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f).normalized();
    const Vec3 turned = (rotation.transpose().cast<float>() * w);
    EXPECT_LT((rotated.eval(w) - c.eval(turned)).abs().maxCoeff(), 1e-5);
  }
  const ShCoefficients identity = sh_rotate(c, Mat3d::Identity());
  for (int i = 0; i < sh_count(6); ++i) EXPECT_LT((identity.values[i] - c.values[i]).abs().maxCoeff(), 1e-12);
}

TEST(ShDiffuseSum, ConstantMapGivesTwentyPiOverTwentyOne) {
  const Environment constant(make_procedural_environment("constant", 32, 16), {.scale = 2.5f});
  for (int lmax : {0, 2, 4, 9}) {
    const ShDiffuseSum sum(constant.sh(lmax));
    for (const Vec3& n : {Vec3(0, 0, 1), Vec3(0, 1, 0), Vec3(0.6f, -0.8f, 0)})
      EXPECT_NEAR(sum(n)[1], 20 * kPi / 21 * 2.5f, 1e-5);
  }
}

TEST(ShDiffuseSum, WrittenOutLowBandsEqualTheRecurrence) {
  // For lmax <= 4 the sum evaluates written-out polynomials; here it is recomputed from
  // its definition, sum_lm Lambda_l h_l L_lm Y_lm(n), with the recurrence in double.
  const Environment office(make_procedural_environment("office", 128, 64), {.rotation_degrees = 33.0f});
  Pcg32 rng(7, 1);
  for (int lmax : {0, 1, 2, 3, 4}) {
    const ShCoefficients& L = office.sh(lmax);
    const ShDiffuseSum sum(L);
    for (int trial = 0; trial < 200; ++trial) {
      const Vec3 n = latlong_to_direction(Vec2(rng.next_float(), rng.next_float()));
      RGBd expected = RGBd::Zero();
      for_each_sh(lmax, double(n.x()), double(n.y()), double(n.z()), [&](int i, double y) {
        int l = 0;
        while ((l + 1) * (l + 1) <= i) ++l;
        expected += sh_lambda(l) * sh_kernel_coefficient(l) * y * L.values[i];
      });
      const RGB got = sum(n);
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(got[c], expected[c], 2e-6 * (1.0 + std::abs(expected[c]))) << lmax << " " << c;
    }
  }
}

TEST(ShDiffuseSum, LanesOfNormalsEqualTheRecurrenceInDouble) {
  // The form for many normals (SIMD lanes of them above lmax 4) against the definition,
  // as above, at band limits with and without a compile-time form, for a count of
  // normals that leaves the last lanes empty.
  const Environment office(make_procedural_environment("office", 128, 64), {.rotation_degrees = 33.0f});
  Pcg32 rng(8, 1);
  for (int lmax : {3, 5, 8, 16}) {
    const ShCoefficients& L = office.sh(lmax);
    const ShDiffuseSum sum(L);
    std::vector<Vec3> normals(37);
    for (Vec3& n : normals) n = latlong_to_direction(Vec2(rng.next_float(), rng.next_float()));
    std::vector<RGB> got(normals.size());
    sum(normals, got);
    for (size_t k = 0; k < normals.size(); ++k) {
      const Vec3& n = normals[k];
      RGBd expected = RGBd::Zero();
      for_each_sh(lmax, double(n.x()), double(n.y()), double(n.z()), [&](int i, double y) {
        int l = 0;
        while ((l + 1) * (l + 1) <= i) ++l;
        expected += sh_lambda(l) * sh_kernel_coefficient(l) * y * L.values[i];
      });
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(got[k][c], expected[c], 1e-5 * (1.0 + std::abs(expected[c]))) << lmax << " " << k;
    }
  }
  std::vector<RGB> wrong_size(2);
  EXPECT_THROW(ShDiffuseSum(office.sh(8))(std::vector<Vec3>(3, Vec3::UnitZ()), wrong_size), Error);
}

TEST(Sh, SumsOverDirectionsEqualTheRecurrenceInDouble) {
  // sh_sum (SIMD lanes of directions) against the basis summed one direction at a time
  // in double, for counts that fill and that leave lanes empty.
  Pcg32 rng(9, 2);
  for (int lmax : {4, 6}) {
    for (size_t count : {size_t(1), size_t(16), size_t(37)}) {
      std::vector<Vec3> directions(count);
      std::vector<float> weights(count);
      for (size_t k = 0; k < count; ++k) {
        directions[k] = latlong_to_direction(Vec2(rng.next_float(), rng.next_float()));
        weights[k] = rng.next_float();
      }
      std::vector<double> sums(sh_count(lmax)), weighted(sh_count(lmax));
      sh_sum(lmax, directions, weights, sums, weighted);
      std::vector<double> expected(sh_count(lmax), 0.0), expected_weighted(sh_count(lmax), 0.0);
      for (size_t k = 0; k < count; ++k)
        for_each_sh(lmax, double(directions[k].x()), double(directions[k].y()), double(directions[k].z()),
                    [&](int i, double y) { expected[i] += y, expected_weighted[i] += weights[k] * y; });
      for (int i = 0; i < sh_count(lmax); ++i) {
        EXPECT_NEAR(sums[i], expected[i], 1e-5 * double(count)) << lmax << " " << count << " " << i;
        EXPECT_NEAR(weighted[i], expected_weighted[i], 1e-5 * double(count)) << lmax << " " << count << " " << i;
      }
    }
  }
  std::vector<double> room(25);
  EXPECT_THROW(sh_sum(4, std::vector<Vec3>(2, Vec3::UnitZ()), std::vector<float>(1, 1.0f), room, room), Error);
}

TEST(ShDiffuseSum, ConvergesToTheDirectIntegralOverTheMap) {
  // E(n) = int L(w) g(n.w) max(n.w, 0) dw summed over every texel (Funk-Hecke says the SH
  // sum is this integral, truncated at lmax). At lmax 16 the office must agree closely.
  const Environment office(make_procedural_environment("office", 256, 128), {});
  const Image& map = office.map();
  const ShDiffuseSum sum(office.sh(16));
  for (const Vec3& n : {Vec3(0, 1, 0), Vec3(0, -1, 0), Vec3(0.6f, 0, 0.8f), Vec3(-0.48f, 0.6f, -0.64f)}) {
    RGBd direct = RGBd::Zero();
    for (int j = 0; j < map.height; ++j) {
      const double solid_angle =
          2 * kPiD / map.width * (std::cos(kPiD * j / map.height) - std::cos(kPiD * (j + 1) / map.height));
      for (int i = 0; i < map.width; ++i) {
        const Vec3 w = latlong_to_direction(Vec2((i + 0.5f) / map.width, (j + 0.5f) / map.height));
        const double mu = n.dot(w);
        if (mu > 0) direct += map.at(i, j).cast<double>() * coat_transmittance_g(mu) * mu * solid_angle;
      }
    }
    const RGB sh_value = sum(n);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(sh_value[c], direct[c], 5e-3 * direct[c]) << n.transpose();
  }
}

}  // namespace
}  // namespace glaze
