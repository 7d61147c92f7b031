// Tests of the path tracer and the tile renderer against closed forms (furnace), each
// other (three unbiased estimators), a direct numerical integral of the shading
// integral, and themselves across thread counts (determinism).
#include "renderer/environment.h"
#include "renderer/latlong.h"
#include "renderer/path_tracer.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace glaze {
namespace {

using testing::front_camera;
using testing::sphere_scene;

// Pixels whose whole footprint lies well inside the sphere's silhouette.
std::vector<std::pair<int, int>> interior_pixels(const PinholeCamera& camera, float margin = 0.9f) {
  std::vector<std::pair<int, int>> pixels;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      bool inside = true;
      for (float dy : {0.0f, 1.0f})
        for (float dx : {0.0f, 1.0f}) {
          const Ray ray = camera.generate_ray(x + dx, y + dy);
          // distance of the sphere centre from the ray
          const float along = -ray.origin.dot(ray.direction);
          inside = inside && (ray.origin + along * ray.direction).norm() < margin;
        }
      if (inside) pixels.emplace_back(x, y);
    }
  return pixels;
}

RenderResult render_scene(const Scene& scene, const Environment& env, const PinholeCamera& camera, int spp,
                          uint64_t seed, DirectLightEstimator estimator = DirectLightEstimator::mis, int threads = 0,
                          int max_depth = 8) {
  const RayTracer tracer(scene);
  PathTracerOptions options;
  options.estimator = estimator;
  options.black_background = true;
  options.max_depth = max_depth;
  const PathTracer path_tracer(scene, tracer, env, options);
  return render(path_tracer, camera, {spp, 0.0, seed, threads, false, false});
}

TEST(PathTracer, WhiteFurnaceIsExactlyOneWithBsdfSampling) {
  // Rd = 1 under radiance 1: the lobe choice and the diffuse sampling are exact, so every
  // BSDF-sampled path carries exactly 1.
  const Environment constant(make_procedural_environment("constant", 16, 8), {});
  const PinholeCamera camera = front_camera(24);
  for (float R0 : {0.0f, 0.04f, 0.5f, 1.0f}) {
    const Scene scene = sphere_scene(R0, RGB::Ones());
    const Image image = render_scene(scene, constant, camera, 4, 1, DirectLightEstimator::bsdf).image;
    for (const auto& [x, y] : interior_pixels(camera))
      ASSERT_LT((image.at(x, y) - RGB::Ones()).abs().maxCoeff(), 1e-5f) << "R0 " << R0 << " pixel " << x << "," << y;
  }
}

TEST(PathTracer, WhiteFurnaceAveragesOneWithMis) {
  const Environment constant(make_procedural_environment("constant", 16, 8), {});
  const PinholeCamera camera = front_camera(32);
  for (float R0 : {0.0f, 0.04f, 0.5f, 1.0f}) {
    const Scene scene = sphere_scene(R0, RGB::Ones());
    const Image a = render_scene(scene, constant, camera, 32, 1).image;
    const Image b = render_scene(scene, constant, camera, 32, 2).image;
    double sum = 0, difference_squares = 0;
    const auto pixels = interior_pixels(camera);
    for (const auto& [x, y] : pixels) {
      sum += a.at(x, y)[1] + b.at(x, y)[1];
      difference_squares += std::pow(a.at(x, y)[1] - b.at(x, y)[1], 2);
    }
    const double mean = sum / (2 * pixels.size());
    EXPECT_NEAR(mean, 1.0, 0.005) << "R0 " << R0;
    // Each pixel within noise: the spread of two independent renders gives sigma.
    const double sigma = std::sqrt(difference_squares / pixels.size() / 2) + 1e-6;
    for (const auto& [x, y] : pixels) ASSERT_LT(std::abs(a.at(x, y)[1] - 1.0), 6 * sigma + 1e-5) << x << "," << y;
  }
}

