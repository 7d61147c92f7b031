// The light probe from a mirror ball (inverse/photos/mirror_ball_probe.h): the reflection
// geometry against reflect_off_ball, and probes from photos rendered here (reflect_off_ball
// and Environment::eval, each pixel the mean of 3x3 rays) through three distorted cameras,
// each with a dark camera and tripod in its own photo, against the true lighting.
#include "inverse/photos/mirror_ball_probe.h"

#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/output_folder.h"
#include "renderer/procedural_environment.h"
#include "renderer/rng.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace glaze {
namespace {

const MirrorBall kBall{Vec3d(0.10, 0.08, 0.07), 0.05};
constexpr float kDark = 0.01f;  // the camera's and tripod's radiance

// A 320x240 camera with a barrel lens, `distance` from the ball at `elevation` and
// `azimuth` (degrees, board frame, z up), looking at the ball.
PinholeCamera probe_camera(double azimuth, double elevation = 30.0, double distance = 0.5) {
  const double a = azimuth * kPiD / 180.0, e = elevation * kPiD / 180.0;
  const Vec3d origin =
      kBall.center + distance * Vec3d(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
  const Vec3d forward = (kBall.center - origin).normalized();
  const Vec3d right = forward.cross(Vec3d::UnitZ()).normalized();
  const Vec3d up = right.cross(forward);
  Eigen::Matrix3d rotation;
  rotation << right, up, -forward;
  PinholeCamera camera;
  camera.name = "az" + std::to_string(int(azimuth));
  camera.camera_to_world.linear() = rotation.cast<float>();
  camera.camera_to_world.translation() = origin.cast<float>();
  camera.width = 320, camera.height = 240;
  camera.fl_x = 900, camera.fl_y = 900, camera.cx = 162.5f, camera.cy = 118.0f;
  camera.distortion.model = LensDistortion::Model::opencv;
  camera.distortion.k1 = -0.12, camera.distortion.k2 = 0.05, camera.distortion.p1 = 0.001;
  camera.distortion.p2 = -0.0005;
  return camera;
}

// Whether the ray from p along unit d meets the camera at `origin`: a ball of 4 cm about
// it, or its tripod, a vertical pole of radius 1.5 cm down to z = -1.
bool hits_camera(const Vec3d& p, const Vec3d& d, const Vec3d& origin) {
  const Vec3d oc = p - origin;
  const double b = oc.dot(d), c = oc.squaredNorm() - 0.04 * 0.04;
  if (b * b - c >= 0.0 && -b + std::sqrt(b * b - c) > 0.0) return true;
  // The pole in the xy plane: |(p + t d - origin)_xy| = 0.015.
  const double a2 = d.x() * d.x() + d.y() * d.y(), b2 = oc.x() * d.x() + oc.y() * d.y();
  const double c2 = oc.x() * oc.x() + oc.y() * oc.y() - 0.015 * 0.015;
  if (a2 == 0.0 || b2 * b2 - a2 * c2 < 0.0) return false;
  const double t = (-b2 - std::sqrt(b2 * b2 - a2 * c2)) / a2;
  const double z = p.z() + t * d.z();
  return t > 0.0 && z < origin.z() && z > -1.0;
}

// The photo of the ball: each pixel the mean of 3x3 rays; what misses the ball sees the
// environment directly.
Image render_ball_photo(const PinholeCamera& camera, const Environment& environment, const RGB& reflectance,
                        bool with_camera) {
  constexpr int kRays = 3;
  Image image(camera.width, camera.height);
  const Vec3d origin = camera.position().cast<double>();
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      RGB sum = RGB::Zero();
      for (int sy = 0; sy < kRays; ++sy)
        for (int sx = 0; sx < kRays; ++sx) {
          const Ray ray = camera.generate_ray(x + (sx + 0.5f) / kRays, y + (sy + 0.5f) / kRays);
          const auto hit = reflect_off_ball(origin, ray.direction.cast<double>().normalized(), kBall);
          if (!hit)
            sum += environment.eval(ray.direction);
          else if (with_camera && hits_camera(hit->point, hit->direction, origin))
            sum += reflectance * kDark;
          else
            sum += reflectance * environment.eval(hit->direction.cast<float>());
        }
      image.set(x, y, sum / float(kRays * kRays));
    }
  return image;
}

std::vector<ProbeView> ball_photos(const Environment& environment, const RGB& reflectance, bool with_camera = true) {
  std::vector<ProbeView> views;
  for (double azimuth : {-60.0, 60.0, 180.0}) {
    ProbeView view;
    view.camera = probe_camera(azimuth);
    view.name = view.camera.name;
    view.radiance = render_ball_photo(view.camera, environment, reflectance, with_camera);
    views.push_back(std::move(view));
  }
  return views;
}

// The map in the probe's frame, each block of texels averaged by solid angle into a
// width x height map.
Image averaged(const Image& map, int width, int height) {
  const int bx = map.width / width, by = map.height / height;
  Image out(width, height);
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      RGBd sum = RGBd::Zero();
      double area = 0.0;
      for (int y = j * by; y < (j + 1) * by; ++y)
        for (int x = i * bx; x < (i + 1) * bx; ++x) {
          const double a = latlong_texel_solid_angle(y, map.width, map.height);
          sum += a * map.at(x, y).cast<double>();
          area += a;
        }
      out.set(i, j, (sum / area).cast<float>());
    }
  return out;
}

