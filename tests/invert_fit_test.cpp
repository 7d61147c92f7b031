// Round trips of `glaze invert-fit` under known lighting (paper section 5): captures of
// the paper's spheres rendered by glaze (the sh integrator: noise-free; the path tracer:
// the model's independent check), fitted, and compared with the materials they were
// rendered with. Also noise, misregistration, parameters at their bounds and bad input.
#include "renderer/image.h"
#include "renderer/rng.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

namespace glaze {
namespace {

using testing::CommandResult;
using testing::TemporaryDirectory;

const std::string kScenes = std::string(GLAZE_SOURCE_DIR) + "/scenes/";

CommandResult glaze(const std::string& arguments, const TemporaryDirectory& dir) { return testing::run_glaze(arguments, dir); }

nlohmann::json read_json(const std::string& path) {
  std::ifstream file(path);
  return nlohmann::json::parse(file);
}

// Renders SCENE's capture set into dir/NAME with the given renderer options.
std::string captures(const TemporaryDirectory& dir, const std::string& scene, const std::string& name,
                     const std::string& options) {
  const std::string folder = dir.file(name);
  const CommandResult run = glaze("render " + kScenes + scene + " --captures " + folder + " " + options, dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return folder;
}

nlohmann::json fit(const TemporaryDirectory& dir, const std::string& folder, const std::string& options) {
  const CommandResult run = glaze("invert-fit " + folder + "/transforms.json --out " + folder + "/fit " + options, dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  std::printf("%s", run.out.c_str());
  return read_json(folder + "/fit/fit.json");
}

void expect_material(const nlohmann::json& result, double R0_tolerance, double Rd_tolerance) {
  const nlohmann::json& truth = result["reference_material"];
  EXPECT_NEAR(result["R0"].get<double>(), truth["R0"].get<double>(), R0_tolerance);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(result["Rd"][c].get<double>(), truth["Rd"][c].get<double>(), Rd_tolerance) << "channel " << c;
  EXPECT_TRUE(result["converged"].get<bool>()) << result["solver"];
}

TEST(InvertFit, ShCapturesRecoverTheMaterialExactly) {
  TemporaryDirectory dir;
  for (const char* scene : {"red_sphere_office.gltf", "white_sphere_blue_room.gltf"}) {
    SCOPED_TRACE(scene);
    const std::string folder = captures(dir, scene, std::string("sh_") + scene, "--integrator sh --ss 1 --lmax 16 --res 96x96");
    const nlohmann::json result = fit(dir, folder, "--mode material --lmax 16 --pixel-footprint 1");
    expect_material(result, 1e-4, 1e-4);
    EXPECT_LT(result["rms"].get<double>(), 1e-4);
  }
}

void path_traced_round_trip(const std::string& scene, const std::string& environment) {
  TemporaryDirectory dir;
  const std::string folder = captures(dir, scene, "path", "--spp 256 --res 128x128 " + environment);
  expect_material(fit(dir, folder, "--mode material"), 0.002, 0.005);
}

TEST(InvertFit, PathTracedCapturesRedOffice) { path_traced_round_trip("red_sphere_office.gltf", ""); }
TEST(InvertFit, PathTracedCapturesWhiteOffice) { path_traced_round_trip("white_sphere_office.gltf", ""); }
TEST(InvertFit, PathTracedCapturesRedBlueRoom) { path_traced_round_trip("red_sphere_blue_room.gltf", ""); }
TEST(InvertFit, PathTracedCapturesWhiteBlueRoom) { path_traced_round_trip("white_sphere_blue_room.gltf", ""); }

TEST(InvertFit, PathTracedCapturesUnderRealMaps) {
  for (const char* name : {"st_fagans_interior_1k.hdr", "lebombo_1k.hdr"}) {
    GLAZE_REQUIRE_ENVMAP(map, name);
    SCOPED_TRACE(name);
    for (const char* scene : {"red_sphere_office.gltf", "white_sphere_office.gltf"}) {
      SCOPED_TRACE(scene);
      path_traced_round_trip(scene, "--env " + map.string());
    }
  }
}

}  // namespace
}  // namespace glaze