// Mean over the interior pixels of `renders` independent images per estimator, and
// the standard error of that mean from their spread.
std::pair<RGBd, RGBd> region_mean(const Scene& scene, const Environment& env, const PinholeCamera& camera,
                                  DirectLightEstimator estimator, int renders, int spp) {
  const auto pixels = interior_pixels(camera, 0.95f);
  std::vector<RGBd> means;
  for (int r = 0; r < renders; ++r) {
    const Image image = render_scene(scene, env, camera, spp, 100 + r, estimator).image;
    RGBd sum = RGBd::Zero();
    for (const auto& [x, y] : pixels) sum += image.at(x, y).cast<double>();
    means.push_back(sum / pixels.size());
  }
  RGBd mean = RGBd::Zero(), variance = RGBd::Zero();
  for (const RGBd& m : means) mean += m / renders;
  for (const RGBd& m : means) variance += (m - mean) * (m - mean) / (renders - 1);
  return {mean, (variance / renders).sqrt()};
}

void expect_estimators_agree(const Environment& env, const char* label) {
  const Scene scene = sphere_scene(0.0452f, RGB(0.9765f, 0.0186f, 0.2f));
  const PinholeCamera camera = front_camera(24);
  const auto [mis, mis_error] = region_mean(scene, env, camera, DirectLightEstimator::mis, 8, 16);
  const auto [bsdf, bsdf_error] = region_mean(scene, env, camera, DirectLightEstimator::bsdf, 8, 16);
  const auto [light, light_error] = region_mean(scene, env, camera, DirectLightEstimator::environment, 8, 16);
  for (int c = 0; c < 3; ++c) {
    EXPECT_LT(std::abs(mis[c] - bsdf[c]), 3 * std::hypot(mis_error[c], bsdf_error[c]) + 1e-6)
        << label << " channel " << c;
    EXPECT_LT(std::abs(mis[c] - light[c]), 3 * std::hypot(mis_error[c], light_error[c]) + 1e-6)
        << label << " channel " << c;
    EXPECT_LT(std::abs(bsdf[c] - light[c]), 3 * std::hypot(bsdf_error[c], light_error[c]) + 1e-6)
        << label << " channel " << c;
  }
  // MIS is never much worse than the better of the two (a sanity check on its weights).
  EXPECT_LT(mis_error[0], 1.5 * std::min(bsdf_error[0], light_error[0]) + 1e-6) << label;
}

TEST(PathTracer, ConvexShortcutAgreesWithTheGeneralPathTracer) {
  // The single-sphere estimator (mirror split off, no shadow rays, batched) against the
  // general path tracer on the same scene: both unbiased, so equal within noise.
  const Environment office(make_procedural_environment("office", 256, 128), {.rotation_degrees = 40});
  const Scene scene = sphere_scene(0.0452f, RGB(0.9765f, 0.0186f, 0.2f));
  const PinholeCamera camera = front_camera(24);
  const RayTracer tracer(scene);
  const auto pixels = interior_pixels(camera, 0.95f);
  std::array<std::vector<RGBd>, 2> means;
  for (int shortcut = 0; shortcut < 2; ++shortcut) {
    PathTracerOptions options;
    options.convex_shortcut = shortcut == 1;
    const PathTracer path_tracer(scene, tracer, office, options);
    EXPECT_EQ(path_tracer.max_depth(), shortcut ? 1 : 8);
    for (int seed = 0; seed < 8; ++seed) {
      const Image image = render(path_tracer, camera, {16, 0.0, uint64_t(seed), 0, false}).image;
      RGBd sum = RGBd::Zero();
      for (const auto& [x, y] : pixels) sum += image.at(x, y).cast<double>();
      means[shortcut].push_back(sum / pixels.size());
    }
  }
  RGBd mean[2], error[2];
  for (int i = 0; i < 2; ++i) {
    mean[i] = error[i] = RGBd::Zero();
    for (const RGBd& m : means[i]) mean[i] += m / 8.0;
    for (const RGBd& m : means[i]) error[i] += (m - mean[i]) * (m - mean[i]) / (7.0 * 8.0);
    error[i] = error[i].sqrt();
  }
  for (int c = 0; c < 3; ++c)
    EXPECT_LT(std::abs(mean[0][c] - mean[1][c]), 3 * std::hypot(error[0][c], error[1][c]) + 1e-6) << "channel " << c;
}

