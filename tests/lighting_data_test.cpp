// Tests of the lighting fit's gathered data (inverse/lighting_fit.h): taking the diffuse
// term's bands above the fit's lmax off the observations (take_off_diffuse_bands), checked
// against the sh integrator, which renders a diffuse sum cut at its --lmax: the same
// captures rendered at lmax 16, less the bands 5-16 of the true lighting, are the ones
// rendered at lmax 4.
#include "inverse/capture_scene.h"
#include "inverse/lighting_fit.h"
#include "inverse/samples.h"
#include "renderer/material.h"
#include "renderer/ray_tracer.h"
#include "test_support.h"

#include <gtest/gtest.h>

namespace glaze {
namespace {

using testing::TemporaryDirectory;

struct Captured {
  CaptureSet captures;
  Scene object;
  SampleSet samples;
};

// The capture set of the white sphere in the blue room (the lighting whose bands above 4
// carry the most), rendered by the sh integrator at `lmax` with one ray per pixel.
std::string render(const TemporaryDirectory& dir, int lmax) {
  const std::string folder = dir.file("lmax" + std::to_string(lmax));
  const testing::CommandResult run =
      testing::run_glaze("render " + testing::scenes_dir() + "white_sphere_blue_room.gltf --captures " + folder +
                             " --integrator sh --ss 1 --res 96x96 --lmax " + std::to_string(lmax),
                         dir);
  EXPECT_EQ(run.exit_code, 0) << run.err;
  return folder;
}

// The set in `folder` and its samples: pixel samples, or `points` points.
Captured capture(const std::string& folder, int points) {
  Captured c{read_transforms(folder + "/transforms.json"), {}, {}};
  c.object = capture_object_scene(c.captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  const RayTracer tracer(c.object);
  SampleOptions options;
  options.points = points;
  c.samples = collect_samples(c.captures, tracer, c.object, options);
  return c;
}

// The true bands 5-16 under the set's material.
DiffuseBandsAbove true_bands(const CaptureSet& captures) {
  const EnvironmentSpec truth = *capture_environment(captures);
  const Environment environment = make_environment(truth.source, truth.options, truth.width, truth.height);
  const PolishedMaterial& material = captures.material->material;
  return {environment.sh(16), kDiffuseNormalisation * (1.0 - double(material.R0())) * material.Rd().cast<double>()};
}

// RMS difference between two sets of observations, relative to the second's RMS.
double relative_difference(const std::vector<RGB>& a, const std::vector<RGB>& b) {
  double squared = 0.0, reference = 0.0;
  for (size_t k = 0; k < a.size(); ++k) {
    squared += (a[k] - b[k]).cast<double>().square().sum();
    reference += b[k].cast<double>().square().sum();
  }
  return std::sqrt(squared / reference);
}

// Pixel samples, and point samples, which are read bilinearly between four pixels and
// modelled by the same blend of the pixels' rows: the bands come off each pixel's share.
TEST(LightingData, TakingOffTheBandsAboveLmaxGivesTheBandLimitedCaptures) {
  TemporaryDirectory dir;
  const std::string full_folder = render(dir, 16), limited_folder = render(dir, 4);
  for (const int points : {0, 2000}) {
    SCOPED_TRACE(points ? "point samples" : "pixel samples");
    const Captured full = capture(full_folder, points), limited = capture(limited_folder, points);
    ASSERT_EQ(full.samples.samples.size(), limited.samples.samples.size());
    const RayTracer full_tracer(full.object), limited_tracer(limited.object);
    LightingData data = gather_lighting_data(full.samples, full.captures, full_tracer, 4, 1, /*noise_free=*/true);
    const LightingData expected =
        gather_lighting_data(limited.samples, limited.captures, limited_tracer, 4, 1, /*noise_free=*/true);
    // The bands are not negligible: the captures differ by over 1% (relative RMS) before.
    const double before = relative_difference(data.observed, expected.observed);
    EXPECT_GT(before, 0.01);
    take_off_diffuse_bands(data, full.samples, true_bands(full.captures));
    EXPECT_EQ(data.diffuse_lmax, 16);
    // After: equal to float rounding (the two renders sum the bands in other orders).
    const double after = relative_difference(data.observed, expected.observed);
    EXPECT_LT(after, 1e-6);
    std::printf("%s samples: difference %.2e before, %.2e after (relative RMS)\n", points ? "point" : "pixel", before,
                after);
    // The observations' moments were formed again, and agree with the band-limited set's.
    for (const auto& [moment, reference] :
         {std::pair(&data.ao, &expected.ao), std::pair(&data.bo, &expected.bo), std::pair(&data.co, &expected.co)})
      EXPECT_LT((*moment - *reference).cwiseAbs().maxCoeff(), 2e-5 * reference->cwiseAbs().maxCoeff());
    EXPECT_LT((data.oo - expected.oo).cwiseAbs().maxCoeff(), 2e-5 * expected.oo.maxCoeff());
    // The rows and their own moments are the geometry's, left as they were.
    EXPECT_LT((data.cc - expected.cc).cwiseAbs().maxCoeff(), 1e-9 * expected.cc.cwiseAbs().maxCoeff());
  }
}

// The taps the bands are taken through are those the diffuse rows were formed from: with
// 4 x 4 rays per pixel and point samples (four pixels each), c = sum over a sample's taps
// of share_g Lambda_l h_l Y(normal), and the shares add up to the rays' mean g.
TEST(LightingData, TapsAreWhatTheDiffuseRowsWereFormedFrom) {
  TemporaryDirectory dir;
  const Captured points = capture(render(dir, 4), 2000);
  const RayTracer tracer(points.object);
  const LightingData data = gather_lighting_data(points.samples, points.captures, tracer, 4, 4, /*noise_free=*/true);
  const size_t count = points.samples.samples.size();
  ASSERT_EQ(data.first_tap.size(), count + 1);
  EXPECT_GT(data.first_tap.back(), 3 * count);  // most points blend four pixels
  const int n = sh_count(4);
  std::vector<float> basis(n);
  double worst = 0.0;
  for (size_t k = 0; k < count; ++k) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(n);
    for (size_t tap = data.first_tap[k]; tap < data.first_tap[k + 1]; ++tap) {
      sh_eval<float>(4, data.tap_normal[tap], basis);
      for (int l = 0; l <= 4; ++l)
        for (int m = -l; m <= l; ++m)
          c[sh_index(l, m)] += data.tap_share_g[tap] * sh_lambda(l) * sh_kernel_coefficient(l) * basis[sh_index(l, m)];
    }
    worst =
        std::max(worst, (c - data.c_row(k).cast<double>()).cwiseAbs().maxCoeff() / std::abs(double(data.c_row(k)[0])));
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(LightingData, BandsAreNotTakenOffDataOfOtherSamples) {
  TemporaryDirectory dir;
  const Captured full = capture(render(dir, 16), 0);
  const RayTracer tracer(full.object);
  LightingData data = gather_lighting_data(full.samples, full.captures, tracer, 4, 1, /*noise_free=*/true);
  SampleSet fewer = full.samples;
  fewer.samples.pop_back();
  const std::vector<RGB> observed = data.observed;
  EXPECT_THROW(take_off_diffuse_bands(data, fewer, true_bands(full.captures)), Error);
  EXPECT_EQ(relative_difference(data.observed, observed), 0.0);  // left whole
}

}  // namespace
}  // namespace glaze