// Relative RMSE over covered texels, weighted by solid angle: RMS(probe - truth) / RMS(truth).
double relative_rmse(const MirrorBallProbe& probe, const Image& truth) {
  double error = 0.0, norm = 0.0;
  for (int j = 0; j < truth.height; ++j)
    for (int i = 0; i < truth.width; ++i) {
      if (!(probe.covered[size_t(j) * truth.width + i] > 0.0f)) continue;
      const double a = latlong_texel_solid_angle(j, truth.width, truth.height);
      error += a * (probe.map.at(i, j) - truth.at(i, j)).cast<double>().square().sum();
      norm += a * truth.at(i, j).cast<double>().square().sum();
    }
  return std::sqrt(error / norm);
}

// The probe's and the truth's texel in the direction from the ball to view v's camera:
// the middle of that camera's reflection in its own photo.
std::pair<RGB, RGB> towards_camera(const MirrorBallProbe& probe, const Image& truth, const PinholeCamera& camera) {
  const Vec3d d = (camera.position().cast<double>() - kBall.center).normalized();
  const Vec2 uv = direction_to_latlong(probe.to_world.transpose() * d.cast<float>());
  const int t = texel_of(uv, truth.width, truth.height);
  return {probe.map.at(t % truth.width, t / truth.width), truth.at(t % truth.width, t / truth.width)};
}

void expect_probe_matches(const Environment& environment, const RGB& reflectance, double tolerance) {
  const std::vector<ProbeView> views = ball_photos(environment, reflectance);
  MirrorBallProbeOptions options;
  options.width = 64, options.height = 32;
  options.reflectance = reflectance;
  const MirrorBallProbe probe = build_mirror_ball_probe(views, kBall, options);
  const Image truth = averaged(environment.map(), 64, 32);
  const double rmse = relative_rmse(probe, truth);
  std::cout << environment.source() << ": probe 64x32 relative RMSE " << 100 * rmse << "% over "
            << 100 * probe.covered_fraction << "% of the sphere; views";
  for (const ProbeViewContribution& v : probe.views)
    std::cout << " " << v.name << " " << 100 * v.weight_share << "% (sees " << 100 * v.covered_fraction << "%)";
  std::cout << "\n";
  EXPECT_LT(rmse, tolerance);
  EXPECT_GT(probe.covered_fraction, 0.97);
  ASSERT_EQ(probe.views.size(), 3u);
  double share = 0.0;
  for (const ProbeViewContribution& v : probe.views) {
    EXPECT_GT(v.weight_share, 0.2);
    EXPECT_GT(v.covered_fraction, 0.6);
    share += v.weight_share;
  }
  EXPECT_NEAR(share, 1.0, 1e-9);
  // Each camera's own reflection is dark in its photo: another view sees past it, and the
  // map there is what photos without the cameras give.
  const MirrorBallProbe unseen = build_mirror_ball_probe(ball_photos(environment, reflectance, false), kBall, options);
  for (const ProbeView& view : views) {
    const RGB found = towards_camera(probe, truth, view.camera).first;
    const RGB expected = towards_camera(unseen, truth, view.camera).first;
    EXPECT_NEAR(found.mean(), expected.mean(), 0.01 * expected.mean()) << view.name;
  }
  // Without leaving it out, the patch is there (what the check above would catch).
  options.camera_radius_m = 0.0;
  const MirrorBallProbe with_camera = build_mirror_ball_probe(views, kBall, options);
  EXPECT_LT(towards_camera(with_camera, truth, views[0].camera).first.mean(),
            0.7 * towards_camera(unseen, truth, views[0].camera).first.mean());
}

