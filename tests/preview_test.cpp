// Tests of the preview: its orbit camera, the progressive passes behind it, the renderer
// thread that publishes them, and the window itself under Xvfb (the screenshot against
// the offline render of the same camera), skipped with a message where no X server
// can be started or the build leaves the window out.
#include "app/orbit_camera.h"
#include "app/preview_renderer.h"
#include "renderer/display.h"
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/path_tracer.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/sh_integrator.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace glaze {
namespace {

using testing::front_camera;
using testing::sphere_scene;

// Where world point p lands on the film (pixels), for a camera looking at it.
Vec2 project(const PinholeCamera& camera, const Vec3& p) {
  const Vec3 local = camera.camera_to_world.inverse() * p;
  return {camera.cx + camera.fl_x * local.x() / -local.z(), camera.cy - camera.fl_y * local.y() / -local.z()};
}

TEST(OrbitCamera, StartsAsTheSceneCameraAndKeepsThePivotInTheCentre) {
  PinholeCamera start = front_camera(64);
  start.camera_to_world.linear() = Eigen::AngleAxisf(0.3f, Vec3(0, 0, 1)).toRotationMatrix();  // a rolled camera
  start.camera_to_world.translation() = Vec3(0, 0, 4);
  OrbitCamera orbit(start, Vec3(0.5f, 0.2f, 0.0f));
  EXPECT_TRUE(orbit.camera().camera_to_world.isApprox(start.camera_to_world));  // roll kept
  EXPECT_NEAR(orbit.distance(), 4.0f, 1e-5);                                    // the centre's depth along the axis
  EXPECT_TRUE(orbit.pivot().isApprox(Vec3(0, 0, 0), 1e-5));

  orbit.orbit(0.7f, 0.4f);
  EXPECT_NEAR((orbit.camera().position() - orbit.pivot()).norm(), 4.0f, 1e-4);  // on the sphere round the pivot
  const Vec2 centre = project(orbit.camera(), orbit.pivot());
  EXPECT_NEAR(centre.x(), 32.0f, 1e-3);
  EXPECT_NEAR(centre.y(), 32.0f, 1e-3);            // still looked at
  EXPECT_GT(orbit.camera().position().y(), 0.5f);  // positive pitch: up
  orbit.orbit(0.0f, -0.4f);
  orbit.orbit(2 * std::numbers::pi_v<float> - 0.7f, 0.0f);  // a whole turn back round
  EXPECT_TRUE(orbit.camera().position().isApprox(start.position(), 1e-4)) << orbit.camera().position().transpose();

  // Pitch never carries the view over the pole, in small steps or in one large one.
  for (int i = 0; i < 20; ++i) orbit.orbit(0.0f, 0.3f);
  Vec3 forward = -orbit.camera().camera_to_world.linear().col(2);
  EXPECT_NEAR(std::asin(forward.y()), -89.0f * kPi / 180.0f, 1e-3);     // camera above, looking down
  EXPECT_GT(orbit.camera().camera_to_world.linear().col(1).y(), 0.0f);  // not upside down
  orbit.orbit(0.0f, -4.0f);  // one step of 229 degrees: stops at the other pole
  forward = -orbit.camera().camera_to_world.linear().col(2);
  EXPECT_NEAR(std::asin(forward.y()), 89.0f * kPi / 180.0f, 1e-3);
  EXPECT_GT(orbit.camera().camera_to_world.linear().col(1).y(), 0.0f);
}

TEST(OrbitCamera, PanMovesThePointUnderTheCursorWithItAndZoomScalesTheDistance) {
  OrbitCamera orbit(front_camera(100), Vec3::Zero());
  const Vec3 grabbed = orbit.pivot();  // at the centre (50, 50)
  orbit.pan(12.0f, -7.0f);             // drag 12 right, 7 up
  const Vec2 moved = project(orbit.camera(), grabbed);
  EXPECT_NEAR(moved.x(), 62.0f, 1e-3);
  EXPECT_NEAR(moved.y(), 43.0f, 1e-3);
  orbit.zoom(0.5f);
  EXPECT_NEAR(orbit.distance(), 2.0f, 1e-5);
  EXPECT_NEAR((orbit.camera().position() - orbit.pivot()).norm(), 2.0f, 1e-5);
  orbit.zoom(-1.0f);  // ignored
  EXPECT_NEAR(orbit.distance(), 2.0f, 1e-5);
}

struct SphereUnderOffice {
  Scene scene = sphere_scene(0.04f, RGB(0.8f, 0.1f, 0.1f));
  Environment environment{make_procedural_environment("office", 128, 64), {}};
  RayTracer tracer{scene};
  PathTracer path{scene, tracer, environment, PathTracerOptions{}};
};

TEST(ProgressiveRender, PassesAreRenderPassesAndCancellingAddsNothing) {
  const SphereUnderOffice s;
  const PinholeCamera camera = front_camera(24);
  RenderOptions options;
  options.spp = 4;
  options.seed = 5;
  ProgressiveRender passes(s.path, camera, options);
  EXPECT_EQ(passes.spp(), 0);
  std::atomic<bool> cancel{true};
  EXPECT_FALSE(passes.add_pass(&cancel));
  EXPECT_EQ(passes.passes(), 0);
  EXPECT_TRUE(passes.add_pass());
  // One pass is exactly what render() gives for the same seed and spp.
  const Image whole = render(s.path, camera, options).image;
  EXPECT_EQ(passes.mean().pixels, whole.pixels);
  EXPECT_EQ(passes.spp(), 4);
  for (float e : passes.relative_standard_error()) EXPECT_TRUE(std::isnan(e));  // one pass: unknown
}

// Observed over predicted squared difference of two 16-pass estimates with different
// seeds: E[(Y_a - Y_b)^2] = se_a^2 + se_b^2 for independent passes, over object pixels.
double seed_difference_ratio(bool pixel_centres) {
  const SphereUnderOffice s;
  const PinholeCamera camera = front_camera(40);
  RenderOptions options;
  options.spp = 1;
  options.pixel_centres = pixel_centres;
  ProgressiveRender a(s.path, camera, options);
  options.seed = 99;
  ProgressiveRender b(s.path, camera, options);
  for (int pass = 0; pass < 16; ++pass) a.add_pass(), b.add_pass();
  const Image mean_a = a.mean(), mean_b = b.mean();
  const std::vector<float> error_a = a.relative_standard_error(), error_b = b.relative_standard_error();
  double observed = 0.0, predicted = 0.0;
  int pixels = 0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const size_t p = size_t(y) * camera.width + x;
      const double ya = luminance(mean_a.at(x, y)), yb = luminance(mean_b.at(x, y));
      if (std::isnan(error_a[p]) || std::isnan(error_b[p]) || error_a[p] == 0.0f) continue;  // background: exact
      observed += (ya - yb) * (ya - yb);
      predicted += std::pow(error_a[p] * ya, 2) + std::pow(error_b[p] * yb, 2);
      ++pixels;
    }
  EXPECT_GT(pixels, 500);
  return observed / predicted;
}

TEST(ProgressiveRender, RelativeErrorPredictsTheDifferenceBetweenTwoSeeds) {
  // Through the pixel centres the passes are independent: the estimate is exact in
  // expectation.
  EXPECT_NEAR(seed_difference_ratio(true), 1.0, 0.2);
  // Over the pixel area the passes continue one stratified sequence, so the mean is
  // better than independent passes would make it: the error shown is an upper bound.
  const double stratified = seed_difference_ratio(false);
  EXPECT_LT(stratified, 1.1);
  EXPECT_GT(stratified, 0.4);
}

TEST(PreviewRenderer, PublishesTheShImageThenPathPassesInLockstep) {
  const SphereUnderOffice s;
  const PinholeCamera camera = front_camera(32);
  PreviewRendererOptions options;
  options.sh.lmax = 4;
  options.sh.supersampling = 2;
  options.path.seed = 3;
  options.max_spp = 3;
  options.lockstep = true;
  PreviewRenderer renderer(s.scene, s.tracer, s.environment, s.path, options, camera, PreviewIntegrator::sh);
  auto frame = renderer.wait_newer(0);
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->version, 1u);
  EXPECT_EQ(frame->sh_ss, 2);
  EXPECT_EQ(frame->path_spp, 0);
  EXPECT_EQ(frame->sh.pixels, render_sh(s.scene, s.tracer, s.environment, camera, options.sh).pixels);
  // n.v: 1 at the sphere's centre, unknown off the object.
  EXPECT_NEAR(frame->n_dot_v[16 * 32 + 16], 1.0f, 2e-3);
  EXPECT_TRUE(std::isnan(frame->n_dot_v[0]));
  RenderOptions path_options = options.path;
  path_options.spp = 1;
  ProgressiveRender reference(s.path, camera, path_options);
  for (int spp = 1; spp <= 3; ++spp) {
    frame = renderer.wait_newer(frame->version);
    reference.add_pass();
    EXPECT_EQ(frame->path_spp, spp);
    EXPECT_EQ(frame->path.pixels, reference.mean().pixels) << spp;
  }
  // max_spp reached: idle, the same frame comes back.
  EXPECT_EQ(renderer.wait_newer(frame->version)->version, frame->version);

  // A new camera: only its own frames come back, starting again from the sh image.
  PinholeCamera moved = camera;
  moved.camera_to_world.translation() = Vec3(0, 0, 5);
  renderer.set_camera(moved);
  frame = renderer.wait_newer(frame->version);
  EXPECT_EQ(frame->path_spp, 0);
  EXPECT_EQ(frame->sh.pixels, render_sh(s.scene, s.tracer, s.environment, moved, options.sh).pixels);
}

