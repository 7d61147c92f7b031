// `glaze reproduce --quick`: the paper's experiments end to end on small images (160x160
// path-traced captures at 256 spp), one lighting per test so that ctest runs them side
// by side. Each asserts the accuracy bounds of the inverse issues on its captures:
// material under known lighting R0 within 0.002 and Rd within 0.005 (path-traced),
// texture texels within 0.02 RMSE, lighting L_lm (l <= 2) within 3% of L00; the joint
// fit to the looser bounds it meets today on path-traced captures (docs/accuracy.md,
// "The joint fit", states the gap). Also that
// recovered materials transfer to other lightings, that a spectral camera shows the
// pseudo-BRDF colour shift that RGB captures cannot, and that the report and its
// figures are written. And pseudo_brdf.h's model against closed forms.
#include "inverse/pseudo_brdf.h"
#include "renderer/image.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

namespace glaze {
namespace {

using testing::expect_all_finite;
using testing::read_json;
using testing::TemporaryDirectory;

nlohmann::json reproduce(const TemporaryDirectory& dir, const std::string& lightings) {
  const testing::CommandResult run = testing::run_glaze(
      "reproduce --quick --no-convergence --lighting " + lightings + " --out " + dir.file("out"), dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json results = read_json(dir.file("out/results.json"));
  expect_all_finite(results["table2"], "table2");
  expect_all_finite(results["lighting"], "lighting");
  expect_all_finite(results["transfer"], "transfer");
  for (const char* figure :
       {"figure5_textures", "figure6_novel_views", "figure7_transfer", "figure8_lighting", "figure9_joint"}) {
    const Image picture = read_image(dir.file(std::string("out/figures/") + figure + ".png"));
    EXPECT_GT(picture.width, 300) << figure;
  }
  std::ifstream report(dir.file("out/report.md"));
  const std::string text((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  for (const char* section : {"Table 2", "Figure 5", "Figure 6", "Figure 7", "Figure 8", "Table 3", "Run time"})
    EXPECT_NE(text.find(section), std::string::npos) << section;
  return results;
}

void expect_inverse_bounds(const nlohmann::json& results) {
  for (const auto& row : results["table2"]) {
    SCOPED_TRACE(row["lighting"].get<std::string>() + " " + row["object"].get<std::string>());
    EXPECT_NEAR(row["R0"].get<double>(), row["true_R0"].get<double>(), 0.002);
    if (row.contains("Rd"))
      for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(row["Rd"][c].get<double>(), row["true_Rd"][c].get<double>(), 0.005) << "channel " << c;
    else
      EXPECT_LT(row["texture_rmse"].get<double>(), 0.02);
  }
  for (const auto& row : results["lighting"]) EXPECT_LT(row["L_lm_error_l2"].get<double>(), 0.03) << row.dump();
  // Held-out views of the homogeneous spheres: what is left is the captures' noise
  // (about 5% per pixel at 256 spp), nothing systematic.
  for (const auto& row : results["holdout"])
    if (row["object"] != "textured") {
      EXPECT_LT(row["relative_rmse"].get<double>(), 0.1) << row.dump();
    }
  // Joint (issue 6 is open for path-traced captures: the bounds below are looser than
  // its 0.003 and 0.01). Measured over capture seeds 0-2 (`reproduce --seed`) at these
  // 160x160, 256-spp captures, R0 and worst Rd: office red -0.0001, -0.0098 to -0.034;
  // office white +0.0001 to +0.0008, -0.0070 to -0.020; blue-room red -0.0002, within
  // 0.016; blue-room white +0.0009 to +0.0038, +0.012 to +0.046; seed 0 under St
  // Fagans red -0.0004, +0.0031, white -0.0025, -0.0053, under Lebombo red -0.0003,
  // -0.011, white -0.0011, -0.014. The blue-room white sphere is the one R0's noise moves
  // most (cross_view.h); comparing the views through 3 x 3 pixels only fails these bounds
  // there (docs/notes/cross-view-comparison.md, docs/notes/studio-lamps.md). Asserted with
  // some margin over the spread above.
  for (const auto& row : results["table3"]) {
    SCOPED_TRACE(row["lighting"].get<std::string>() + " " + row["object"].get<std::string>());
    EXPECT_NEAR(row["joint_R0_error"].get<double>(), 0.0, 0.004);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(row["joint_Rd_error"][c].get<double>(), 0.0, 0.08) << "channel " << c;
  }
}

TEST(Reproduce, QuickOfficeAndBlueRoom) {
  TemporaryDirectory dir;
  const nlohmann::json results = reproduce(dir, "office,blue-room");
  expect_inverse_bounds(results);
  // RGB captures: a recovered material renders right in the other lighting (up to its
  // fit error). The spectral camera: the same fit shifts colour, several times more.
  double rgb = 0.0, spectral = 0.0;
  for (const auto& row : results["transfer"]) {
    if (row["fitted_in"] == row["shown_in"]) continue;
    if (row["kind"] == "rgb") {
      EXPECT_LT(row["relative_rmse"].get<double>(), 0.01) << row.dump();
      rgb = std::max(rgb, row["relative_rmse"].get<double>());
    } else {
      spectral = std::max(spectral, row["relative_rmse"].get<double>());
    }
  }
  EXPECT_GT(spectral, 5 * rgb);
}

// Under a real map: St Fagans, whose small bright window panes are where comparing the
// views through larger stencils failed the joint bounds at this size
// (docs/notes/cross-view-comparison.md). Lebombo is fitted from simulated photographs
// (PhotoShootAcceptance) and from noise-free captures (InvertFitJoint).
TEST(Reproduce, QuickRealMap) {
  GLAZE_REQUIRE_ENVMAP(st_fagans, "st_fagans_interior_1k.hdr");
  TemporaryDirectory dir;
  expect_inverse_bounds(reproduce(dir, st_fagans.string()));
}

TEST(Reproduce, BadOptionsGiveClearErrors) {
  TemporaryDirectory dir;
  testing::expect_clear_failure(testing::run_glaze("reproduce --quick", dir), "--out");
  testing::expect_clear_failure(testing::run_glaze("reproduce --out x --lighting nowhere", dir), "nowhere");
  testing::expect_clear_failure(testing::run_glaze("reproduce --out x --scenes " + dir.file("none"), dir), "--scenes");
}

// A grey reflectance is flat, so the camera sees each light primary as itself: M = g I,
// and the spectral render is the RGB render.
TEST(PseudoBrdf, GreyIsDiagonalAndSpectralRenderMatchesRgb) {
  const Mat3 M = spectral_diffuse_matrix(RGB::Constant(0.5f));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(M(r, c), r == c ? 0.5f : 0.0f, 1e-4f) << r << "," << c;
  const Scene scene = testing::sphere_scene(0.04f, RGB::Constant(0.5f));
  const RayTracer tracer(scene);
  const Environment environment = make_environment("procedural:office", {}, 128, 64);
  const PinholeCamera camera = testing::front_camera(24);
  const ShIntegratorOptions options{4, 1, true, 1, true};
  const Image rgb = render_sh(scene, tracer, environment, camera, options);
  const Image spectral = render_sh_spectral(scene, tracer, environment, camera, options, M);
  for (size_t i = 0; i < rgb.pixels.size(); ++i)
    EXPECT_NEAR(spectral.pixels[i], rgb.pixels[i], 1e-3f * (1.0f + rgb.pixels[i]));
}

// A colour within reach is seen as itself under white light (M's rows sum to it), yet M
// is not diagonal: light of another colour is reflected differently than RGB says.
TEST(PseudoBrdf, ColourUnderWhiteLightIsKeptButMixesChannels) {
  const RGB white_sphere(0.6242f, 0.6210f, 0.4083f);
  const Mat3 M = spectral_diffuse_matrix(white_sphere);
  for (int r = 0; r < 3; ++r) EXPECT_NEAR(M.row(r).sum(), white_sphere[r], 1e-4f);
  EXPECT_GT(std::abs(M(0, 1)) + std::abs(M(1, 2)) + std::abs(M(2, 1)), 0.01f);
  // Too saturated for any reflectance in (0, 1): the nearest stays in (0, 1) per channel.
  const Mat3 red = spectral_diffuse_matrix(RGB(0.9765f, 0.0186f, 0.0f));
  for (int r = 0; r < 3; ++r) EXPECT_TRUE(red.row(r).sum() >= -1e-4f && red.row(r).sum() <= 1.0f) << r;
  EXPECT_GT(red.row(0).sum(), 0.85f);
}

}  // namespace
}  // namespace glaze