TEST(MirrorBallProbe, SolverReflectsBackThroughThePixel) {
  const PinholeCamera camera = probe_camera(25.0, 40.0, 0.35);
  const Vec3d origin = camera.position().cast<double>();
  int checked = 0;
  double worst_px = 0.0, worst_m = 0.0;
  for (int y = 0; y < camera.height; y += 3)
    for (int x = 0; x < camera.width; x += 3) {
      const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
      const auto hit = reflect_off_ball(origin, ray.direction.cast<double>().normalized(), kBall);
      if (!hit || hit->cos_incidence < 0.02) continue;
      const auto found = ball_point_reflecting(origin, hit->direction, kBall);
      ASSERT_TRUE(found) << x << " " << y;
      worst_m = std::max(worst_m, (found->point - hit->point).norm());
      EXPECT_NEAR(found->cos_incidence, hit->cos_incidence, 1e-9);
      EXPECT_LT((found->direction - hit->direction).norm(), 1e-12);
      const Vec3 local = (camera.camera_to_world.inverse() * found->point.cast<float>());
      const auto film = camera.project(local);
      ASSERT_TRUE(film);
      worst_px = std::max(worst_px, double((*film - Vec2(x + 0.5f, y + 0.5f)).norm()));
      ++checked;
    }
  EXPECT_GT(checked, 100);
  EXPECT_LT(worst_m, 1e-10);
  EXPECT_LT(worst_px, 2e-3);

  // Closed forms: straight back towards the camera the point nearest it; at the outline
  // (pi/2 + acos(r/D) from it) the tangent point; beyond, hidden.
  const Vec3d axis = (origin - kBall.center).normalized();
  const auto nearest = ball_point_reflecting(origin, axis, kBall);
  ASSERT_TRUE(nearest);
  EXPECT_LT((nearest->point - (kBall.center + kBall.radius * axis)).norm(), 1e-12);
  EXPECT_NEAR(nearest->cos_incidence, 1.0, 1e-12);
  const double D = (origin - kBall.center).norm(), outline = kPiD / 2 + std::acos(kBall.radius / D);
  const Vec3d side = axis.unitOrthogonal();
  const auto grazing =
      ball_point_reflecting(origin, std::cos(outline - 1e-9) * axis + std::sin(outline - 1e-9) * side, kBall);
  ASSERT_TRUE(grazing);
  EXPECT_LT(grazing->cos_incidence, 1e-4);
  EXPECT_NEAR((grazing->point - origin).norm(), std::sqrt(D * D - kBall.radius * kBall.radius), 1e-6);
  EXPECT_FALSE(ball_point_reflecting(origin, std::cos(outline + 1e-3) * axis + std::sin(outline + 1e-3) * side, kBall));
  EXPECT_FALSE(ball_point_reflecting(kBall.center, axis, kBall));
}

// Measured 1.2% (2.6% when the photos were read bilinearly), and 0.34% under potsdamer.
TEST(MirrorBallProbe, OfficeFromThreeDistortedViews) {
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  const Environment office = make_environment("procedural:office", frame, 1024, 512);
  expect_probe_matches(office, RGB(0.62f, 0.60f, 0.57f), 0.02);
}