TEST(PreviewRenderer, PathFirstRendersPassesBeforeTheShImage) {
  const SphereUnderOffice s;
  PreviewRendererOptions options;
  options.max_spp = 10;
  options.lockstep = true;
  PreviewRenderer renderer(s.scene, s.tracer, s.environment, s.path, options, front_camera(16),
                           PreviewIntegrator::path);
  std::shared_ptr<const PreviewFrame> frame;
  for (int step = 1; step <= 8; ++step) {
    frame = renderer.wait_newer(frame ? frame->version : 0);
    EXPECT_EQ(frame->path_spp, step);
    EXPECT_EQ(frame->sh_ss, 0);
  }
  frame = renderer.wait_newer(frame->version);
  EXPECT_EQ(frame->sh_ss, options.sh.supersampling);  // then the sh image, in the background
}

TEST(PreviewRenderer, ShowsTheRegisteredPathAndShIntegrators) {
  EXPECT_EQ(preview_integrator("path"), PreviewIntegrator::path);
  EXPECT_EQ(preview_integrator("sh"), PreviewIntegrator::sh);
  EXPECT_THROW(preview_integrator("photon"), Error);
}

// ---- The window, under Xvfb ----------------------------------------------------------

#if GLAZE_HAVE_PREVIEW
constexpr const char* kXvfb = "xvfb-run -a -s '-screen 0 1280x1024x24' ";