TEST(PathTracer, EstimatorsAgreeInTheOffice) {
  expect_estimators_agree(Environment(make_procedural_environment("office", 512, 256), {}), "office");
}

TEST(PathTracer, EstimatorsAgreeUnderARealMap) {
  GLAZE_REQUIRE_ENVMAP(path, "st_fagans_interior_1k.hdr");
  expect_estimators_agree(Environment::load(path.string()), "st_fagans");
}

// docs/design.md §2 without SH truncation: F(n.v) L(r) + sum over texels of f_d L cos dOmega,
// with the texel radiance at its centre (the bilinear map agrees to O(texel^2)).
RGB direct_shading(const PolishedMaterial& material, const Environment& env, const Vec3& n, const Vec3& v) {
  const Image& map = env.map();
  RGBd diffuse = RGBd::Zero();
  const Vec3 wo = Frame::from_normal(n).to_local(v);
  for (int j = 0; j < map.height; ++j) {
    const double solid_angle =
        2 * kPiD / map.width * (std::cos(kPiD * j / map.height) - std::cos(kPiD * (j + 1) / map.height));
    for (int i = 0; i < map.width; ++i) {
      const Vec3 w = env.uv_to_direction(Vec2((i + 0.5f) / map.width, (j + 0.5f) / map.height));
      const float mu = n.dot(w);
      if (mu <= 0) continue;
      const Vec3 wi = Frame::from_normal(n).to_local(w);
      diffuse += (material.eval_diffuse(wo, wi) * mu * env.scale() * map.at(i, j)).cast<double>() * solid_angle;
    }
  }
  const Vec3 r = 2 * n.dot(v) * n - v;
  return material.fresnel(n.dot(v)) * env.eval(r) + diffuse.cast<float>();
}

TEST(PathTracer, SphereMatchesDirectIntegralOfTheShadingModel) {
  const Environment env(make_procedural_environment("office", 256, 128), {.rotation_degrees = 20});
  const Scene scene = sphere_scene(0.0452f, RGB(0.9765f, 0.0186f, 0.3f));
  const PolishedMaterial material = scene.material_at(0, Vec2::Zero());
  // A narrow field of view so that one pixel sees an almost constant normal; the
  // reference averages the direct integral over a 4 x 4 grid in the pixel.
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() = Vec3(0, 0, 4);
  const PinholeCamera camera = PinholeCamera::from_vertical_fov("zoom", pose, 0.2f, 64, 64);
  const RayTracer tracer(scene);
  for (const auto& [x, y] : {std::pair{32, 32}, {20, 40}, {45, 14}, {10, 30}}) {
    RGBd reference = RGBd::Zero();
    for (int sy = 0; sy < 4; ++sy)
      for (int sx = 0; sx < 4; ++sx) {
        const Ray ray = camera.generate_ray(x + (sx + 0.5f) / 4, y + (sy + 0.5f) / 4);
        const auto hit = tracer.intersect(ray);
        ASSERT_TRUE(hit.has_value());
        reference += direct_shading(material, env, hit->normal, -ray.direction).cast<double>() / 16.0;
      }
    // Path-traced estimate of this pixel with its standard error over seeds.
    PathTracerOptions options;
    const PathTracer path_tracer(scene, tracer, env, options);
    std::vector<RGBd> estimates;
    for (int seed = 0; seed < 8; ++seed) {
      Pcg32 rng(seed, 7);
      RGBd sum = RGBd::Zero();
      const int n = 4096;
      for (int k = 0; k < n; ++k)
        sum +=
            path_tracer.radiance(camera.generate_ray(x + rng.next_float(), y + rng.next_float()), rng).cast<double>();
      estimates.push_back(sum / n);
    }
    RGBd mean = RGBd::Zero(), variance = RGBd::Zero();
    for (const RGBd& e : estimates) mean += e / 8.0;
    for (const RGBd& e : estimates) variance += (e - mean) * (e - mean) / 7.0;
    const RGBd standard_error = (variance / 8.0).sqrt();
    for (int c = 0; c < 3; ++c)
      EXPECT_LT(std::abs(mean[c] - reference[c]), 4 * standard_error[c] + 2e-3 * reference[c] + 1e-5)
          << "pixel " << x << "," << y << " channel " << c << ": path " << mean[c] << " direct " << reference[c];
  }
}

