// photo_shoot_test.cpp: the photographs front end from end to end. A shoot simulated by
// glaze (shoot_simulator.h: 3 views, 7 exposures 2 EV apart, 8-bit with shot and read
// noise, a distorted lens, mirror-ball photos) goes through `glaze captures` and
// `glaze invert-fit`, and what comes out is held against the simulation's truth: the
// sphere, the probe, the ball's reflectance and the material.
#include "inverse/photos/shoot_simulator.h"
#include "renderer/capture_set.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>

namespace glaze {
namespace {

using testing::read_json;
using testing::run_glaze;
using testing::TemporaryDirectory;

// A 3-view shoot of the sphere of `scene` (scaled to 5 cm) under `environment` through a
// barrel-distorted lens, 640x480. The board is 1.5 sphere diameters along a row (15 mm
// squares): framed to fill the picture, it leaves the sphere about 90 px across in
// radius, which the probe needs (docs/notes/light-probe.md: its error grows as the
// ball's image shrinks). The board photos are lit by a uniform light, which 4 samples a
// pixel render with little noise besides the camera's own. `calibrate`: the intrinsics
// and lens come from 8 calibration photos, else shoot.json gives them.
ShootSimulation simulated_shoot(const TemporaryDirectory& dir, const std::string& scene,
                                const std::optional<std::string>& environment, bool calibrate) {
  ShootSimulation shoot;
  shoot.scene = testing::scenes_dir() + scene;
  if (environment) shoot.environment = EnvironmentSpec{*environment, {}};
  shoot.out = dir.path() / "shoot";
  shoot.width = 640;
  shoot.height = 480;
  shoot.lens = LensDistortion{LensDistortion::Model::opencv, -0.12, 0.03, 0.0, 0.0, 0.0005, -0.0003};
  shoot.board.square = 0.015;
  shoot.board_spp = 4;
  shoot.calibration_photos = calibrate ? 8 : 0;
  shoot.known_intrinsics = !calibrate;
  shoot.seed = 7;
  return shoot;
}

// Relative RMSE of `probe` against `truth` times `unit` on a 64x32 lat-long grid of world
// directions, over the cells that `coverage` (the probe's mask, in the probe's frame)
// covers wholly; each cell the mean of 4 x 4 directions.
double probe_error(const Environment& probe, const Environment& coverage, const Environment& truth, const RGB& unit,
                   int* cells) {
  constexpr int kWidth = 64, kHeight = 32, kSub = 4;
  double error = 0.0, norm = 0.0, cross = 0.0, probe_norm = 0.0;
  *cells = 0;
  for (int j = 0; j < kHeight; ++j)
    for (int i = 0; i < kWidth; ++i) {
      RGBd p = RGBd::Zero(), t = RGBd::Zero();
      bool covered = true;
      for (int b = 0; b < kSub; ++b)
        for (int a = 0; a < kSub; ++a) {
          const double u = (i + (a + 0.5) / kSub) / kWidth, v = (j + (b + 0.5) / kSub) / kHeight;
          const double phi = 2 * kPiD * u, theta = kPiD * v;
          const Vec3 w(float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)),
                       float(-std::sin(theta) * std::cos(phi)));
          covered = covered && coverage.eval(w)[0] > 0.5f;
          p += probe.eval(w).cast<double>();
          t += (truth.eval(w) * unit).cast<double>();
        }
      if (!covered) continue;
      ++*cells;
      error += (p - t).square().sum();
      norm += t.square().sum();
      cross += (p * t).sum();
      probe_norm += p.square().sum();
    }
  const double scale = cross / norm;
  std::printf("probe / truth: best scale %.4f, relative RMSE after it %.4f\n", scale,
              std::sqrt(std::max(0.0, probe_norm - 2 * scale * cross + scale * scale * norm) / (scale * scale * norm)));
  return std::sqrt(error / norm);
}

// The environment of a capture set's transforms.json, and the coverage mask beside it, in
// the world frame.
struct CapturedProbe {
  Environment map, coverage;
};
CapturedProbe captured_probe(const std::string& folder) {
  const CaptureSet captures = read_transforms(folder);
  EXPECT_TRUE(captures.environment);
  const EnvironmentOptions& options = captures.environment->options;
  return {Environment::load(captures.environment->file, options),
          Environment::load(folder + "/environment_coverage.png", options)};
}