// Whether an X server can be started here (xvfb-run present and working).
bool xvfb_works() {
  static const bool works = std::system("xvfb-run -a -s '-screen 0 640x480x24' true >/dev/null 2>&1") == 0;
  return works;
}

#define GLAZE_REQUIRE_XVFB()                                                                             \
  if (!xvfb_works())                                                                                     \
  GTEST_SKIP() << "no X server could be started (xvfb-run missing or Xvfb failed: apt-get install xvfb " \
                  "xauth libgl1-mesa-dri); skipping the window test"

testing::CommandResult glaze_in_xvfb(const std::string& arguments, const testing::TemporaryDirectory& dir) {
  testing::CommandResult run = testing::run_glaze(arguments, dir, kXvfb);
  // xvfb-run -a can race with another instance for a display number: try once more.
  if (run.exit_code != 0 && run.err.find("Xvfb failed to start") != std::string::npos)
    run = testing::run_glaze(arguments, dir, kXvfb);
  return run;
}

// 8-bit codes of a PNG (read_image decodes sRGB; encoding again gives the codes back).
std::vector<int> codes(const std::string& path, int& width, int& height) {
  const Image image = read_image(path);
  width = image.width, height = image.height;
  std::vector<int> out(image.pixels.size());
  for (size_t k = 0; k < out.size(); ++k) {
    const float v = image.pixels[k];
    const double encoded = v <= 0.0031308f ? 12.92 * v : 1.055 * std::pow(double(v), 1 / 2.4) - 0.055;
    out[k] = int(std::lround(255 * encoded));
  }
  return out;
}