TEST(ShIntegrator, MatchesTheDirectIntegralUpToSHTruncation) {
  // With one sample per pixel (ss 1) the sh integrator evaluates docs/design.md §2 at the pixel
  // centre; the direct texel sum evaluates it without SH truncation. They differ only by
  // the truncated diffuse term: small at lmax 16, larger at lmax 2.
  const Environment env(make_procedural_environment("office", 256, 128), {.rotation_degrees = 20});
  const Scene scene = sphere_scene(0.0452f, RGB(0.9765f, 0.0186f, 0.3f));
  const PolishedMaterial material = scene.material_at(0, Vec2::Zero());
  const RayTracer tracer(scene);
  const PinholeCamera camera = front_camera(32);
  double error16 = 0, error2 = 0;
  for (const auto& [x, y] : {std::pair{16, 16}, {10, 20}, {22, 9}, {6, 15}, {20, 26}}) {
    const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
    const auto hit = tracer.intersect(ray);
    ASSERT_TRUE(hit.has_value());
    const RGB direct = direct_shading(material, env, hit->normal, -ray.direction);
    const RGB sh16 = render_sh(scene, tracer, env, camera, {16, 1, true, 0}).at(x, y);
    const RGB sh2 = render_sh(scene, tracer, env, camera, {2, 1, true, 0}).at(x, y);
    EXPECT_LT((sh16 - direct).abs().maxCoeff(), 5e-3f * direct.maxCoeff()) << x << "," << y;
    error16 += (sh16 - direct).abs().sum();
    error2 += (sh2 - direct).abs().sum();
  }
  EXPECT_LT(error16, 0.5 * error2);
}

TEST(Render, IsBitIdenticalAcrossThreadCounts) {
  const Environment env(make_procedural_environment("office", 128, 64), {});
  const Scene scene = sphere_scene(0.0452f, RGB(0.9765f, 0.0186f, 0.0f));
  const PinholeCamera camera = front_camera(40);
  const Image one = render_scene(scene, env, camera, 8, 42, DirectLightEstimator::mis, 1).image;
  const Image two = render_scene(scene, env, camera, 8, 42, DirectLightEstimator::mis, 2).image;
  const Image other_seed = render_scene(scene, env, camera, 8, 43, DirectLightEstimator::mis, 2).image;
  EXPECT_EQ(one.pixels, two.pixels);
  EXPECT_NE(one.pixels, other_seed.pixels);
}

