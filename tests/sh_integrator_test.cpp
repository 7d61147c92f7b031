// Acceptance of the sh integrator (docs/design.md §2) against converged path-traced references
// of the red sphere scene, in the procedural office and blue room and under real maps.
//
// Both images are point-sampled at pixel centres (RenderOptions::pixel_centres, ss 1),
// so that the comparison measures the shading model and not pixel filtering (the
// anti-aliasing part of the sh error is measured by `glaze convergence`). The reference
// is two independent path-traced halves: their mean is the reference, half their
// difference its noise, which is taken out of the measured error (independent errors add
// in the mean square). What is left is the SH truncation of the diffuse term.
#include "renderer/environment.h"
#include "renderer/image_error.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "renderer/rng.h"
#include "renderer/sh.h"
#include "renderer/sh_integrator.h"
#include "renderer/shading.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

namespace glaze {
namespace {

struct ModelErrors {
  double noise;                   // relative RMSE of the path-traced reference itself
  std::map<int, double> by_lmax;  // sh error beyond that noise
  double truncation4;             // sh at lmax 4 against sh at lmax 32
  double truncation8;             // sh at lmax 8 against sh at lmax 32 (noise-free)
  double unclamped4;              // sh error at lmax 4 without clamping negative diffuse sums
};

// `spp` per half of the reference: the error beyond the reference's noise is
// sqrt(e^2 - noise^2), whose own scatter grows with the noise (about 0.2 of it here), so
// a lighting whose small bright sources make the path tracer noisy needs more.
ModelErrors measure(const std::string& environment_spec, int spp = 1024) {
  const Scene scene = load_scene(std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf");
  const Environment environment = make_environment(environment_spec);
  const RayTracer tracer(scene);
  const PinholeCamera camera = scene.make_camera(scene.camera("view_0"), std::pair(96, 96));
  const std::vector<uint8_t> mask = interior_mask(tracer, camera);
  PathTracerOptions path_options;
  path_options.black_background = true;
  const PathTracer path_tracer(scene, tracer, environment, path_options);
  RenderOptions options;
  options.spp = spp;
  options.pixel_centres = true;
  options.seed = 11;
  const Image first = render(path_tracer, camera, options).image;
  options.seed = 12;
  const Image second = render(path_tracer, camera, options).image;
  Image reference = first;
  for (size_t i = 0; i < reference.pixels.size(); ++i)
    reference.pixels[i] = 0.5f * (first.pixels[i] + second.pixels[i]);

  ModelErrors errors;
  errors.noise = 0.5 * image_error(first, second, mask).relative_rmse;
  auto sh = [&](int lmax) { return render_sh(scene, tracer, environment, camera, {lmax, 1, true, 0}); };
  for (int lmax : {2, 4, 8, 16}) {
    const double measured = image_error(sh(lmax), reference, mask).relative_rmse;
    errors.by_lmax[lmax] = std::sqrt(std::max(0.0, measured * measured - errors.noise * errors.noise));
  }
  const Image converged = sh(32);
  errors.truncation4 = image_error(sh(4), converged, mask).relative_rmse;
  errors.truncation8 = image_error(sh(8), converged, mask).relative_rmse;
  const Image unclamped = render_sh(scene, tracer, environment, camera, {4, 1, true, 0, false});
  const double measured = image_error(unclamped, reference, mask).relative_rmse;
  errors.unclamped4 = std::sqrt(std::max(0.0, measured * measured - errors.noise * errors.noise));
  std::printf(
      "%s: reference noise %.3f%%, sh error beyond it: lmax 2 %.3f%%, 4 %.3f%%, 8 %.3f%%, 16 %.3f%%; "
      "truncation (vs lmax 32) at lmax 4 %.3f%%, 8 %.3f%%, lmax 4 unclamped %.3f%%\n",
      environment_spec.c_str(), 100 * errors.noise, 100 * errors.by_lmax[2], 100 * errors.by_lmax[4],
      100 * errors.by_lmax[8], 100 * errors.by_lmax[16], 100 * errors.truncation4, 100 * errors.truncation8,
      100 * errors.unclamped4);
  return errors;
}

// What holds for any lighting: the path tracer and the SH model agree up to the SH
// truncation of the diffuse term (which the sh model alone measures against lmax 32),
// and the error falls with lmax toward the reference's noise.
void expect_model_agrees_up_to_truncation(const ModelErrors& e) {
  EXPECT_NEAR(e.by_lmax.at(4), e.truncation4, 0.002 + 0.1 * e.truncation4);
  EXPECT_LT(e.by_lmax.at(16), 0.004);
  EXPECT_LE(e.by_lmax.at(8), e.by_lmax.at(2) + 0.001);
  EXPECT_LE(e.by_lmax.at(16), e.by_lmax.at(4) + 0.001);
}

TEST(ShIntegratorAcceptance, OfficeWithinOnePercentAtLmax4) {
  const ModelErrors e = measure("procedural:office");
  expect_model_agrees_up_to_truncation(e);
  EXPECT_LT(e.by_lmax.at(4), 0.01);
}

// The blue room's two projector spots are small and bright: the diffuse response to a
// near point light has energy far beyond l = 4, and lmax 4 is not within 1% here (the
// measured figure is printed and reported); lmax 8 is: its truncation, noise-free, is
// under 1%, and the path tracer agrees with it. The spots also make the path tracer
// noisy (3.1% at 1024 spp per half): 8192 per half brings that to 1.1%, and the error
// beyond the noise scatters by about 0.2% of it.
TEST(ShIntegratorAcceptance, BlueRoomWithinOnePercentAtLmax8) {
  const ModelErrors e = measure("procedural:blue-room", 8192);
  expect_model_agrees_up_to_truncation(e);
  EXPECT_LT(e.truncation8, 0.01);
  EXPECT_NEAR(e.by_lmax.at(8), e.truncation8, 0.003);
}

// Every real map: lmax 8 within 1%. lmax 4 is within 1% under the three maps whose
// light comes from large areas (St Fagans, Lebombo, Potsdamer Platz; measured 0.45%,
// 0.29%, 0.41%), not under the two with small bright sources (Grace's windows
// 1.44%, studio_small_03's 3e5:1 lamps 1.68%; their truncation alone, noise-free
// against lmax 32, is the same 1.46% and 1.69%): the paper's model, not the renderer.
TEST(ShIntegratorAcceptance, RealMapsAgreeUpToTruncation) {
  for (const auto& [name, spread] : {std::pair("st_fagans_interior_1k.hdr", true), std::pair("lebombo_1k.hdr", true),
                                     std::pair("grace_latlong.exr", false), std::pair("studio_small_03_1k.hdr", false),
                                     std::pair("potsdamer_platz_1k.hdr", true)}) {
    GLAZE_REQUIRE_ENVMAP(path, name);
    SCOPED_TRACE(name);
    const ModelErrors e = measure(path.string());
    expect_model_agrees_up_to_truncation(e);
    EXPECT_LT(e.by_lmax.at(8), 0.01);
    if (spread) {
      EXPECT_LT(e.by_lmax.at(4), 0.01);
    }
  }
}

// Stiff cases: a near-mirror, a black base, grazing silhouettes and a 1e5:1 "sun" of one
// texel. The images stay finite and non-negative; where the truncated SH diffuse sum
// rings below zero (on the side turned away from the sun), the integrator clamps the
// irradiance at zero: negative light is truncation, never physics.
Image sun_map(float contrast) {
  Image map(64, 32);
  for (float& value : map.pixels) value = 1.0f;
  map.set(20, 8, RGB::Constant(contrast));
  return map;
}

using testing::front_camera;
using testing::sphere_scene;

TEST(ShIntegratorStiff, SunRingsBelowZeroAndIsClampedThere) {
  const Environment sun(sun_map(1e5f), {});
  const ShDiffuseSum diffuse_sum(sun.sh(4));
  // The sun's direction, and the sphere of normals: some see a negative truncated sum.
  const Vec3 towards_sun = sun.uv_to_direction(Vec2(20.5f / 64, 8.5f / 32));
  int negative = 0, total = 0;
  Pcg32 rng(3);
  for (int k = 0; k < 4000; ++k, ++total) {
    const float z = 2.0f * rng.next_float() - 1.0f, phi = 2.0f * kPi * rng.next_float();
    const float r = std::sqrt(std::max(0.0f, 1.0f - z * z));
    negative += diffuse_sum(Vec3(r * std::cos(phi), r * std::sin(phi), z))[0] < 0.0f;
  }
  EXPECT_GT(diffuse_sum(towards_sun)[0], 0.0f);
  EXPECT_GT(negative, total / 50) << "expected SH ringing below zero away from a 1e5:1 sun at lmax 4";
  std::printf("1e5:1 sun at lmax 4: %.1f%% of normals see a negative truncated diffuse sum\n",
              100.0 * negative / total);

  const Scene scene = sphere_scene(0.04f, RGB(0.8f, 0.5f, 0.2f));
  const RayTracer tracer(scene);
  const Image image = render_sh(scene, tracer, sun, front_camera(64), {4, 2, true, 0});
  for (float value : image.pixels) {
    ASSERT_TRUE(std::isfinite(value));
    ASSERT_GE(value, 0.0f);
  }
}

TEST(ShIntegratorStiff, MirrorBlackBaseAndGrazingViewsStayFinite) {
  const Environment sun(sun_map(3e5f), {});
  const PinholeCamera camera = front_camera(64);
  for (const auto& [R0, Rd] :
       {std::pair(0.999f, RGB::Zero()), std::pair(0.0f, RGB::Zero()), std::pair(0.04f, RGB::Ones())}) {
    const Scene scene = sphere_scene(R0, Rd);
    const RayTracer tracer(scene);
    const Image image = render_sh(scene, tracer, sun, camera, {4, 4, true, 0});
    PathTracerOptions path_options;
    path_options.black_background = true;
    const PathTracer path_tracer(scene, tracer, sun, path_options);
    RenderOptions options;
    options.spp = 16;
    const Image path = render(path_tracer, camera, options).image;
    for (size_t i = 0; i < image.pixels.size(); ++i) {
      ASSERT_TRUE(std::isfinite(image.pixels[i]) && image.pixels[i] >= 0.0f) << "sh, R0 " << R0;
      ASSERT_TRUE(std::isfinite(path.pixels[i]) && path.pixels[i] >= 0.0f)
          << "path, R0 " << R0 << " value " << path.pixels[i];
    }
    if (Rd.maxCoeff() == 0.0f) {
      // A black base reflects only the coat's mirror: F(n.v) L(r) at every sample.
      const int x = 32, y = 32;
      const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
      const SurfaceHit hit = *tracer.intersect(ray);
      const float mu = hit.normal.dot(-ray.direction);
      const RGB expected = PolishedMaterial(R0, Rd).fresnel(mu) * sun.eval(reflect(-ray.direction, hit.normal));
      EXPECT_LT((render_sh(scene, tracer, sun, camera, {4, 1, true, 0}).at(x, y) - expected).abs().maxCoeff(),
                1e-6f * (1.0f + expected.maxCoeff()));
    }
  }
}

// Refinement re-renders a pixel on a finer grid where its K x K samples show an edge:
// every pixel of the refined image is the uniform K x K image's or a uniform M x M
// image's for some K < M <= 8 (the same rays, so to rounding); the silhouette (on a black
// background) is refined and most pixels are not; and the result is about as close to a
// uniform 16 x 16 image as the uniform 8 x 8 one is, far closer than the K x K one.
TEST(ShIntegratorSampling, RefinedPixelsTakeAFinerGridWhereTheCoarseSamplesShowAnEdge) {
  const Scene scene = load_scene(std::string(GLAZE_SOURCE_DIR) + "/scenes/red_sphere_office.gltf");
  const Environment environment = make_environment("procedural:office");
  const RayTracer tracer(scene);
  const PinholeCamera camera = scene.make_camera(scene.camera("view_0"), std::pair(128, 128));
  ShIntegratorOptions options{4, 2, true, 0};
  std::map<int, Image> uniform;  // by grid size
  for (int grid : {2, 3, 4, 5, 6, 7, 8, 16}) {
    options.supersampling = grid;
    uniform[grid] = render_sh(scene, tracer, environment, camera, options);
  }
  options.supersampling = 2;
  options.refined_supersampling = 8;
  const Image refined = render_sh(scene, tracer, environment, camera, options);
  const Image& coarse = uniform[2];
  const Image& finest = uniform[16];
  int refined_pixels = 0, silhouette_pixels = 0, silhouette_refined = 0;
  double refined_error = 0.0, coarse_error = 0.0, eight_error = 0.0;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const RGB value = refined.at(x, y);
      auto same = [&](const Image& other) {
        return ((value - other.at(x, y)).abs() <= RGB::Constant(1e-5f) * (1.0f + other.at(x, y).abs())).all();
      };
      int grid = 0;  // the coarsest uniform grid it is
      for (const auto& [size, image] : uniform)
        if (grid == 0 && size <= 8 && same(image)) grid = size;
      ASSERT_GT(grid, 0) << "pixel " << x << ", " << y << " is none of the uniform images";
      refined_pixels += grid > 2;
      // On the sphere beside a pixel off it (a black background): the samples step.
      bool silhouette = false;
      for (const auto& [dx, dy] : {std::pair(-1, 0), std::pair(1, 0), std::pair(0, -1), std::pair(0, 1)})
        silhouette |= x + dx >= 0 && x + dx < camera.width && y + dy >= 0 && y + dy < camera.height &&
                      coarse.at(x, y).maxCoeff() > 0.0f && coarse.at(x + dx, y + dy).maxCoeff() == 0.0f;
      silhouette_pixels += silhouette;
      silhouette_refined += silhouette && grid > 2;
      refined_error += (value - finest.at(x, y)).square().sum();
      coarse_error += (coarse.at(x, y) - finest.at(x, y)).square().sum();
      eight_error += (uniform[8].at(x, y) - finest.at(x, y)).square().sum();
    }
  std::printf(
      "refined %d of %d pixels (%d on the silhouette); squared error against 16 x 16: %.3g of 2 x 2's, "
      "%.3g of 8 x 8's\n",
      refined_pixels, camera.width * camera.height, silhouette_pixels, refined_error / coarse_error,
      refined_error / eight_error);
  EXPECT_GT(silhouette_pixels, 20);
  EXPECT_EQ(silhouette_refined, silhouette_pixels);
  EXPECT_GT(refined_pixels, silhouette_pixels);                 // the reflected window's edges too
  EXPECT_LT(refined_pixels, camera.width * camera.height / 4);  // but not the smooth parts
  EXPECT_LT(refined_error, 0.02 * coarse_error);
  EXPECT_LT(refined_error, 2.0 * eight_error);
}

}  // namespace
}  // namespace glaze
