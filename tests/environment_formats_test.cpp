// Environment files in the angular-map (light probe) and mirror-ball formats
// (renderer/environment_format.h): the pixel <-> direction maps against their published
// definitions, lat-long maps written by glaze's own writer and read back, recognition,
// and scenes and capture sets that name such a file.
#include "renderer/environment.h"
#include "renderer/environment_format.h"
#include "renderer/error.h"
#include "renderer/latlong.h"
#include "renderer/mirror_ball.h"
#include "renderer/procedural_environment.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <fstream>

namespace glaze {
namespace {

using testing::CapturedWarnings;
using testing::read_json;
using testing::TemporaryDirectory;

constexpr EnvironmentFormat kAngular = EnvironmentFormat::angular, kMirrorBall = EnvironmentFormat::mirror_ball;

double angle_between(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

// Writes `latlong` as a probe image in `format` with glaze's writer and reads it back as an
// environment file.
Environment round_trip(const TemporaryDirectory& dir, const Image& latlong, EnvironmentFormat format, int size,
                       const std::string& name) {
  write_image(dir.file(name), latlong_to_probe(latlong, format, size));
  EnvironmentOptions options;
  options.format = format;
  return Environment::load(dir.file(name), options);
}

// The luminance-weighted mean direction of a lat-long map (over solid angle).
Vec3d bright_direction(const Image& map) {
  Vec3d sum = Vec3d::Zero();
  for (int j = 0; j < map.height; ++j)
    for (int i = 0; i < map.width; ++i) {
      const Vec2 uv((i + 0.5f) / map.width, (j + 0.5f) / map.height);
      sum += double(luminance(map.at(i, j))) * latlong_texel_solid_angle(j, map.width, map.height) *
             latlong_to_direction(uv).cast<double>();
    }
  return sum.normalized();
}

// Largest difference between two sets of SH coefficients, relative to the first's L00.
double sh_difference(const ShCoefficients& a, const ShCoefficients& b) {
  double largest = 0.0;
  for (size_t k = 0; k < a.values.size(); ++k)
    largest = std::max(largest, ((a.values[k] - b.values[k]).abs() / a.values[0]).maxCoeff());
  return largest;
}

// `map` with the directions within `degrees` of -Z (the mirror ball's blind spot) black.
Image without_blind_spot(Image map, double degrees) {
  for (int j = 0; j < map.height; ++j)
    for (int i = 0; i < map.width; ++i) {
      const Vec3 d = latlong_to_direction(Vec2((i + 0.5f) / map.width, (j + 0.5f) / map.height));
      if (angle_between(d.cast<double>(), -Vec3d::UnitZ()) < degrees * kPiD / 180.0) map.set(i, j, RGB::Zero());
    }
  return map;
}

TEST(EnvironmentFormats, AngularMapMatchesDebevecsDefinition) {
  // Debevec's light-probe gallery: direction (Dx, Dy, Dz) is at (u, v) = (Dx, Dy) r with
  // r = acos(Dz) / (pi sqrt(Dx^2 + Dy^2)), u right and v up in [-1, 1].
  for (const Vec3d& d : {Vec3d(0.3, 0.4, 0.5), Vec3d(-0.7, 0.1, -0.6), Vec3d(0.05, -0.9, 0.2), Vec3d(1, 0, 0)}) {
    const Vec3d n = d.normalized();
    const double r = std::acos(n.z()) / (kPiD * std::hypot(n.x(), n.y()));
    const Vec2d expected(n.x() * r, n.y() * r);
    EXPECT_LT((probe_position(kAngular, d) - expected).norm(), 1e-12) << d.transpose();
    EXPECT_LT(angle_between(probe_direction(kAngular, expected), n), 1e-9) << d.transpose();
  }
  // The centre looks back along +Z, the rim is -Z, half way out is the horizon.
  EXPECT_LT(angle_between(probe_direction(kAngular, {0, 0}), Vec3d::UnitZ()), 1e-12);
  EXPECT_LT(angle_between(probe_direction(kAngular, {0, 1}), -Vec3d::UnitZ()), 1e-7);
  EXPECT_LT(angle_between(probe_direction(kAngular, {0, 0.5}), Vec3d::UnitY()), 1e-12);
  EXPECT_LT(angle_between(probe_direction(kAngular, {-0.5, 0}), -Vec3d::UnitX()), 1e-12);
}

TEST(EnvironmentFormats, MirrorBallMatchesAReflectedOrthographicRay) {
  // An independent construction: a ray along -Z at (x, y) reflected off the unit ball.
  const MirrorBall ball{Vec3d::Zero(), 1.0};
  for (const Vec2d& p : {Vec2d(0, 0), Vec2d(0.3, -0.2), Vec2d(-0.6, 0.7), Vec2d(0.95, 0.1), Vec2d(0, -0.999)}) {
    const auto hit = reflect_off_ball(Vec3d(p.x(), p.y(), 10.0), -Vec3d::UnitZ(), ball);
    ASSERT_TRUE(hit.has_value());
    EXPECT_LT(angle_between(probe_direction(kMirrorBall, p), hit->direction), 1e-9) << p.transpose();
    EXPECT_LT((probe_position(kMirrorBall, hit->direction) - p).norm(), 1e-6) << p.transpose();
  }
  // At radius sin(45 deg) the ball reflects the horizon (+X to the right).
  EXPECT_LT(angle_between(probe_direction(kMirrorBall, {std::sqrt(0.5), 0}), Vec3d::UnitX()), 1e-12);
}

TEST(EnvironmentFormats, BrightTexelLandsInTheSameDirection) {
  TemporaryDirectory dir;
  const int width = 128, height = 64;
  // One texel 50 degrees from +Z, one 120 degrees (still clear of the ball's blind spot).
  for (const auto& [i, j] : {std::pair{80, 24}, std::pair{20, 40}}) {
    Image map(width, height);
    map.set(i, j, RGB(1000.0f, 500.0f, 250.0f));
    const Vec3d truth = latlong_to_direction(Vec2((i + 0.5f) / width, (j + 0.5f) / height)).cast<double>();
    const double texel = kPiD / height;
    for (EnvironmentFormat format : {kAngular, kMirrorBall}) {
      const Environment back = round_trip(dir, map, format, 128, "probe.exr");
      EXPECT_EQ(back.map().width, 256);
      EXPECT_EQ(back.map().height, 128);
      const double error = angle_between(bright_direction(back.map()), truth);
      std::printf("%s texel (%d, %d): %.3f texels off\n", environment_format_name(format), i, j, error / texel);
      EXPECT_LT(error, texel) << environment_format_name(format) << " texel (" << i << ", " << j << ")";
    }
  }
}

TEST(EnvironmentFormats, ShOfTheReadBackMatchesTheOriginal) {
  TemporaryDirectory dir;
  const Image office = make_procedural_environment("office", 256, 128);
  const Environment original(office, {});
  const Environment angular = round_trip(dir, office, kAngular, 256, "angular.exr");
  const double angular_error = sh_difference(original.sh(4), angular.sh(4));
  // The ball's blind spot: directions within 20 degrees of -Z (the last 1.5 pixels of a
  // 256-pixel ball reach 17.6 degrees) left out of both.
  const Environment ball = round_trip(dir, office, kMirrorBall, 256, "ball.exr");
  const Environment original_seen(without_blind_spot(office, 20.0), {});
  const Environment ball_seen(without_blind_spot(ball.map(), 20.0), {});
  const double ball_error = sh_difference(original_seen.sh(4), ball_seen.sh(4));
  const double ball_whole = sh_difference(original.sh(4), ball.sh(4));
  std::printf(
      "SH lmax 4, largest difference / L00: angular %.4f, mirror ball %.4f outside the blind spot (%.4f "
      "with it)\n",
      angular_error, ball_error, ball_whole);
  EXPECT_LT(angular_error, 0.01);
  EXPECT_LT(ball_error, 0.01);
}

TEST(EnvironmentFormats, RealProbeRoundTrip) {
  GLAZE_REQUIRE_ENVMAP(grace, "grace_latlong.exr");
  TemporaryDirectory dir;
  const Environment original = Environment::load(grace.string());
  const Environment angular = round_trip(dir, original.map(), kAngular, 512, "grace_angular.exr");
  const double error = sh_difference(original.sh(4), angular.sh(4));
  std::printf("Grace cathedral, angular 512: SH lmax 4 largest difference / L00 %.4f\n", error);
  EXPECT_LT(error, 0.01);
}

TEST(EnvironmentFormats, RecognisedFromTheImage) {
  CapturedWarnings warnings;
  Image latlong(64, 32);
  std::fill(latlong.pixels.begin(), latlong.pixels.end(), 1.0f);
  EXPECT_EQ(recognise_environment_format(latlong, "a.exr"), EnvironmentFormat::latlong);
  EXPECT_TRUE(warnings.messages.empty());

  const Image probe = latlong_to_probe(latlong, kAngular, 32);
  EXPECT_EQ(recognise_environment_format(probe, "p.exr"), kAngular);
  ASSERT_EQ(warnings.messages.size(), 1u);
  EXPECT_NE(warnings.messages[0].find("read as an angular map"), std::string::npos) << warnings.messages[0];
  EXPECT_NE(warnings.messages[0].find("mirror_ball"), std::string::npos) << warnings.messages[0];

  Image square(32, 32);
  std::fill(square.pixels.begin(), square.pixels.end(), 1.0f);
  try {
    recognise_environment_format(square, "s.exr");
    ADD_FAILURE() << "a square image with light in its corners was read";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("give its format"), std::string::npos) << error.what();
  }
  // A given format that cannot be: a probe must be square.
  EXPECT_THROW(probe_to_latlong(latlong, kAngular, "a.exr"), Error);
  EXPECT_THROW(parse_environment_format("cube", "--env-format"), Error);
}

// A copy of red_sphere_office.gltf lit by `environment` (scene.extras.glaze.environment).
std::string scene_with(const TemporaryDirectory& dir, const nlohmann::json& environment, const std::string& name) {
  nlohmann::json scene = read_json(testing::scenes_dir() + "red_sphere_office.gltf");
  scene["scenes"][0]["extras"]["glaze"]["environment"] = environment;
  const std::string file = dir.file(name);
  std::ofstream(file) << scene.dump();
  return file;
}

// The office as a lat-long file and, through `glaze env-convert`, as an angular map.
void write_office(const TemporaryDirectory& dir) {
  write_image(dir.file("office.exr"), make_procedural_environment("office", 256, 128));
  const auto run = testing::run_glaze(
      "env-convert " + dir.file("office.exr") + " --to angular --out " + dir.file("office_angular.exr"), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(image_size(dir.file("office_angular.exr")).width, 256);
}

TEST(EnvironmentFormats, SceneWithAnAngularFileRendersAsWithTheLatLong) {
  TemporaryDirectory dir;
  write_office(dir);
  const std::string options = " --integrator sh --ss 1 --lmax 8 --res 48x48";
  const std::string latlong = scene_with(dir, {{"file", "office.exr"}}, "latlong.gltf");
  const std::string angular = scene_with(dir, {{"file", "office_angular.exr"}, {"format", "angular"}}, "angular.gltf");
  for (const auto& [scene, out] :
       {std::pair{latlong, "latlong_render.exr"}, std::pair{angular, "angular_render.exr"}}) {
    const auto run = testing::run_glaze("render " + scene + " --out " + dir.file(out) + options, dir);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    EXPECT_EQ(run.err.find("angular map"), std::string::npos) << "the format was given: " << run.err;
  }
  const Image a = read_image(dir.file("latlong_render.exr")), b = read_image(dir.file("angular_render.exr"));
  double sum_a = 0.0, sum_diff = 0.0;
  for (size_t k = 0; k < a.pixels.size(); ++k) {
    sum_a += a.pixels[k];
    sum_diff += std::abs(a.pixels[k] - b.pixels[k]);
  }
  std::printf("render under the angular file: mean |difference| %.4f of the mean\n", sum_diff / sum_a);
  EXPECT_LT(sum_diff / sum_a, 0.01);
}

TEST(EnvironmentFormats, CaptureSetWithAnAngularFileFitsAsWithTheLatLong) {
  TemporaryDirectory dir;
  write_office(dir);
  const std::string scene = scene_with(dir, {{"file", "office.exr"}}, "latlong.gltf");
  const auto render = testing::run_glaze(
      "render " + scene + " --captures " + dir.file("set") + " --integrator sh --ss 1 --res 64x64", dir);
  ASSERT_EQ(render.exit_code, 0) << render.err;
  const std::string transforms = dir.file("set/transforms.json");
  auto fit = [&](const nlohmann::json& environment, const std::string& out, std::string* err) {
    nlohmann::json set = read_json(transforms);
    set["environment"] = environment;
    std::ofstream(transforms) << set.dump();
    const auto run =
        testing::run_glaze("invert-fit " + transforms + " --mode material --lmax 8 --out " + dir.file(out), dir);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    *err = run.err;
    return read_json(dir.file(out + "/fit.json"));
  };
  std::string err;
  const nlohmann::json latlong = fit({{"file", dir.file("office.exr")}}, "fit_latlong", &err);
  // No format: recognised as an angular map, with a warning.
  const nlohmann::json angular = fit({{"file", dir.file("office_angular.exr")}}, "fit_angular", &err);
  EXPECT_NE(err.find("read as an angular map"), std::string::npos) << err;
  std::printf("R0 %.5f vs %.5f\n", angular["R0"].get<double>(), latlong["R0"].get<double>());
  EXPECT_NEAR(angular["R0"].get<double>(), latlong["R0"].get<double>(), 0.003);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(angular["Rd"][c].get<double>(), latlong["Rd"][c].get<double>(), 0.01);
  // The format key is kept by the capture set's reader and the wrong one is refused.
  const nlohmann::json given =
      fit({{"file", dir.file("office_angular.exr")}, {"format", "angular"}}, "fit_given", &err);
  EXPECT_EQ(err.find("read as an angular map"), std::string::npos) << err;
  EXPECT_DOUBLE_EQ(given["R0"].get<double>(), angular["R0"].get<double>());
}

// `--env-format` on the command line, and the errors a wrong or missing format gives.
TEST(EnvironmentFormats, CommandLineFormat) {
  TemporaryDirectory dir;
  write_office(dir);
  auto sh = [&](const std::string& arguments) {
    const auto run = testing::run_glaze("sh " + arguments + " --lmax 2", dir);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return nlohmann::json::parse(run.out)["L_lm"];
  };
  const nlohmann::json latlong = sh(dir.file("office.exr"));
  const nlohmann::json angular = sh(dir.file("office_angular.exr") + " --env-format angular");
  for (size_t k = 0; k < latlong.size(); ++k)
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(angular[k][c].get<double>(), latlong[k][c].get<double>(), 0.01 * latlong[0][c].get<double>());
  testing::expect_clear_failure(testing::run_glaze("sh " + dir.file("office.exr") + " --env-format mirror_ball", dir),
                                "must be a square image");
  Image square(16, 16);
  std::fill(square.pixels.begin(), square.pixels.end(), 1.0f);
  write_image(dir.file("square.exr"), square);
  testing::expect_clear_failure(
      testing::run_glaze("render " + testing::scenes_dir() + "red_sphere_office.gltf --env " + dir.file("square.exr") +
                             " --integrator sh --res 8x8 --out " + dir.file("x.exr"),
                         dir),
      "--env-format");
}

}  // namespace
}  // namespace glaze