// The views of a capture set must carry independent noise, as photographs do: the camera's
// index enters every pixel's streams (render.h). The same camera rendered as index 0 and
// as index 1, same seed, differs by as much as two seeds do (the typical difference
// is the noise's times sqrt 2 either way); with streams keyed by the pixel alone the
// two images were identical, and two views' noise correlated pixel by pixel.
TEST(Render, EachCameraDrawsItsOwnStreams) {
  const Environment env(make_procedural_environment("blue-room", 128, 64), {});
  const Scene scene = sphere_scene(0.04f, RGB(0.8f, 0.8f, 0.8f));
  const PinholeCamera camera = front_camera(96);
  const RayTracer tracer(scene);
  PathTracerOptions path_options;
  path_options.black_background = true;
  const PathTracer path_tracer(scene, tracer, env, path_options);
  auto image = [&](uint64_t seed, uint64_t camera_index) {
    RenderOptions options;
    options.spp = 4;
    options.seed = seed;
    return render(path_tracer, camera, options, camera_index).image;
  };
  const Image first = image(7, 0), other_camera = image(7, 1), other_seed = image(8, 0);
  EXPECT_EQ(other_camera.pixels, image(7, 1).pixels);  // deterministic
  // The median over the sphere's pixel values of |a - b| (robust to the few pixels whose
  // paths found the bright window).
  auto median_difference = [](const Image& a, const Image& b) {
    std::vector<double> differences;
    for (size_t i = 0; i < a.pixels.size(); ++i)
      if (a.pixels[i] > 0.0f) differences.push_back(std::abs(double(a.pixels[i]) - double(b.pixels[i])));
    std::nth_element(differences.begin(), differences.begin() + differences.size() / 2, differences.end());
    return differences[differences.size() / 2];
  };
  const double across_cameras = median_difference(first, other_camera),
               across_seeds = median_difference(first, other_seed);
  std::printf("median |difference|: other camera %.4g, other seed %.4g\n", across_cameras, across_seeds);
  EXPECT_GT(across_seeds, 0.0);
  EXPECT_NEAR(across_cameras / across_seeds, 1.0, 0.1);
}

TEST(PathTracer, SingleSphereUsesOneBounceAndOtherScenesTheirDepth) {
  const Environment env(make_procedural_environment("constant", 8, 4), {});
  Scene sphere = sphere_scene(0.04f, RGB::Ones());
  const RayTracer sphere_tracer(sphere);
  EXPECT_EQ(PathTracer(sphere, sphere_tracer, env, {}).max_depth(), 1);
  sphere.spheres.push_back({"second", Vec3(3, 0, 0), 1.0f, 0, Mat3::Identity()});
  const RayTracer two_tracer(sphere);
  EXPECT_EQ(PathTracer(sphere, two_tracer, env, {}).max_depth(), 8);
}

TEST(PathTracer, BlackGroundHidesHalfOfTheSky) {
  // A sphere (R0 = 0, Rd = 0.5) resting on a huge black sphere (a ground plane) under a
  // constant sky of radiance 1. At the point facing the camera, n = +Z is horizontal: the
  // diffuse lobe is symmetric about the horizon, the ground hides exactly its lower half,
  // and F = 0 there, so Lo = Rd * 1/2 = 0.25. Direct light only (max depth 1): even a
  // black coat mirrors the sky at grazing angles (F -> 1), which would add light here.
  // Checked with shadow rays (MIS and environment sampling) and without (BSDF sampling).
  const Environment sky(make_procedural_environment("constant", 16, 8), {});
  Scene scene = sphere_scene(0.0f, RGB::Constant(0.5f));
  scene.materials.push_back({"black", 0.0f, RGB::Zero(), -1});
  scene.spheres.push_back({"ground", Vec3(0, -1e5f - 1, 0), 1e5f, 1, Mat3::Identity()});  // horizon dip 0.26 deg
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.translation() = Vec3(0, 0, 4);
  const PinholeCamera camera = PinholeCamera::from_vertical_fov("c", pose, 0.02f, 3, 3);  // centre pixel ~ n = +Z
  for (DirectLightEstimator estimator :
       {DirectLightEstimator::mis, DirectLightEstimator::bsdf, DirectLightEstimator::environment}) {
    std::vector<float> values;
    for (int seed = 0; seed < 6; ++seed)
      values.push_back(render_scene(scene, sky, camera, 2048, seed, estimator, 0, 1).image.at(1, 1)[0]);
    double mean = 0, variance = 0;
    for (float v : values) mean += v / values.size();
    for (float v : values) variance += (v - mean) * (v - mean) / (values.size() - 1);
    EXPECT_NEAR(mean, 0.25, 4 * std::sqrt(variance / values.size()) + 2e-3) << "estimator " << int(estimator);
  }
}

}  // namespace
}  // namespace glaze