// Everything the issue asks of one simulated shoot.
void expect_shoot_recovered(const std::string& scene, const std::optional<std::string>& environment, bool calibrate) {
  TemporaryDirectory dir;
  const SimulatedShoot truth = simulate_shoot(simulated_shoot(dir, scene, environment, calibrate));

  // The chain with the ball's reflectance given.
  const testing::CommandResult run = run_glaze("captures " + dir.file("shoot") + " --out " + dir.file("captures"), dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json report = read_json(dir.file("captures/captures_report.json"));
  const nlohmann::json& object = report["object"];
  const Vec3d center(object["center"][0].get<double>(), object["center"][1].get<double>(),
                     object["center"][2].get<double>());
  EXPECT_LT((center - truth.sphere_center).norm(), 0.5e-3) << object.dump();
  EXPECT_NEAR(object["radius"].get<double>() / truth.sphere_radius, 1.0, 0.003);

  const CapturedProbe probe = captured_probe(dir.file("captures"));
  const Environment true_lighting = make_environment(truth.environment.source, truth.environment.options,
                                                     truth.environment.width, truth.environment.height);
  int cells = 0;
  const double probe_rmse = probe_error(probe.map, probe.coverage, true_lighting, truth.hdr_unit, &cells);
  EXPECT_LT(probe_rmse, 0.05);
  EXPECT_GT(cells, 64 * 32 / 2);

  // The material under the probe's lighting.
  const testing::CommandResult material =
      run_glaze("invert-fit " + dir.file("captures") + " --mode material --out " + dir.file("material"), dir);
  ASSERT_EQ(material.exit_code, 0) << material.err;
  const nlohmann::json fit = read_json(dir.file("material/fit.json"));
  EXPECT_NEAR(fit["R0"].get<double>(), truth.material.R0(), 0.003);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(fit["Rd"][c].get<double>(), truth.material.Rd()[c], 0.01) << c;

  // The chain again without the reflectance: estimated by the joint fit, whose material
  // must meet twice the bounds that noise-free capture sets meet (R0 0.001, Rd 0.003).
  nlohmann::json shoot = read_json(dir.file("shoot/shoot.json"));
  shoot["probe"].erase("reflectance");
  std::ofstream(dir.file("shoot/shoot.json")) << shoot.dump(2);
  const testing::CommandResult estimate =
      run_glaze("captures " + dir.file("shoot") + " --out " + dir.file("estimate"), dir);
  ASSERT_EQ(estimate.exit_code, 0) << estimate.err;
  const nlohmann::json estimated = read_json(dir.file("estimate/captures_report.json"))["probe"];
  for (int c = 0; c < 3; ++c)
    EXPECT_NEAR(estimated["reflectance"][c].get<double>() / truth.reflectance, 1.0, 0.03) << estimated.dump();
  const nlohmann::json& joint = estimated["joint_fit"];
  EXPECT_NEAR(joint["R0"].get<double>(), truth.material.R0(), 0.002);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(joint["Rd"][c].get<double>(), truth.material.Rd()[c], 0.006) << c;
  std::printf(
      "%s: centre off by %.3f mm, radius by %.3f%%, probe RMSE %.2f%% over %d cells, material R0 %+.4f, "
      "reflectance %.4f (true %.4f), joint R0 %+.4f\n",
      scene.c_str(), 1e3 * (center - truth.sphere_center).norm(),
      100 * (object["radius"].get<double>() / truth.sphere_radius - 1), 100 * probe_rmse, cells,
      fit["R0"].get<double>() - truth.material.R0(), estimated["reflectance"][1].get<double>(), truth.reflectance,
      joint["R0"].get<double>() - truth.material.R0());
}

TEST(PhotoShootAcceptance, RedSphereInTheOffice) {
  expect_shoot_recovered("red_sphere_office.gltf", std::nullopt, true);
}
TEST(PhotoShootAcceptance, WhiteSphereInTheOffice) {
  expect_shoot_recovered("white_sphere_office.gltf", std::nullopt, false);
}
TEST(PhotoShootAcceptance, RedSphereUnderARealMap) {
  GLAZE_REQUIRE_ENVMAP(map, "lebombo_1k.hdr");
  expect_shoot_recovered("red_sphere_office.gltf", map.string(), false);
}
TEST(PhotoShootAcceptance, WhiteSphereUnderARealMap) {
  GLAZE_REQUIRE_ENVMAP(map, "lebombo_1k.hdr");
  expect_shoot_recovered("white_sphere_office.gltf", map.string(), false);
}

}  // namespace
}  // namespace glaze
