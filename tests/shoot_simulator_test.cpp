// shoot_simulator_test.cpp: the photo-shoot simulator (inverse/photos/shoot_simulator.h)
// writes a shoot that glaze's own front end reads back to the truth it records: the
// registration recovers the cameras, the HDR merge the radiance times the recorded unit,
// and the mirror ball shows the environment times its reflectance, and the camera.
#include "inverse/photos/bracket.h"
#include "inverse/photos/camera_response.h"
#include "inverse/photos/hdr_merge.h"
#include "inverse/photos/registration.h"
#include "inverse/photos/shoot_simulator.h"
#include "renderer/procedural_environment.h"
#include "test_support.h"

#include <nlohmann/json.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <fstream>
#include <iterator>

namespace glaze::testing {
namespace {

using nlohmann::json;

ShootSimulation small_shoot(const TemporaryDirectory& dir, const std::string& name) {
  ShootSimulation options;
  options.scene = scenes_dir() + "red_sphere_office.gltf";
  options.out = dir.path() / name;
  options.width = 160;
  options.height = 120;
  options.board_supersampling = 2;
  options.calibration_photos = 0;
  options.exposures = 5;
  options.lens = {LensDistortion::Model::opencv, -0.1, 0.02, 0.0, 0.0, 0.0, 0.0};
  return options;
}

// The folder holds what hdr-merge and register read, and the truth.
TEST(ShootSimulator, WritesTheShootLayout) {
  TemporaryDirectory dir;
  // The board photos come from the sh integrator, exact for a flat board under a uniform
  // light, which must not warn that it leaves out the scene's occlusion.
  ::testing::internal::CaptureStderr();
  const SimulatedShoot shoot = simulate_shoot(small_shoot(dir, "shoot"));
  const std::string warnings = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(warnings.find("single convex object"), std::string::npos) << warnings;
  for (const char* folder : {"view_000", "view_001", "view_002", "probe_000", "probe_001", "probe_002"}) {
    EXPECT_TRUE(std::filesystem::exists(shoot.folder / folder / "board.png")) << folder;
    const Bracket bracket = find_bracket(shoot.folder / folder);
    ASSERT_EQ(bracket.exposures.size(), 5u) << folder;
    // 2 EV apart: each exposure 4 times the last.
    for (size_t k = 1; k < 5; ++k)
      EXPECT_NEAR(bracket.exposures[k].exposure / bracket.exposures[k - 1].exposure, 4.0, 1e-9);
  }
  const json description = json::parse(std::ifstream(shoot.folder / "shoot.json"));
  EXPECT_EQ(description.at("object").at("type"), "sphere");
  EXPECT_FALSE(description.contains("camera"));
  EXPECT_EQ(description.at("probe").at("reflectance").get<double>(), 0.6);
  const json truth = json::parse(std::ifstream(shoot.folder / "simulation.json"));
  EXPECT_NEAR(truth.at("object").at("radius").get<double>(), 0.05, 1e-12);
  // The sphere stands on the table (z = 0) and the ball where it stood.
  EXPECT_NEAR(truth.at("object").at("center")[2].get<double>(), 0.05, 1e-12);
  EXPECT_NEAR(truth.at("probe").at("center")[0].get<double>(), truth.at("object").at("center")[0].get<double>(), 1e-12);
  EXPECT_EQ(truth.at("views").size(), 3u);
  EXPECT_EQ(truth.at("environment").at("procedural"), "office");
  // The board's up (+z) is the scene's +Y, which the map's +Y was: to_world takes +Y to +z.
  const json& to_world = truth.at("environment").at("to_world");
  EXPECT_NEAR(to_world[2][1].get<double>(), 1.0, 1e-6);
  // A second shoot into the same folder is refused.
  EXPECT_THROW(simulate_shoot(small_shoot(dir, "shoot")), Error);
}

// register_shoot on a simulated 640 x 480 shoot (8 calibration photos; 320 x 240 is too
// coarse for the board seen at 30 degrees) recovers the intrinsics and every view's pose.
TEST(ShootSimulator, RegistrationRecoversTheCameras) {
  TemporaryDirectory dir;
  ShootSimulation options = small_shoot(dir, "shoot");
  options.width = 640;
  options.height = 480;
  options.calibration_photos = 8;
  options.probe = false;
  options.exposures = 2;
  const SimulatedShoot shoot = simulate_shoot(options);
  const glaze::Registration registration = register_shoot(read_shoot(shoot.folder));
  const PinholeCamera& truth = shoot.views.front().camera;
  std::printf("fl %.3f (true %.3f), cx %.3f (%.3f), cy %.3f (%.3f), k1 %.4f (%.4f)\n", registration.camera.fl_x,
              truth.fl_x, registration.camera.cx, truth.cx, registration.camera.cy, truth.cy, registration.camera.k1,
              truth.distortion.k1);
  EXPECT_NEAR(registration.camera.fl_x, truth.fl_x, 0.01 * truth.fl_x);
  EXPECT_NEAR(registration.camera.cx, truth.cx, 3.0);
  EXPECT_NEAR(registration.camera.cy, truth.cy, 3.0);
  ASSERT_EQ(registration.views.size(), shoot.views.size());
  for (size_t v = 0; v < shoot.views.size(); ++v) {
    const Eigen::Matrix4d expected = shoot.views[v].camera.camera_to_world.matrix().cast<double>();
    const Eigen::Matrix4d& found = registration.views[v].camera_to_world;
    const double degrees =
        Eigen::AngleAxisd(Eigen::Matrix3d(found.topLeftCorner<3, 3>().transpose() * expected.topLeftCorner<3, 3>()))
            .angle() *
        180.0 / M_PI;
    const double millimetres = 1000.0 * (found.col(3) - expected.col(3)).norm();
    std::printf("%s: pose off by %.4f degrees and %.3f mm\n", shoot.views[v].name.c_str(), degrees, millimetres);
    EXPECT_LT(degrees, 0.25);  // 0.04 to 0.13 seen: calibrated from 11 photos at 30 degrees
    EXPECT_LT(millimetres, 2.0);
  }
}

// hdr-merge's chain (the response recovered from the brackets, the merge) gives the true
// radiance times simulation.json's unit. Without noise the median relative error is
// within 1% (the recovered response's accuracy); with shot and read noise each pixel
// scatters by a few percent but the median ratio stays within 2% of 1.
struct MergeError {
  double median_ratio, median_error;
};
MergeError merge_error(bool noise) {
  TemporaryDirectory dir;
  ShootSimulation options = small_shoot(dir, "shoot");
  options.exposures = 7;
  options.keep_radiance = true;
  options.camera.noise = noise;
  const SimulatedShoot shoot = simulate_shoot(options);
  std::vector<BracketPhotos> photos;
  std::vector<ResponseSamples> samples;
  for (const Bracket& bracket : find_brackets(shoot.folder)) {
    photos.push_back(read_bracket(bracket));
    samples.push_back(sample_bracket(photos.back()));
  }
  const CameraResponse response = recover_response(samples);
  EXPECT_EQ(photos.size(), shoot.radiance.size());
  std::vector<double> ratios, errors;
  for (size_t b = 0; b < photos.size(); ++b) {
    const HdrMerge merged = merge_bracket(photos[b], response);
    const Image& truth = shoot.radiance[b];
    for (size_t p = 0; p < merged.alpha.size(); ++p)
      for (int c = 0; c < 3; ++c) {
        const double expected = shoot.hdr_unit[c] * truth.pixels[3 * p + c];
        if (merged.alpha[p] > 0 && expected > 0) ratios.push_back(merged.radiance.pixels[3 * p + c] / expected);
      }
  }
  for (const double ratio : ratios) errors.push_back(std::abs(ratio - 1.0));
  std::nth_element(ratios.begin(), ratios.begin() + ratios.size() / 2, ratios.end());
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  const MergeError result{ratios[ratios.size() / 2], errors[errors.size() / 2]};
  std::printf("noise %s: merged / (unit x truth) median %.4f, median error %.4f over %zu values\n",
              noise ? "on" : "off", result.median_ratio, result.median_error, errors.size());
  return result;
}

TEST(ShootSimulator, MergedBracketIsTheRadianceTimesTheUnit) {
  const MergeError clean = merge_error(false);
  EXPECT_LT(clean.median_error, 0.01);
  const MergeError noisy = merge_error(true);
  EXPECT_NEAR(noisy.median_ratio, 1.0, 0.02);
  EXPECT_LT(noisy.median_error, 0.06);
}

// The ball's photo under a constant environment (radiance 1): the reflectance where a ray
// meets the ball and reflects to the room, the dark camera where it reflects back to it
// (the ball's centre pixel), 1 where it misses.
TEST(ShootSimulator, ProbeShowsReflectanceAndTheCamera) {
  const Environment environment(make_procedural_environment("constant", 16, 8), {});
  const Vec3d ball(0.1, 0.05, 0.05);
  const Vec3 eye(0.1f + 0.4f, 0.05f, 0.3f);
  // An odd film: the centre pixel's one ray (supersampling 1) points at the ball's centre.
  PinholeCamera camera =
      PinholeCamera::from_vertical_fov("probe", look_at(eye, ball.cast<float>(), Vec3::UnitZ()), 0.3f, 63, 47);
  camera.distortion = {LensDistortion::Model::opencv, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0};
  const Image image = render_probe(environment, camera, ball, 0.05, 0.6, 1);
  const auto at = [&](int x, int y) { return image.pixels[3 * (size_t(y) * image.width + x)]; };
  // Head-on: the ray comes back to the camera's body, the dark grey of the room's mean (1).
  EXPECT_NEAR(at(31, 23), kOccluderAlbedo, 1e-5);
  EXPECT_NEAR(at(0, 0), 1.0, 1e-5);  // a corner misses the ball
  // Below the centre, on the ball: the reflected ray goes down to the table at x > eye.x,
  // past the tripod; above it, towards the ceiling: both see the room at 0.6.
  EXPECT_NEAR(at(31, 30), 0.6, 1e-5);
  EXPECT_NEAR(at(31, 16), 0.6, 1e-5);
  // Between them, rays reflected down the tripod's line: some pixel of the column below
  // the centre sees it.
  int tripod = 0;
  for (int y = 24; y < 40; ++y) tripod += std::abs(at(31, y) - kOccluderAlbedo) < 1e-5;
  EXPECT_GT(tripod, 0);
}

// The photos depend on the seed, not on the thread count.
TEST(ShootSimulator, DeterministicForAnyThreadCount) {
  TemporaryDirectory dir;
  ShootSimulation one = small_shoot(dir, "one");
  one.width = 96;
  one.height = 72;
  one.threads = 1;
  ShootSimulation two = one;
  two.out = dir.path() / "two";
  two.threads = 3;
  simulate_shoot(one);
  simulate_shoot(two);
  const auto bytes = [](const std::filesystem::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  for (const char* file : {"view_000/board.png", "view_001/bracket_2.png", "probe_002/bracket_4.png"})
    EXPECT_EQ(bytes(one.out / file), bytes(two.out / file)) << file;
}

}  // namespace
}  // namespace glaze::testing
