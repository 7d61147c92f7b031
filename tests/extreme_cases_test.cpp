// Round trips of `glaze invert-fit` on extreme cases (the issue "extreme cases as
// tests"): a nearly black sphere (Rd 0.02), a white one with Rd = 1 and R0 at its bound
// 0 or at 0.2, lighting dominated by one small source (the studio map), and captures
// with 5% noise. Every fit must give finite numbers (no NaN, which fit.json would hold
// as null), and estimates within the stated bounds or a clear warning that the data do
// not constrain them. The bounds: sh captures (noise-free) R0 and Rd within 1e-4;
// path-traced captures R0 within 0.002 and Rd within 0.005 at 256 spp; 5% noise within
// 0.01; --mode lighting L_lm (l <= 2) within 3% of L00. Small images (96x96 to
// 256x256), so that the file runs in seconds (and under ASan in CI).
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <tuple>

namespace glaze {
namespace {

using testing::add_multiplicative_noise;
using testing::CommandResult;
using testing::expect_all_finite;
using testing::read_json;
using testing::run_glaze;
using testing::sphere_scene_file;
using testing::TemporaryDirectory;

const std::string kScenes = testing::scenes_dir();

// Renders `scene` (a path) as a capture set into dir/NAME with the given options.
std::string captures(const TemporaryDirectory& dir, const std::string& scene, const std::string& name,
                     const std::string& options) {
  const std::string folder = dir.file(name);
  const CommandResult run = run_glaze("render " + scene + " --captures " + folder + " " + options, dir);
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return folder;
}

struct Fit {
  nlohmann::json result;  // fit.json
  std::string err;        // what glaze printed to stderr (its warnings)
};

// invert-fit on the capture set in `folder`: exits 0, and fit.json holds only finite numbers.
Fit fit(const TemporaryDirectory& dir, const std::string& folder, const std::string& options) {
  const CommandResult run =
      run_glaze("invert-fit " + folder + "/transforms.json --out " + folder + "/fit " + options, dir);
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 0) << run.err;
  std::printf("%s%s", run.out.c_str(), run.err.c_str());
  Fit result{read_json(folder + "/fit/fit.json"), run.err};
  // The one null glaze writes on purpose: a map error over a grid with no wholly
  // covered cell (nothing to compare), which says so with cells = 0.
  nlohmann::json checked = result.result;
  if (checked.contains("reference_map_error"))
    for (auto& [grid, entry] : checked["reference_map_error"].items())
      if (entry["relative_rmse"].is_null() && entry["cells"].get<int>() == 0) entry["relative_rmse"] = 0.0;
  expect_all_finite(checked, "fit.json");
  return result;
}

// R0 and Rd against the set's own material: within the tolerances, or (an Rd channel)
// reported as not constrained, with the warning that says so. Prints the numbers.
void expect_material(const std::string& label, const Fit& fit, double R0_tolerance, double Rd_tolerance) {
  const nlohmann::json& result = fit.result;
  const nlohmann::json& truth = result["reference_material"];
  std::printf("%s: R0 %.5f (true %.5f), Rd %.5f %.5f %.5f (true %.5f %.5f %.5f)\n", label.c_str(),
              result["R0"].get<double>(), truth["R0"].get<double>(), result["Rd"][0].get<double>(),
              result["Rd"][1].get<double>(), result["Rd"][2].get<double>(), truth["Rd"][0].get<double>(),
              truth["Rd"][1].get<double>(), truth["Rd"][2].get<double>());
  EXPECT_NEAR(result["R0"].get<double>(), truth["R0"].get<double>(), R0_tolerance) << label;
  for (int c = 0; c < 3; ++c) {
    const double error = std::abs(result["Rd"][c].get<double>() - truth["Rd"][c].get<double>());
    if (error <= Rd_tolerance) continue;
    // Out of bounds is acceptable only when said: the channel flagged and the warning printed.
    EXPECT_FALSE(result["Rd_constrained"][c].get<bool>())
        << label << ": Rd channel " << c << " off by " << error << " (bound " << Rd_tolerance << ") with no warning";
    EXPECT_NE(fit.err.find(std::string("Rd ") + "RGB"[c] + " is not constrained"), std::string::npos) << label << "\n"
                                                                                                      << fit.err;
  }
  EXPECT_TRUE(result["converged"].get<bool>()) << label << ": " << result["solver"];
  for (int c = 0; c < 3; ++c) {  // clamped to the physical range
    EXPECT_GE(result["Rd"][c].get<double>(), 0.0);
    EXPECT_LE(result["Rd"][c].get<double>(), 1.0);
  }
}

// --mode lighting: L_lm for l <= 2 within 3% of L00 of the set's own lighting, or a
// warning on stderr that the data do not pin the lighting down.
void expect_lighting(const std::string& label, const Fit& fit) {
  const nlohmann::json& result = fit.result;
  const double error = result["reference_L_lm_error_l2"].get<double>();
  std::printf(
      "%s: L_lm (l <= 2) max error %.2f%% of L00, scale %.4f %.4f %.4f, mirror share %.1f%%, %s, map's own L_lm "
      "%.2f%% off\n",
      label.c_str(), 100 * error, result["reference_scale"][0].get<double>(),
      result["reference_scale"][1].get<double>(), result["reference_scale"][2].get<double>(),
      100 * result["mirror_share"].get<double>(), result["solve"].get<std::string>().c_str(),
      100 * result["map_sh_disagreement"].get<double>());
  EXPECT_EQ(result["L_lm"].size(), 25u);
  if (error >= 0.03) {
    EXPECT_NE(fit.err.find("glaze: warning:"), std::string::npos)
        << label << ": L_lm (l <= 2) off by " << 100 * error << "% of L00 (bound 3%) and no warning\n"
        << fit.err;
  }
}

const RGB kWhite = RGB::Ones();
const RGB kNearlyBlack = RGB::Constant(0.02f);

// (1) A nearly black sphere (Rd 0.02, R0 0.04) in the office: almost all the light it
// sends back is the mirror reflection, the diffuse term a few percent of it.
TEST(ExtremeCases, NearlyBlackSphereShCaptures) {
  TemporaryDirectory dir;
  const std::string folder =
      captures(dir, sphere_scene_file(dir, 0.04f, kNearlyBlack), "black", "--integrator sh --ss 1 --res 96x96");
  // No --lmax or --pixel-footprint: transforms.json records how glaze rendered them.
  const Fit result = fit(dir, folder, "--mode material");
  expect_material("nearly black, sh", result, 1e-4, 1e-4);
}

// (2) Rd = 1 (the upper bound of Rd) with R0 = 0 (the lower bound of R0: no mirror
// term at normal incidence, only the Fresnel rise at grazing angles) and with R0 = 0.2.
TEST(ExtremeCases, WhiteSphereRdOneShCaptures) {
  TemporaryDirectory dir;
  for (const float R0 : {0.0f, 0.2f}) {
    const std::string name = "white_R0_" + std::to_string(R0);
    SCOPED_TRACE(name);
    const std::string folder =
        captures(dir, sphere_scene_file(dir, R0, kWhite, name + ".gltf"), name, "--integrator sh --ss 1 --res 96x96");
    const Fit result = fit(dir, folder, "--mode material");
    expect_material("Rd = 1, R0 = " + std::to_string(R0) + ", sh", result, 1e-4, 1e-4);
    if (R0 == 0.0f) {
      // At its bound, and not below it.
      EXPECT_GE(result.result["R0"].get<double>(), 0.0);
    }
  }
}

// The same extremes path-traced (the model's independent check) at 64 spp instead of
// the 256 the bounds are stated for: the error is noise (measured: seeds 0 and 1 differ
// by as much as it), which grows as 1/sqrt(spp), so the bounds are doubled: R0 0.004,
// Rd 0.01. Measured at 64 spp, 96x96: nearly black R0 -0.0003, Rd +0.0004..0.0005;
// Rd = 1, R0 = 0.2: R0 -0.0007..-0.0015, Rd exact (clamped at 1).
TEST(ExtremeCases, NearlyBlackAndRdOnePathTraced) {
  TemporaryDirectory dir;
  for (const auto& [R0, Rd, name] : {std::tuple{0.04f, kNearlyBlack, "black"}, std::tuple{0.2f, kWhite, "white"}}) {
    SCOPED_TRACE(name);
    const std::string folder =
        captures(dir, sphere_scene_file(dir, R0, Rd, std::string(name) + ".gltf"), name, "--spp 64 --res 96x96");
    expect_material(std::string(name) + ", path-traced 64 spp", fit(dir, folder, "--mode material"), 0.004, 0.01);
  }
}

// (3) Lighting dominated by one small source: the studio map. The material under it
// (the white sphere of the scenes).
TEST(ExtremeCases, StudioMapMaterial) {
  GLAZE_REQUIRE_ENVMAP(studio, "studio_small_03_1k.hdr");
  TemporaryDirectory dir;
  const std::string folder = captures(dir, kScenes + "white_sphere_office.gltf", "studio",
                                      "--integrator sh --ss 1 --res 96x96 --env " + studio.string());
  expect_material("white sphere, studio map, sh", fit(dir, folder, "--mode material"), 1e-4, 1e-4);
}

// The studio map recovered from the white sphere of known material (--mode lighting),
// three input views as in the InvertFitLighting tests, 256x256: within 3% (measured
// 1.1% of L00).
TEST(ExtremeCases, StudioMapLighting) {
  GLAZE_REQUIRE_ENVMAP(studio, "studio_small_03_1k.hdr");
  TemporaryDirectory dir;
  const std::string folder =
      captures(dir, kScenes + "white_sphere_office.gltf", "studio",
               "--integrator sh --ss 1 --res 256x256 --holdout novel_0,novel_1 --env " + studio.string());
  const Fit result = fit(dir, folder, "--mode lighting --pixel-footprint 1");
  expect_lighting("studio map, lighting, 256x256", result);
  EXPECT_LT(result.result["reference_L_lm_error_l2"].get<double>(), 0.03);
}

// The same at 128x128: the small source's reflection covers few pixels (100 of the
// 2048 cells of the 64x32 solve map are covered, against 1620 at 256x256). Measured:
// L_lm off by 11.9% of L00 (and 3.5% with all five views); the office at 128x128 gives
// 0.9%. This test asks for what the issue asks: within 3%, or a warning. glaze warns
// twice: the views are reproduced to 21% only, and L_lm differs from the recovered map's
// own by 25% of L00 (map_sh_disagreement; 1.1% L_lm error at 256x256 gives no warning).
TEST(ExtremeCases, StudioMapLightingAtLowResolutionIsWithinBoundsOrWarns) {
  GLAZE_REQUIRE_ENVMAP(studio, "studio_small_03_1k.hdr");
  TemporaryDirectory dir;
  const std::string folder =
      captures(dir, kScenes + "white_sphere_office.gltf", "studio",
               "--integrator sh --ss 1 --res 128x128 --holdout novel_0,novel_1 --env " + studio.string());
  expect_lighting("studio map, lighting, 128x128", fit(dir, folder, "--mode lighting --pixel-footprint 1"));
}

// --mode lighting on a sphere of R0 = 0 (no mirror at normal incidence: F = (1 - mu)^5)
// from sh captures whose diffuse term goes to l = 8, above the fit's lmax 4, so that a
// first fit's map predicts the bands above 4 for a second. That map divided each
// texel's light by F down to F ~ 1e-6 near the views' centres, its bands 5-8 were the
// diffuse model's residual times 1e6, and L00 came out at -726 (Rd 1) and -185 (Rd 0.5)
// for a true 8.57 (errors of 72,300% and 20,800% of L00), exit 0. Samples under F = 0.01
// no longer estimate the map. Measured now: Rd 1 0.22%, Rd 0.5 0.32%. The truth: the
// set's own lighting (reference_L_lm_error_l2, reference_scale).
TEST(ExtremeCases, LightingFitOnR0ZeroSphere) {
  TemporaryDirectory dir;
  for (const float Rd : {1.0f, 0.5f}) {
    const std::string name = "R0_0_Rd_" + std::to_string(Rd);
    SCOPED_TRACE(name);
    const std::string folder = captures(dir, sphere_scene_file(dir, 0.0f, RGB::Constant(Rd), name + ".gltf"), name,
                                        "--integrator sh --lmax 8 --ss 1 --res 96x96");
    const Fit result = fit(dir, folder, "--mode lighting");
    expect_lighting(name + ", lighting", result);
    EXPECT_EQ(result.result["passes"], 2);
    EXPECT_LT(result.result["reference_L_lm_error_l2"].get<double>(), 0.03);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(result.result["reference_scale"][c].get<double>(), 1.0, 0.03);
  }
}

// R0 = 0 with Rd = 0 reflects light only at grazing angles: the fit was 8% off in L00
// with exit 0 and only the reproduction warning, which blames a small source. Now
// --mode lighting refuses such a material, and warns about a channel of Rd = 0 beside
// others that reflect (where its L_lm was off by as much).
TEST(ExtremeCases, LightingFitRefusesAnObjectThatReflectsOnlyAtGrazingAngles) {
  TemporaryDirectory dir;
  const std::string black = captures(dir, sphere_scene_file(dir, 0.0f, RGB::Zero(), "black.gltf"), "black",
                                     "--integrator sh --ss 1 --res 96x96");
  const CommandResult refused =
      run_glaze("invert-fit " + black + "/transforms.json --out " + black + "/fit --mode lighting", dir);
  EXPECT_FALSE(refused.crashed) << refused.err;
  EXPECT_EQ(refused.exit_code, 1) << refused.err;
  EXPECT_NE(refused.err.find("transforms.json: R0 = 0 and Rd = 0"), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("only at grazing angles"), std::string::npos) << refused.err;
  EXPECT_FALSE(std::filesystem::exists(black + "/fit/fit.json"));

  const std::string blue = captures(dir, sphere_scene_file(dir, 0.0f, RGB(1.0f, 0.5f, 0.0f), "yellow.gltf"), "yellow",
                                    "--integrator sh --ss 1 --res 96x96");
  const Fit result = fit(dir, blue, "--mode lighting");
  EXPECT_NE(result.err.find("R0 = 0 and Rd = 0 in the blue channel"), std::string::npos) << result.err;
  EXPECT_EQ(result.err.find("in the red channel: it reflects"), std::string::npos) << result.err;
}

// (4) 5% multiplicative noise (as in InvertFit.FivePercentNoiseKeepsEstimatesWithinOnePercent)
// on the nearly black sphere and on the Rd = 1 spheres: within 0.01, or said.
TEST(ExtremeCases, FivePercentNoiseOnNearlyBlackAndRdOneSpheres) {
  TemporaryDirectory dir;
  for (const auto& [R0, Rd, name] : {std::tuple{0.04f, kNearlyBlack, "black"}, std::tuple{0.0f, kWhite, "white_R0_0"},
                                     std::tuple{0.2f, kWhite, "white_R0_0.2"}}) {
    SCOPED_TRACE(name);
    const std::string folder = captures(dir, sphere_scene_file(dir, R0, Rd, std::string(name) + ".gltf"), name,
                                        "--integrator sh --ss 1 --res 96x96");
    add_multiplicative_noise(folder, 0.05f);
    const Fit result = fit(dir, folder, "--mode material --lmax 4 --pixel-footprint 1");
    expect_material(std::string(name) + ", 5% noise", result, 0.01, 0.01);
    EXPECT_GE(result.result["R0"].get<double>(), 0.0);
  }
}

// 5% noise under the studio map: the bright source's reflection is a few pixels, each
// with its own 5% error.
TEST(ExtremeCases, FivePercentNoiseUnderTheStudioMap) {
  GLAZE_REQUIRE_ENVMAP(studio, "studio_small_03_1k.hdr");
  TemporaryDirectory dir;
  const std::string folder = captures(dir, sphere_scene_file(dir, 0.04f, kNearlyBlack), "black",
                                      "--integrator sh --ss 1 --res 96x96 --env " + studio.string());
  add_multiplicative_noise(folder, 0.05f);
  expect_material("nearly black, studio map, 5% noise",
                  fit(dir, folder, "--mode material --lmax 4 --pixel-footprint 1"), 0.01, 0.01);
}

// --mode joint on a white (Rd = 1) sphere with coat R0 in the office, noise-free
// 128x128 captures, three views; prints what it recovered.
Fit joint_fit_on_white_sphere(const TemporaryDirectory& dir, float R0) {
  const std::string folder = captures(dir, sphere_scene_file(dir, R0, kWhite), "joint",
                                      "--integrator sh --ss 1 --res 128x128 --holdout novel_0,novel_1");
  const Fit fitted = fit(dir, folder, "--mode joint --pixel-footprint 1");
  const nlohmann::json& result = fitted.result;
  std::printf(
      "joint, Rd = 1, R0 = %g: R0 %.4f, Rd %.4f %.4f %.4f, lighting scale %.4f %.4f %.4f, L_lm error %.2f%% of L00\n",
      R0, result["R0"].get<double>(), result["Rd"][0].get<double>(), result["Rd"][1].get<double>(),
      result["Rd"][2].get<double>(), result["reference_scale"][0].get<double>(),
      result["reference_scale"][1].get<double>(), result["reference_scale"][2].get<double>(),
      100 * result["reference_L_lm_error_l2"].get<double>());
  return fitted;
}

// (5) --mode joint (material and lighting together) on the Rd = 1, R0 = 0.2 sphere in
// the office, noise-free, 128x128, three views: the noise-free bounds (R0
// within 0.001, Rd within 0.003, the lighting's scale within 3%) hold at Rd's upper
// bound too. Measured: R0 0.19996, Rd 0.9986 0.9987 0.9986, scale 1.0011.
TEST(ExtremeCases, JointFitOnRdOneSphereMeetsTheNoiseFreeBounds) {
  TemporaryDirectory dir;
  const Fit fitted = joint_fit_on_white_sphere(dir, 0.2f);
  const nlohmann::json& result = fitted.result;
  EXPECT_EQ(result["mode"], "joint");
  EXPECT_EQ(result["L_lm"].size(), 25u);
  EXPECT_NEAR(result["R0"].get<double>(), 0.2, 0.001);
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(result["Rd"][c].get<double>(), 1.0, 0.003) << "channel " << c;
    EXPECT_LE(result["Rd"][c].get<double>(), 1.0) << "channel " << c;
    EXPECT_NEAR(result["reference_scale"][c].get<double>(), 1.0, 0.03) << "channel " << c;
  }
}

