// Tests of the environment (renderer/environment.h): mapping, lookup, orientation,
// importance sampling against its PDF, extreme maps and the procedural rooms.
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/procedural_environment.h"
#include "renderer/rng.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

Image gradient_map(int width, int height) {
  Image map(width, height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) map.set(i, j, RGB(float(i), float(j), float(i + 10 * j)));
  return map;
}

TEST(Environment, MappingFollowsTheConvention) {
  const Environment env(gradient_map(8, 4), {});
  // -Z is u = 0, +X is u = 1/4, +Z is u = 1/2, -X is u = 3/4; +Y is v = 0.
  EXPECT_NEAR(env.direction_to_uv(Vec3(0, 0, -1)).x(), 0.0f, 1e-6f);
  EXPECT_NEAR(env.direction_to_uv(Vec3(1, 0, 0)).x(), 0.25f, 1e-6f);
  EXPECT_NEAR(env.direction_to_uv(Vec3(0, 0, 1)).x(), 0.5f, 1e-6f);
  EXPECT_NEAR(env.direction_to_uv(Vec3(-1, 0, 0)).x(), 0.75f, 1e-6f);
  EXPECT_NEAR(env.direction_to_uv(Vec3(0, 1, 0)).y(), 0.0f, 1e-6f);
  EXPECT_NEAR(env.direction_to_uv(Vec3(0, -1, 0)).y(), 1.0f, 1e-6f);
  Pcg32 rng(1);
  for (int k = 0; k < 100; ++k) {
    const Vec2 uv(rng.next_float(), 0.01f + 0.98f * rng.next_float());
    EXPECT_LT((env.direction_to_uv(env.uv_to_direction(uv)) - uv).norm(), 1e-5f);
  }
}

TEST(Environment, BilinearLookupHitsTexelCentresAndWraps) {
  const Environment env(gradient_map(8, 4), {.scale = 2.0f});
  const Image& map = env.map();
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 8; ++i) {
      const Vec3 w = env.uv_to_direction(Vec2((i + 0.5f) / 8, (j + 0.5f) / 4));
      EXPECT_LT((env.eval(w) - 2.0f * map.at(i, j)).abs().maxCoeff(), 1e-3f) << i << "," << j;
    }
  // Halfway between column 7 and column 0 (across the seam), row 1 centre.
  const Vec3 seam = env.uv_to_direction(Vec2(0.0f, 1.5f / 4));
  EXPECT_LT((env.eval(seam) - 2.0f * 0.5f * (map.at(7, 1) + map.at(0, 1))).abs().maxCoeff(), 1e-3f);
  // Above the first row's centre the lookup clamps to row 0.
  EXPECT_LT((env.eval(Vec3(0, 1, 0)) - env.eval(env.uv_to_direction(Vec2(0.0f, 0.5f / 4)))).abs().maxCoeff(), 1e-3f);
}

TEST(Environment, RotationAndToWorldTurnTheMap) {
  const Image map = make_procedural_environment("office", 64, 32);
  const Environment still(map, {});
  const Environment turned(map, {.rotation_degrees = 90.0f});
  const Mat3 flip = Eigen::AngleAxisf(kPi, Vec3::UnitX()).toRotationMatrix();
  const Environment upside_down(map, {.to_world = flip});
  Pcg32 rng(2);
  for (int k = 0; k < 50; ++k) {
    const Vec3 w = Vec3(rng.next_float() - 0.5f, rng.next_float() - 0.5f, rng.next_float() - 0.5f).normalized();
    // Rotating by +90 degrees about +Y moves what was at w to R w (+Z turns towards +X).
    EXPECT_LT((turned.eval(rotation_about_y(90.0f) * w) - still.eval(w)).abs().maxCoeff(), 1e-3f);
    EXPECT_LT((upside_down.eval(flip * w) - still.eval(w)).abs().maxCoeff(), 1e-3f);
  }
  EXPECT_NEAR(turned.direction_to_uv(Vec3(-1, 0, 0)).x(), 0.0f, 1e-6f);  // -Z (u = 0) moved to -X
}

TEST(Environment, RejectsBadOptionsAndEmptyMaps) {
  Mat3 shear = Mat3::Identity();
  shear(0, 1) = 0.5f;
  EXPECT_THROW(Environment(gradient_map(8, 4), {.to_world = shear}), Error);
  EXPECT_THROW(Environment(gradient_map(8, 4), {.to_world = -Mat3::Identity()}), Error);  // a reflection
  EXPECT_THROW(Environment(gradient_map(8, 4), {.scale = -1.0f}), Error);
  EXPECT_THROW(Environment(Image(), {}), Error);
  EXPECT_THROW(make_procedural_environment("nowhere", 64, 32), Error);
  EXPECT_THROW(make_procedural_environment("office", 0, 32), Error);
}