const std::string kScene = std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf";

TEST(PreviewWindow, ShScreenshotIsTheOfflineRenderPixelForPixel) {
  GLAZE_REQUIRE_XVFB();
  testing::TemporaryDirectory dir;
  // Tolerance: at most 1 code of 255 per channel (the picture is drawn 1:1 with nearest
  // texels, so any larger difference is a defect, not rounding).
  for (const std::string display : {"", " --exposure 1.5 --tone-map aces", " --tone-map clamp --exposure -1"}) {
    const auto shot = glaze_in_xvfb("preview " + kScene + " --integrator sh --res 160x120 --frames 1 --screenshot " +
                                        dir.file("shot.png") + display,
                                    dir);
    ASSERT_EQ(shot.exit_code, 0) << shot.err;
    const auto offline = testing::run_glaze(
        "render " + kScene + " --integrator sh --res 160x120 --out " + dir.file("offline.png") + display, dir);
    ASSERT_EQ(offline.exit_code, 0) << offline.err;
    int w1, h1, w2, h2;
    const std::vector<int> a = codes(dir.file("shot.png"), w1, h1), b = codes(dir.file("offline.png"), w2, h2);
    ASSERT_EQ(w1, 160);
    ASSERT_EQ(h1, 120);
    ASSERT_EQ(w2, 160);
    ASSERT_EQ(h2, 120);
    int worst = 0;
    for (size_t k = 0; k < a.size(); ++k) worst = std::max(worst, std::abs(a[k] - b[k]));
    EXPECT_LE(worst, 1) << display;
    EXPECT_NE(shot.err.find("first image"), std::string::npos) << shot.err;
  }
}

TEST(PreviewWindow, PathScreenshotDiffersFromTheOfflineRenderOnlyByNoise) {
  // 32 preview passes against an offline 32-spp render: their difference is no larger
  // than that between two offline renders with different seeds (an independent measure
  // of the noise), and has no bias.
  GLAZE_REQUIRE_XVFB();
  testing::TemporaryDirectory dir;
  const std::string common = " --res 96x96 --tone-map clamp --exposure -1";
  const auto shot = glaze_in_xvfb(
      "preview " + kScene + " --integrator path --frames 32 --screenshot " + dir.file("shot.png") + common, dir);
  ASSERT_EQ(shot.exit_code, 0) << shot.err;
  for (const char* seed : {"1", "2"})
    ASSERT_EQ(testing::run_glaze("render " + kScene + " --spp 32 --seed " + seed + " --out " +
                                     dir.file(std::string("o") + seed + ".png") + common,
                                 dir)
                  .exit_code,
              0);
  int w, h;
  const std::vector<int> preview = codes(dir.file("shot.png"), w, h), one = codes(dir.file("o1.png"), w, h),
                         two = codes(dir.file("o2.png"), w, h);
  double preview_gap = 0, seed_gap = 0, bias = 0;
  for (size_t k = 0; k < preview.size(); ++k) {
    preview_gap += std::abs(preview[k] - one[k]);
    seed_gap += std::abs(two[k] - one[k]);
    bias += preview[k] - one[k];
  }
  EXPECT_LT(preview_gap, 1.3 * seed_gap + preview.size() * 0.1);
  EXPECT_LT(std::abs(bias) / preview.size(), 0.5);
}

