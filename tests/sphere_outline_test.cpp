// sphere_outline_test.cpp: a sphere located from its outline (inverse/photos): a known
// sphere rendered by glaze's sh integrator through three distorted cameras, in the board's
// frame (+Z up) under the office and a real map, located and compared with the truth.
#include "inverse/photos/sphere_outline.h"
#include "renderer/environment.h"
#include "renderer/mirror_ball.h"
#include "renderer/ray_tracer.h"
#include "renderer/sh_integrator.h"
#include "test_support.h"

#include <Eigen/Geometry>

namespace glaze::testing {
namespace {

const Vec3d kCenter(0.031, -0.018, 0.05);  // resting on the board, off its origin
constexpr double kRadius = 0.05;
constexpr int kWidth = 320, kHeight = 240;

// A camera at ~30 degrees elevation and ~0.5 m, at azimuth `degrees`, aimed a little off
// the sphere so that it images off the film's centre, where the lens bends most.
PinholeCamera view_camera(double degrees, int index) {
  const double a = degrees * M_PI / 180, e = (28.0 + 3.0 * index) * M_PI / 180, distance = 0.47 + 0.03 * index;
  const Vec3 eye =
      (kCenter + distance * Vec3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e))).cast<float>();
  const Vec3 target = (kCenter + Vec3d(0.02 * std::sin(a), -0.015, 0.01 * index)).cast<float>();
  const Vec3 forward = (target - eye).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  PinholeCamera camera;
  camera.name = "view_00" + std::to_string(index);
  camera.camera_to_world.linear().col(0) = right;
  camera.camera_to_world.linear().col(1) = right.cross(forward);
  camera.camera_to_world.linear().col(2) = -forward;
  camera.camera_to_world.translation() = eye;
  camera.width = kWidth;
  camera.height = kHeight;
  camera.fl_x = camera.fl_y = 330.0f;
  camera.cx = 163.5f;
  camera.cy = 118.0f;
  camera.distortion = {LensDistortion::Model::opencv, -0.1, 0.01, 0.0005, -0.0003, 0.0, 0.0};
  return camera;
}

// A lat-long map's +Y turned to the board's +Z.
EnvironmentOptions board_up() {
  EnvironmentOptions options;
  options.to_world = Eigen::AngleAxisf(float(M_PI / 2), Vec3::UnitX()).toRotationMatrix();
  return options;
}

// The three views of a sphere of material (R0, Rd) at `center` under `environment`.
std::vector<SphereView> render_views(const Environment& environment, float R0, const RGB& Rd,
                                     const Vec3d& center = kCenter, int views = 3) {
  Scene scene;
  scene.path = "sphere-outline-test";
  scene.materials.push_back({"coated", R0, Rd, -1});
  scene.spheres.push_back({"ball", center.cast<float>(), float(kRadius), 0, Mat3::Identity()});
  const RayTracer tracer(scene);
  ShIntegratorOptions options;
  options.supersampling = 3;
  options.refined_supersampling = 8;
  std::vector<SphereView> result;
  for (int v = 0; v < views; ++v) {
    SphereView view;
    view.camera = view_camera(20.0 + 120.0 * v, v);
    view.name = view.camera.name;
    view.image = render_sh(scene, tracer, environment, view.camera, options);
    result.push_back(std::move(view));
  }
  return result;
}
// The same under a glaze environment spec.
std::vector<SphereView> render_views(const std::string& environment_spec, float R0, const RGB& Rd,
                                     const Vec3d& center = kCenter, int views = 3) {
  return render_views(make_environment(environment_spec, board_up(), 512, 256), R0, Rd, center, views);
}

// What a merge of an 8-bit bracket leaves: 1% multiplicative noise, values quantised to
// 7 significant bits (a code of 128 .. 255 in the exposure that measured them), and the
// brightest pixels (the lamps and their reflections) saturated: alpha 0 and clipped.
void degrade_like_a_merge(std::vector<SphereView>& views) {
  Pcg32 rng(44);
  for (SphereView& view : views) {
    std::vector<float> sorted = view.image.pixels;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() * 998 / 1000, sorted.end());
    const float clip = sorted[sorted.size() * 998 / 1000];
    view.alpha.assign(size_t(view.image.width) * view.image.height, 1.0f);
    for (size_t i = 0; i < view.image.pixels.size(); ++i) {
      float& value = view.image.pixels[i];
      value *= 1.0f + 0.01f * standard_normal(rng);
      if (value > 0.0f) {
        const float step = std::exp2(std::floor(std::log2(value))) / 128.0f;
        value = std::round(value / step) * step;
      }
      if (value >= clip) value = clip, view.alpha[i / 3] = 0.0f;
    }
  }
}