TEST(MirrorBallProbe, RealMapFromThreeDistortedViews) {
  GLAZE_REQUIRE_ENVMAP(path, "potsdamer_platz_1k.hdr");
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  expect_probe_matches(Environment::load(path.string(), frame), RGB::Constant(0.6f), 0.01);
}

// A pixel saturated in the photo (alpha 0, its value a lower bound) is left out: the
// other views give those directions, and one view alone leaves them uncovered.
TEST(MirrorBallProbe, SaturatedPixelsAreLeftOut) {
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  const Environment office = make_environment("procedural:office", frame, 256, 128);
  std::vector<ProbeView> views = ball_photos(office, RGB::Ones());
  for (ProbeView& view : views) {
    view.alpha.assign(size_t(view.radiance.width) * view.radiance.height, 1.0f);
    for (size_t p = 0; p < view.alpha.size(); ++p)
      if (view.radiance.pixels[3 * p] > 3.0f) {
        view.alpha[p] = 0.0f;
        for (int c = 0; c < 3; ++c) view.radiance.pixels[3 * p + c] = 3.0f;
      }
  }
  MirrorBallProbeOptions options;
  options.width = 64, options.height = 32;
  const MirrorBallProbe probe = build_mirror_ball_probe(views, kBall, options);
  // The ceiling's lights (26) are saturated in every view: uncovered, and no covered
  // texel holds a clipped value.
  const Image truth = averaged(office.map(), 64, 32);
  int lights = 0;
  for (size_t t = 0; t < probe.covered.size(); ++t) {
    const RGB expected = truth.at(int(t % 64), int(t / 64));
    if (expected.x() > 20.0f) {
      ++lights;
      EXPECT_EQ(probe.covered[t], 0.0f);
    }
  }
  EXPECT_GT(lights, 0);
  EXPECT_LT(probe.covered_fraction, 0.97);
  EXPECT_LT(relative_rmse(probe, truth), 0.1);
}

TEST(MirrorBallProbe, WritesMapAndMaskThatEnvironmentReadsInBoardFrame) {
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  const Environment office = make_environment("procedural:office", frame, 256, 128);
  const std::vector<ProbeView> views = ball_photos(office, RGB::Ones());
  MirrorBallProbeOptions options;
  options.width = 64, options.height = 32;
  const MirrorBallProbe probe = build_mirror_ball_probe(views, kBall, options);
  testing::TemporaryDirectory dir;
  ProbeFiles files;
  {
    OutputFolder out(dir.path(), "done.json", "probe output");
    files = write_mirror_ball_probe(out, probe);
    out.finish("{}");
  }
  EXPECT_EQ(std::filesystem::path(files.map).filename(), "env.exr");
  const Image mask = read_image(files.mask);
  ASSERT_EQ(mask.width, 64);
  for (size_t t = 0; t < probe.covered.size(); ++t) EXPECT_EQ(mask.pixels[3 * t], probe.covered[t]);
  EnvironmentOptions read_frame;
  read_frame.to_world = probe.to_world;
  const Environment read = Environment::load(files.map, read_frame);
  // Board +Z (up) reads the top row: the ceiling; -Z the floor.
  EXPECT_NEAR(read.eval(Vec3::UnitZ()).mean(), office.eval(Vec3::UnitZ()).mean(),
              0.1 * office.eval(Vec3::UnitZ()).mean());
  EXPECT_NEAR(read.eval(-Vec3::UnitZ()).mean(), office.eval(-Vec3::UnitZ()).mean(),
              0.1 * office.eval(-Vec3::UnitZ()).mean());
}

TEST(MirrorBallProbe, NoViewSeeingTheBallIsAnError) {
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  const Environment office = make_environment("procedural:office", frame, 64, 32);
  std::vector<ProbeView> views = ball_photos(office, RGB::Ones());
  views.resize(1);
  MirrorBall elsewhere = kBall;
  elsewhere.center += Vec3d(0.0, 0.0, 3.0);  // far outside the photo
  MirrorBallProbeOptions options;
  options.width = 32, options.height = 16;
  EXPECT_THROW(build_mirror_ball_probe(views, elsewhere, options), Error);
  views[0].alpha.resize(5);
  EXPECT_THROW(build_mirror_ball_probe(views, kBall, options), Error);
}