TEST(PreviewWindow, InvertFitPreviewShowsObservedPredictedAndResidual) {
  GLAZE_REQUIRE_XVFB();
  testing::TemporaryDirectory dir;
  ASSERT_EQ(testing::run_glaze("render " + kScene +
                                   " --integrator sh --ss 1 --res 64x64 --holdout novel_0,novel_1 --captures " +
                                   dir.file("caps"),
                               dir)
                .exit_code,
            0);
  const auto run = glaze_in_xvfb("invert-fit " + dir.file("caps/transforms.json") + " --mode material --out " +
                                     dir.file("fit") + " --preview --frames 2 --screenshot " + dir.file("shot.png"),
                                 dir);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  int w, h;
  const std::vector<int> shot = codes(dir.file("shot.png"), w, h);
  // Three views of 64x64 in rows, three panels each, 4-pixel gutters.
  ASSERT_EQ(w, 3 * 64 + 2 * 4);
  ASSERT_EQ(h, 3 * 64 + 2 * 4);
  for (int view = 0; view < 3; ++view) {
    char name[32];
    std::snprintf(name, sizeof name, "view_%03d.exr", view);
    const std::vector<uint8_t> observed = display_image(read_image(dir.file("caps/" + std::string(name))), {});
    const std::vector<uint8_t> predicted = display_image(read_image(dir.file("fit/render_" + std::string(name))), {});
    int worst_observed = 0, worst_predicted = 0, residual_sum = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x)
        for (int c = 0; c < 3; ++c) {
          const size_t row = size_t(view * 68 + y) * w;
          const size_t k = size_t(y * 64 + x) * 3 + c;
          worst_observed = std::max(worst_observed, std::abs(shot[(row + x) * 3 + c] - observed[k]));
          worst_predicted = std::max(worst_predicted, std::abs(shot[(row + 68 + x) * 3 + c] - predicted[k]));
          residual_sum += shot[(row + 136 + x) * 3 + c];
        }
    EXPECT_LE(worst_observed, 1) << view;
    EXPECT_LE(worst_predicted, 1) << view;             // the final state: the fit's own re-render
    EXPECT_LT(residual_sum, 64 * 64 * 3 * 2) << view;  // sh captures fit exactly: nearly black
  }
}

TEST(PreviewWindow, NoDisplayIsAClearError) {
  testing::TemporaryDirectory dir;
  testing::expect_clear_failure(testing::run_glaze("preview " + kScene, dir, "env -u DISPLAY "), "DISPLAY");
  testing::expect_clear_failure(testing::run_glaze("preview " + kScene, dir, "env DISPLAY=:4321 "), "DISPLAY=:4321");
  testing::expect_clear_failure(testing::run_glaze("render " + kScene + " --integrator sh --res 32x32 --captures " +
                                                       dir.file("caps") + " && env -u DISPLAY " + GLAZE_EXECUTABLE +
                                                       " invert-fit " + dir.file("caps/transforms.json") +
                                                       " --mode material --out " + dir.file("fit") + " --preview",
                                                   dir),
                                "DISPLAY");
  EXPECT_FALSE(std::filesystem::exists(dir.file("fit/fit.json")));  // failed before any work
  testing::expect_clear_failure(testing::run_glaze("preview " + kScene + " --screenshot x.png", dir, "env -u DISPLAY "),
                                "--frames");
  testing::expect_clear_failure(testing::run_glaze("preview " + kScene + " --frames 1 --screenshot x.exr", dir), "PNG");
  testing::expect_clear_failure(
      testing::run_glaze("preview " + kScene + " --tone-map reinhard", dir, "env -u DISPLAY "), "reinhard");
}
#else
TEST(PreviewWindow, BuiltWithoutThePreviewSaysSo) {
  testing::TemporaryDirectory dir;
  testing::expect_clear_failure(
      testing::run_glaze("preview " + std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf", dir),
      "GLAZE_PREVIEW=OFF");
  GTEST_SKIP() << "this build leaves the preview window out (GLAZE_PREVIEW=OFF): its window tests do not apply";
}
#endif

}  // namespace
}  // namespace glaze