// Issue 44's acceptance: the centre within 0.5 mm and the radius within 0.3%; every
// view's edges used for the most part and within half a pixel of the fitted outline.
void expect_located(const SphereFit& fit, const Vec3d& center, const std::string& what) {
  EXPECT_LT((fit.center - center).norm(), 0.5e-3) << what << ": centre " << fit.center.transpose();
  EXPECT_LT(std::abs(fit.radius / kRadius - 1.0), 0.003) << what << ": radius " << fit.radius;
  ASSERT_EQ(fit.views.size(), 3u);
  for (const SphereViewFit& view : fit.views) {
    EXPECT_GT(view.points, view.samples / 2) << what << " " << view.name;
    EXPECT_LT(view.rms_px, 0.5) << what << " " << view.name;
  }
  EXPECT_FALSE(fit.solver_summary.empty());
  std::printf("%s: centre error %.3f mm, radius error %.3f%%, RMS %.3f px (%.3f mm)\n", what.c_str(),
              1e3 * (fit.center - center).norm(), 100.0 * (fit.radius / kRadius - 1.0), fit.rms_px, fit.rms_mm);
}

// The outline of the sphere in a view is where rays start to meet it: each outline point
// of the true sphere, moved half a pixel out along the ray fan, misses the sphere, and half
// a pixel in, meets it (an independent check of the projection through the lens).
TEST(SphereOutline, ProjectedOutlineIsWhereRaysGrazeTheSphere) {
  const PinholeCamera camera = view_camera(20.0, 0);
  const std::vector<Vec2d> outline = sphere_outline(camera, kCenter, kRadius, 64);
  ASSERT_EQ(outline.size(), 64u);
  Vec2d middle = Vec2d::Zero();
  for (const Vec2d& p : outline) middle += p / 64.0;
  for (const Vec2d& p : outline) {
    const Vec2d out = (p - middle).normalized();
    for (const double step : {-0.5, 0.5}) {
      const Vec2d film = p + step * out;
      const Ray ray = camera.generate_ray(float(film.x()), float(film.y()));
      const bool hit =
          reflect_off_ball(ray.origin.cast<double>(), ray.direction.cast<double>(), {kCenter, kRadius}).has_value();
      EXPECT_EQ(hit, step < 0.0) << "outline point " << p.transpose() << " step " << step;
    }
  }
}

TEST(SphereOutline, RedSphereInTheOffice) {
  std::vector<SphereView> views = render_views("procedural:office", 0.04f, {0.8f, 0.1f, 0.1f});
  expect_located(locate_sphere(views), kCenter, "red, office");
  degrade_like_a_merge(views);
  expect_located(locate_sphere(views), kCenter, "red, office, 8-bit merge");
}

TEST(SphereOutline, WhiteSphereUnderARealMap) {
  GLAZE_REQUIRE_ENVMAP(map, "st_fagans_interior_1k.hdr");
  std::vector<SphereView> views = render_views(map.string(), 0.04f, {0.8f, 0.8f, 0.8f});
  expect_located(locate_sphere(views), kCenter, "white, st_fagans");
  degrade_like_a_merge(views);
  expect_located(locate_sphere(views), kCenter, "white, st_fagans, 8-bit merge");
}

// Masks given (each pixel on the sphere when most of it is, by 4 x 4 rays): the outline is
// their boundary, whatever the image shows (here: nothing at all).
TEST(SphereOutline, MasksGiveTheOutline) {
  std::vector<SphereView> views;
  for (int v = 0; v < 3; ++v) {
    SphereView view;
    view.camera = view_camera(20.0 + 120.0 * v, v);
    view.name = view.camera.name;
    view.image = Image(kWidth, kHeight);
    view.mask.assign(size_t(kWidth) * kHeight, 0.0f);
    for (int j = 0; j < kHeight; ++j)
      for (int i = 0; i < kWidth; ++i) {
        int hits = 0;
        for (int s = 0; s < 16; ++s) {
          const Ray ray = view.camera.generate_ray(i + (s % 4 + 0.5f) / 4, j + (s / 4 + 0.5f) / 4);
          hits +=
              reflect_off_ball(ray.origin.cast<double>(), ray.direction.cast<double>(), {kCenter, kRadius}).has_value();
        }
        view.mask[size_t(j) * kWidth + i] = hits > 8 ? 1.0f : 0.0f;
      }
    views.push_back(std::move(view));
  }
  expect_located(locate_sphere(views), kCenter, "masks");
}