// --mode joint on the matte extreme: Rd = 1, R0 = 0 (the mirror carries 3% of the
// light, all of it at grazing angles). The split of each channel between Rd and the
// lighting's scale rests on the few grazing samples where F >= 0.01; only the product
// Rd x scale is pinned by the diffuse light alone. (An earlier joint fit moved from
// Rd 1.00 1.00 0.88 to 0.70 0.38 0.35 on captures that differed by float rounding, the
// products staying at 0.98-1.00; this one recovers Rd 1.0000 and scale 1.0000, where the
// estimate of Rd met its upper bound.) glaze warns that the object is matte-like.
// Asserted: finite numbers, that warning, R0 within 0.001, Rd in range, and the
// identifiable product within 3% of 1.
TEST(ExtremeCases, JointFitOnMatteRdOneSphereWarns) {
  TemporaryDirectory dir;
  const Fit fitted = joint_fit_on_white_sphere(dir, 0.0f);
  const nlohmann::json& result = fitted.result;
  EXPECT_NE(fitted.err.find("matte-like"), std::string::npos) << fitted.err;
  EXPECT_NEAR(result["R0"].get<double>(), 0.0, 0.001);
  EXPECT_GE(result["R0"].get<double>(), 0.0);
  for (int c = 0; c < 3; ++c) {
    const double Rd = result["Rd"][c].get<double>(), scale = result["reference_scale"][c].get<double>();
    EXPECT_GE(Rd, 0.0) << "channel " << c;
    EXPECT_LE(Rd, 1.0) << "channel " << c;
    EXPECT_NEAR(Rd * scale, 1.0, 0.03) << "channel " << c;
  }
}

}  // namespace
}  // namespace glaze