// The least-squares ratio recovers a known factor per channel, despite a few texels where
// the absolute estimate is wrong.
TEST(MirrorBallProbe, ReflectanceRatioRecoversKnownFactor) {
  const Image truth = make_procedural_environment("office", 64, 32);
  const RGBd factor(0.61, 0.58, 0.55);
  Image probe(64, 32), absolute = truth;
  std::vector<float> probe_covered(64 * 32, 1.0f), absolute_covered(64 * 32, 1.0f);
  Pcg32 rng(7);
  for (size_t t = 0; t < probe_covered.size(); ++t) {
    for (int c = 0; c < 3; ++c)
      probe.pixels[3 * t + c] = float(factor[c] * truth.pixels[3 * t + c] * (1.0 + 0.02 * (rng.next_float() - 0.5)));
    if (t % 23 == 0) absolute.pixels[3 * t] *= 3.0f;  // a wrong fit there
    if (t % 5 == 0) probe_covered[t] = 0.0f;          // the probe's blind spots
    if (t % 7 == 0) absolute_covered[t] = 0.0f;
  }
  const ReflectanceRatio ratio = reflectance_ratio(probe, probe_covered, absolute, absolute_covered);
  EXPECT_EQ(ratio.texels, size_t(std::count_if(probe_covered.begin(), probe_covered.end(), [&, t = 0](float) mutable {
              const bool both = t % 5 != 0 && t % 7 != 0;
              ++t;
              return both;
            })));
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio.reflectance[c], factor[c], 0.005 * factor[c]) << c;
  EXPECT_LT(ratio.relative_rms[1], 0.02);
  EXPECT_THROW(reflectance_ratio(probe, {}, Image(32, 16), {}), Error);
}

// The lead's reflectance estimate end to end: a probe built with reflectance 1 from photos
// of a 0.6 ball, against the true lighting as a capture set holds it (lat-long in the
// board's frame, +Y along the board's y), resampled into the probe's frame.
TEST(MirrorBallProbe, ReflectanceFromProbeAgainstLightingInBoardFrame) {
  EnvironmentOptions frame;
  frame.to_world = probe_to_board();
  const Environment office = make_environment("procedural:office", frame, 256, 128);
  MirrorBallProbeOptions options;
  options.width = 64, options.height = 32;
  const MirrorBallProbe probe = build_mirror_ball_probe(ball_photos(office, RGB::Constant(0.6f)), kBall, options);
  // The same lighting in the board's own frame (to_world identity), 128x64.
  const Environment board(Image(128, 64), {}, "board frame");
  Image in_board(128, 64);
  std::vector<float> known(128 * 64, 1.0f);
  for (int j = 0; j < 64; ++j)
    for (int i = 0; i < 128; ++i) {
      in_board.set(i, j, office.eval(board.uv_to_direction(Vec2((i + 0.5f) / 128, (j + 0.5f) / 64))));
      if (j >= 56) known[size_t(j) * 128 + i] = 0.0f;  // the board's -Y pole unknown
    }
  const LatlongResample resampled = resample_into_probe_frame(in_board, known, Mat3::Identity(), 64, 32);
  const size_t unknown = std::count(resampled.covered.begin(), resampled.covered.end(), 0.0f);
  EXPECT_GT(unknown, 0u);
  EXPECT_LT(unknown, 64u * 32u / 4);
  const ReflectanceRatio ratio = reflectance_ratio(probe.map, probe.covered, resampled.map, resampled.covered);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(ratio.reflectance[c], 0.6, 0.003) << c;
  std::cout << "reflectance " << ratio.reflectance.transpose() << " over " << ratio.texels << " texels, relative RMS "
            << ratio.relative_rms.transpose() << "\n";
}

}  // namespace
}  // namespace glaze