TEST(Environment, WarnsForNonTwoToOneAndRepairsNonFiniteTexels) {
  testing::CapturedWarnings warnings;
  Image map(6, 4);
  std::fill(map.pixels.begin(), map.pixels.end(), 1.0f);
  map.pixels[0] = std::numeric_limits<float>::quiet_NaN();
  map.pixels[4] = std::numeric_limits<float>::infinity();
  map.pixels[7] = -2.0f;
  const Environment env(map, {}, "odd.exr");
  ASSERT_EQ(warnings.messages.size(), 2u);
  EXPECT_NE(warnings.messages[0].find("not 2:1"), std::string::npos);
  EXPECT_NE(warnings.messages[1].find("3 texel values"), std::string::npos);
  EXPECT_TRUE(env.map().at(0, 0).allFinite());
  for (int k = 0; k < 100; ++k)
    EXPECT_TRUE(env.eval(Vec3(std::sin(k * 1.f), std::cos(k * 1.f), 0.3f).normalized()).allFinite());
}

// Checks sample() against pdf(): the PDF's mass per cell of a (u, v) grid, computed
// exactly (the density in (u, v) is constant over each texel: pdf * 2 pi^2 sin(theta)),
// against a histogram of samples by chi-square; and sample() and pdf() agreeing.
void check_sampling(const Environment& env, int samples, uint64_t seed) {
  const int grid_u = 32, grid_v = 16, width = env.map().width, height = env.map().height;
  std::vector<double> expected(grid_u * grid_v, 0.0), observed(grid_u * grid_v, 0.0);
  double total = 0.0;
  for (int j = 0; j < height; ++j) {
    for (int i = 0; i < width; ++i) {
      const Vec2 centre((i + 0.5f) / width, (j + 0.5f) / height);
      const double density_uv = env.pdf(env.uv_to_direction(centre)) * 2 * kPiD * kPiD * std::sin(kPiD * centre.y());
      // Split the texel's (u, v) rectangle over the grid cells it overlaps.
      for (int cj = j * grid_v / height; cj < grid_v && cj <= (j + 1) * grid_v / height; ++cj) {
        const double v_overlap =
            std::min((j + 1.0) / height, (cj + 1.0) / grid_v) - std::max(double(j) / height, double(cj) / grid_v);
        if (v_overlap <= 0) continue;
        for (int ci = i * grid_u / width; ci < grid_u && ci <= (i + 1) * grid_u / width; ++ci) {
          const double u_overlap =
              std::min((i + 1.0) / width, (ci + 1.0) / grid_u) - std::max(double(i) / width, double(ci) / grid_u);
          if (u_overlap <= 0) continue;
          expected[cj * grid_u + ci] += density_uv * u_overlap * v_overlap;
          total += density_uv * u_overlap * v_overlap;
        }
      }
    }
  }
  EXPECT_NEAR(total, 1.0, 1e-4) << env.source();
  Pcg32 rng(seed);
  int disagreements = 0;
  for (int k = 0; k < samples; ++k) {
    const EnvironmentSample s = env.sample(rng);
    ASSERT_TRUE(s.direction.allFinite());
    if (s.pdf == 0.0f) continue;
    ASSERT_NEAR(s.direction.norm(), 1.0f, 1e-4f);
    // sample() and pdf() agree on the density of the direction drawn, except where the
    // float round trip direction -> (u, v) lands across a texel boundary.
    ASSERT_GT(s.pdf, 0.0f);
    disagreements += std::abs(env.pdf(s.direction) - s.pdf) > 1e-3f * s.pdf;
    const Vec2 uv = env.direction_to_uv(s.direction);
    const int i = std::min(int(uv.x() * grid_u), grid_u - 1), j = std::min(int(uv.y() * grid_v), grid_v - 1);
    observed[j * grid_u + i] += 1;
  }
  EXPECT_LE(disagreements, samples / 2000) << env.source();
  for (double& e : expected) e *= samples / total;
  EXPECT_GT(testing::chi_square_p_value(observed, expected), 1e-3) << env.source();
}

// The solid-angle density is right if importance sampling estimates the integral of
// the radiance over the sphere without bias: mean of L(w) / pdf(w) against a direct sum
// of texels times their exact solid angles (agreeing with the bilinear map to O(texel^2)).
void check_unbiased_integral(const Environment& env, int samples, uint64_t seed) {
  const Image& map = env.map();
  double direct = 0.0;
  for (int j = 0; j < map.height; ++j) {
    const double solid_angle =
        2 * kPiD / map.width * (std::cos(kPiD * j / map.height) - std::cos(kPiD * (j + 1) / map.height));
    for (int i = 0; i < map.width; ++i) direct += luminance(map.at(i, j)) * solid_angle;
  }
  Pcg32 rng(seed);
  double sum = 0.0, sum_squares = 0.0;
  for (int k = 0; k < samples; ++k) {
    const EnvironmentSample s = env.sample(rng);
    const double value = s.pdf > 0 ? luminance(env.eval(s.direction)) / env.scale() / s.pdf : 0.0;
    sum += value;
    sum_squares += value * value;
  }
  const double mean = sum / samples, standard_error = std::sqrt((sum_squares / samples - mean * mean) / samples);
  EXPECT_LT(std::abs(mean - direct), 4 * standard_error + 2e-3 * direct) << env.source() << " direct " << direct;
}