// The sphere moved by 1 cm in the last view: that view disagrees and is named.
TEST(SphereOutline, AViewWhereTheSphereMovedDisagrees) {
  std::vector<SphereView> views = render_views("procedural:office", 0.04f, {0.8f, 0.1f, 0.1f});
  views[2] = std::move(render_views("procedural:office", 0.04f, {0.8f, 0.1f, 0.1f}, kCenter + Vec3d(0.01, 0, 0))[2]);
  try {
    locate_sphere(views);
    FAIL() << "a view where the sphere moved was accepted";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("disagree"), std::string::npos) << message;
    EXPECT_NE(message.find("view_002"), std::string::npos) << message;
  }
}

// A view without the sphere (it stands 50 m below the board there, out of the picture):
// the error names that view.
TEST(SphereOutline, AViewWithoutTheSphereIsNamed) {
  std::vector<SphereView> views = render_views("procedural:office", 0.04f, {0.8f, 0.8f, 0.8f});
  views[1] = std::move(render_views("procedural:office", 0.04f, {0.8f, 0.8f, 0.8f}, Vec3d(0, 0, -50), 2)[1]);
  try {
    locate_sphere(views);
    FAIL() << "a view without the sphere was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("view_001"), std::string::npos) << error.what();
  }
}

TEST(SphereOutline, OneViewIsNotEnough) {
  std::vector<SphereView> views = render_views("procedural:office", 0.04f, {0.8f, 0.1f, 0.1f}, kCenter, 1);
  try {
    locate_sphere(views);
    FAIL() << "one view was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("at least 2 views"), std::string::npos) << error.what();
  }
}

// A landscape-like map: a bright sky over a darker ground, both with detail (each texel of
// 64 x 32 log-normal, 50% in its log), which the sphere's rim mirrors.
Environment detailed_landscape() {
  Image map(64, 32);
  Pcg32 rng(19);
  for (int j = 0; j < map.height; ++j)
    for (int i = 0; i < map.width; ++i) {
      const float detail = std::exp(0.5f * standard_normal(rng));
      const float level = j < map.height / 2 ? 3.0f : 0.6f;
      map.set(i, j, level * detail * RGB(0.8f, 0.9f, 1.0f));
    }
  return Environment(std::move(map), board_up(), "landscape");
}

// Under a detailed map the rim mirrors detail that the outline's hinges cannot follow:
// the views' edges come out displaced, each part of the outline its own way. Given the
// lighting, the rim's mirror is modelled and the outline follows the sphere again.
TEST(SphereOutline, TheRimsMirrorOfADetailedMapIsModelledUnderTheLighting) {
  const Environment landscape = detailed_landscape();
  const std::vector<SphereView> views = render_views(landscape, 0.04f, {0.8f, 0.8f, 0.8f});
  const SphereFit hinges = locate_sphere(views);
  const SphereFit mirrored = locate_sphere(views, {}, &landscape);
  expect_located(hinges, kCenter, "landscape, hinges only");
  expect_located(mirrored, kCenter, "landscape, the rim's mirror");
  for (const SphereViewFit& view : mirrored.views) {
    EXPECT_TRUE(view.rim_mirror) << view.name;
    // The views' radiance is the lighting's: the scale read off their backgrounds is 1.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(view.lighting_scale[c], 1.0, 0.02) << view.name;
  }
  EXPECT_LT(1e3 * (mirrored.center - kCenter).norm(), 0.5 * 1e3 * (hinges.center - kCenter).norm());
  EXPECT_LT(mirrored.rms_px, 0.8 * hinges.rms_px);
}

// A lighting that is not what the views show past the sphere (here: another place's, the
// office's, for photos taken in the landscape) is not used: no view's background agrees
// with it, and the outline is located as without a lighting.
TEST(SphereOutline, ALightingTheBackgroundDisagreesWithIsNotUsed) {
  const Environment landscape = detailed_landscape();
  const std::vector<SphereView> views = render_views(landscape, 0.04f, {0.8f, 0.8f, 0.8f});
  const Environment office = make_environment("procedural:office", board_up(), 256, 128);
  const SphereFit fit = locate_sphere(views, {}, &office);
  for (const SphereViewFit& view : fit.views) EXPECT_FALSE(view.rim_mirror) << view.name;
  const SphereFit hinges = locate_sphere(views);
  EXPECT_EQ(fit.center, hinges.center);
  EXPECT_EQ(fit.radius, hinges.radius);
}

}  // namespace
}  // namespace glaze::testing
