// Results that used to come out wrong without a word (issue "hostile input and faults"):
// an environment bright enough to overflow float in a render, which now is refused when
// it is made (and renders below that limit stay finite), and a lighting fit whose L_lm
// disagrees with its own map, which now is warned about.
#include "inverse/fit_diagnostics.h"
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/sh.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace glaze {
namespace {

using testing::CapturedWarnings;
using testing::CommandResult;
using testing::quoted;
using testing::run_glaze;
using testing::TemporaryDirectory;

Image constant_map(int width, int height, float value) {
  Image map(width, height);
  for (float& v : map.pixels) v = value;
  return map;
}

// The message of the Error that making `map` as an environment throws ("" if none).
std::string refusal(const Image& map, float scale, const std::string& source) {
  try {
    const Environment environment(map, EnvironmentOptions{.scale = scale}, source);
  } catch (const Error& error) {
    return error.what();
  }
  return "";
}

// A texel of 3e38 (just under FLT_MAX) put Inf into renders; now the map is refused with
// the file, the texel, its value and what to do.
TEST(SilentResults, EnvironmentRefusesATexelNearFloatMax) {
  Image map = constant_map(16, 8, 0.5f);
  map.set(3, 2, RGB(0.5f, 3e38f, 0.5f));
  const std::string message = refusal(map, 1.0f, "bright.exr");
  EXPECT_NE(message.find("bright.exr"), std::string::npos) << message;
  EXPECT_NE(message.find("texel (3, 2)"), std::string::npos) << message;
  EXPECT_NE(message.find("3e+38"), std::string::npos) << message;
  EXPECT_NE(message.find("scale the map down"), std::string::npos) << message;
}

// An ordinary map times --env-scale 1e38: refused, the scale named.
TEST(SilentResults, EnvironmentRefusesAScaleThatOverflows) {
  const std::string message = refusal(constant_map(16, 8, 2.0f), 1e38f, "office");
  EXPECT_NE(message.find("office"), std::string::npos) << message;
  EXPECT_NE(message.find("scale 1e+38"), std::string::npos) << message;
  // Up to the limit, 1e20, maps are accepted: 9e19, and 1e19 (in float 9.99999998e18) times 10.
  EXPECT_EQ(refusal(constant_map(16, 8, 9e19f), 1.0f, "limit"), "");
  EXPECT_EQ(refusal(constant_map(16, 8, 1e19f), 10.0f, "limit"), "");
  EXPECT_NE(refusal(constant_map(16, 8, 1e19f), 11.0f, "limit"), "");
}

// Just below the limit a render stays finite: the sphere under an office-like map of 0.5
// with one texel of 1e19, path-traced and with the sh integrator. The CLI refuses
// --env-scale 1e38 with exit 1.
TEST(SilentResults, RenderUnderATexelOf1e19IsFinite) {
  TemporaryDirectory dir;
  Image map = constant_map(64, 32, 0.5f);
  map.set(40, 10, RGB::Constant(1e19f));
  const std::string env = dir.file("bright.exr");
  write_image(env, map);
  const std::string scene = quoted(testing::scenes_dir() + "red_sphere_office.gltf");
  for (const char* integrator : {"path --spp 4", "sh"}) {
    SCOPED_TRACE(integrator);
    const std::string out = dir.file("render.exr");
    const CommandResult run = run_glaze("render " + scene + " --env " + quoted(env) + " --res 32x32 --integrator " +
                                            integrator + " --out " + quoted(out),
                                        dir);
    ASSERT_FALSE(run.crashed) << run.err;
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const Image image = read_image(out);
    float brightest = 0.0f;
    for (float v : image.pixels) {
      ASSERT_TRUE(std::isfinite(v));
      brightest = std::max(brightest, v);
    }
    EXPECT_GT(brightest, 1e3f);  // the bright texel is seen (its reflection, or its share of L00)
  }
  const CommandResult scaled = run_glaze(
      "render " + scene + " --env-scale 1e38 --res 8x8 --integrator sh --out " + quoted(dir.file("x.exr")), dir);
  EXPECT_FALSE(scaled.crashed) << scaled.err;
  EXPECT_EQ(scaled.exit_code, 1) << scaled.err;
  EXPECT_NE(scaled.err.find("scale the map down"), std::string::npos) << scaled.err;
}

// invert-fit recovers lighting of the captures' own scale: captures of 1e24 times the
// office's give a map near 1e25, which the re-renders would overflow under. The fit
// refuses it before it writes lighting.exr, with exit 1.
TEST(SilentResults, InvertFitRefusesARecoveredMapBeyondTheLimit) {
  TemporaryDirectory dir;
  const std::string folder = dir.file("bright");
  const CommandResult render =
      run_glaze("render " + quoted(testing::sphere_scene_file(dir, 0.04f, RGB::Constant(0.5f))) + " --captures " +
                    quoted(folder) + " --integrator sh --ss 1 --res 64x64",
                dir);
  ASSERT_EQ(render.exit_code, 0) << render.err;
  testing::rewrite_frames(folder, [](float value, Pcg32&) { return value * 1e24f; });
  const CommandResult run = run_glaze(
      "invert-fit " + quoted(folder + "/transforms.json") + " --out " + quoted(folder + "/fit") + " --mode lighting",
      dir);
  EXPECT_FALSE(run.crashed) << run.err;
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("recovered lighting: texel"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("scale the map down"), std::string::npos) << run.err;
  EXPECT_FALSE(std::filesystem::exists(folder + "/fit/lighting.exr"));
}

// A lighting fit whose map is the constant 1 (L00 = sqrt(4 pi)): with L_lm equal to the
// map's own, no warning and a disagreement of 0; with L00 twice that, or an L_1-1 of
// half of L00, the warning and the disagreement (1/2 of the larger L00, 1/2 of L00).
TEST(SilentResults, LightingFitWarnsWhenLlmDisagreesWithItsMap) {
  LightingData data;
  data.lmax = 2;
  LightingFit fit;
  fit.map = constant_map(64, 32, 1.0f);
  fit.mirror_share = 1.0, fit.channel_mirror_share = RGBd::Ones();  // no matte-like warnings
  fit.coefficients = ShCoefficients(2);
  const double L00 = std::sqrt(4.0 * kPiD);
  const LightingFitOptions options{.solve_width = 0};
  auto disagreement = [&](double fitted_L00, double L1m1) {
    fit.coefficients.values[0] = RGBd::Constant(fitted_L00);
    fit.coefficients.values[1] = RGBd::Constant(L1m1);
    const LightingDiagnostics diagnostics = diagnose_lighting(fit, data, options, nullptr);
    bool warned = false;
    for (const std::string& warning : diagnostics.warnings)
      warned = warned || warning.find("differs from the recovered map's own") != std::string::npos;
    EXPECT_EQ(warned, diagnostics.map_sh_disagreement > 0.1) << diagnostics.map_sh_disagreement;
    return diagnostics.map_sh_disagreement;
  };
  EXPECT_NEAR(disagreement(L00, 0.0), 0.0, 1e-3);
  EXPECT_NEAR(disagreement(2 * L00, 0.0), 0.5, 1e-3);
  EXPECT_NEAR(disagreement(L00, 0.5 * L00), 0.5, 1e-3);
  EXPECT_NEAR(disagreement(L00, 0.05 * L00), 0.05, 1e-3);  // within the tolerance: no warning
}

}  // namespace
}  // namespace glaze