TEST(EnvironmentSampling, MatchesPdfOnOffice) {
  check_sampling(Environment(make_procedural_environment("office", 256, 128), {.rotation_degrees = 30}, "office"),
                 400000, 1);
}

TEST(EnvironmentSampling, MatchesPdfOnBlueRoom) {
  check_sampling(Environment(make_procedural_environment("blue-room", 128, 64), {}, "blue-room"), 200000, 2);
}

TEST(EnvironmentSampling, MatchesPdfOnRealMap) {
  GLAZE_REQUIRE_ENVMAP(path, "st_fagans_interior_1k.hdr");
  const Environment env = Environment::load(path.string());
  check_sampling(env, 400000, 3);
  check_unbiased_integral(env, 400000, 13);
}

TEST(EnvironmentSampling, UnbiasedIntegralOnProceduralRooms) {
  check_unbiased_integral(Environment(make_procedural_environment("office", 512, 256), {.rotation_degrees = 10}),
                          400000, 21);
  check_unbiased_integral(Environment(make_procedural_environment("blue-room", 256, 128), {}), 400000, 22);
}

TEST(EnvironmentSampling, MatchesPdfOnRotatedGraceCathedral) {
  GLAZE_REQUIRE_ENVMAP(path, "grace_latlong.exr");
  const Mat3 flip = Eigen::AngleAxisf(kPi, Vec3::UnitX()).toRotationMatrix();
  check_sampling(Environment::load(path.string(), {.to_world = flip}), 400000, 4);
}

TEST(EnvironmentSampling, CoversEveryDirectionTheLookupLights) {
  // A single hot texel: the bilinear lookup spreads it into its neighbours, and the
  // sampler must be able to reach all of them (pdf > 0 wherever eval > 0).
  Image map(64, 32);
  map.set(20, 10, RGB(1e6f, 1e6f, 1e6f));
  const Environment env(map, {});
  Pcg32 rng(6);
  int lit = 0;
  for (int k = 0; k < 200000; ++k) {
    const Vec3 w = env.uv_to_direction(Vec2((18 + 5 * rng.next_float()) / 64, (8 + 5 * rng.next_float()) / 32));
    if (env.eval(w).maxCoeff() > 0.0f) {
      ++lit;
      ASSERT_GT(env.pdf(w), 0.0f);
    }
  }
  EXPECT_GT(lit, 1000);
}

TEST(EnvironmentSampling, HighDynamicRangeAndTinyMaps) {
  // 1e6:1: one texel a million times brighter than the rest takes nearly all samples.
  Image map(128, 64);
  std::fill(map.pixels.begin(), map.pixels.end(), 1.0f);
  map.set(40, 30, RGB::Constant(1e6f));
  const Environment hdr(map, {});
  check_sampling(hdr, 200000, 7);
  const ShCoefficients& sh = hdr.sh(8);
  for (const RGBd& v : sh.values) EXPECT_TRUE(v.allFinite());

  Image one(1, 1);
  one.set(0, 0, RGB(0.5f, 1.0f, 2.0f));
  const Environment tiny(one, {});
  EXPECT_LT((tiny.eval(Vec3(0.3f, -0.9f, 0.1f).normalized()) - RGB(0.5f, 1.0f, 2.0f)).abs().maxCoeff(), 1e-6f);
  check_sampling(tiny, 100000, 8);
  EXPECT_NEAR(tiny.sh(4)(0, 0)[2], 2.0 * 2.0 * std::sqrt(kPiD), 1e-6);
  for (int i = 1; i < sh_count(4); ++i) EXPECT_LT(tiny.sh(4).values[i].abs().maxCoeff(), 1e-6);
}

TEST(ProceduralEnvironment, OfficeHasItsCeilingLightsAndBlueRoomItsSpots) {
  const Image office = make_procedural_environment("office", 512, 256);
  const Environment env(office, {});
  // Straight up is the ceiling between panels or a panel: count bright texels in the
  // upper hemisphere: 24 panels must show up as separate bright regions.
  int bright = 0;
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 512; ++i) bright += luminance(office.at(i, j)) > 10.0f;
  EXPECT_GT(bright, 500);
  EXPECT_GT(luminance(env.eval(Vec3(0, 1, 0))), 0.0f);
  EXPECT_LT(luminance(env.eval(Vec3(0, -1, 0))), 1.0f);  // floor is dark
  const Environment blue(make_procedural_environment("blue-room", 512, 256), {});
  const RGB wall = blue.eval(Vec3(0, 0, 1));
  EXPECT_GT(wall[2], 2 * wall[0]);  // blue walls
  const RGB white_spot = blue.eval(Vec3(-0.8f, 0.5f, -3.0f).normalized());
  const RGB red_spot = blue.eval(Vec3(3.0f, 0.7f, 0.6f).normalized());
  EXPECT_GT(luminance(white_spot), 10 * luminance(wall));
  EXPECT_GT(red_spot[0], 3 * red_spot[1]);
  EXPECT_GT(red_spot[0], 10 * wall[0]);
}

}  // namespace
}  // namespace glaze
