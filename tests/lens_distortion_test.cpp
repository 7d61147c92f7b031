// Tests of lens_distortion.h and the camera's rays through it: the models against OpenCV's
// own projection (an independent implementation), their inverse, and the camera's rays.
#include "renderer/camera.h"
#include "renderer/error.h"
#include "renderer/lens_distortion.h"

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>

#include <vector>

namespace glaze {
namespace {

using Model = LensDistortion::Model;

const LensDistortion kBarrel{Model::opencv, -0.28, 0.09, -0.012, 0.0, 0.0013, -0.0021};
const LensDistortion kFisheye{Model::opencv_fisheye, 0.05, -0.01, 0.004, -0.0009};

// Normalised image points (x, y down) filling a field of view of about 90 degrees.
std::vector<Vec2d> field_points() {
  std::vector<Vec2d> points;
  for (int j = -8; j <= 8; ++j)
    for (int i = -10; i <= 10; ++i) points.emplace_back(0.09 * i, 0.07 * j);
  return points;
}

// Where OpenCV images the camera-frame points (x, y, 1) with focal 1 and centre 0.
std::vector<cv::Point2d> opencv_projection(const LensDistortion& lens, const std::vector<Vec2d>& points) {
  std::vector<cv::Point3d> object;
  for (const Vec2d& p : points) object.emplace_back(p.x(), p.y(), 1.0);
  const cv::Matx33d identity = cv::Matx33d::eye();
  const cv::Vec3d zero(0, 0, 0);
  std::vector<cv::Point2d> image;
  if (lens.model == Model::opencv_fisheye) {
    cv::fisheye::projectPoints(object, image, zero, zero, identity, cv::Vec4d(lens.k1, lens.k2, lens.k3, lens.k4));
  } else {
    cv::projectPoints(object, zero, zero, identity, std::vector<double>{lens.k1, lens.k2, lens.p1, lens.p2, lens.k3},
                      image);
  }
  return image;
}

TEST(LensDistortion, ModelsAgreeWithOpenCvsProjection) {
  for (const LensDistortion& lens : {kBarrel, kFisheye}) {
    const std::vector<Vec2d> points = field_points();
    const std::vector<cv::Point2d> expected = opencv_projection(lens, points);
    for (size_t i = 0; i < points.size(); ++i) {
      const Vec2d distorted = lens.distort(points[i]);
      EXPECT_NEAR(distorted.x(), expected[i].x, 1e-12)
          << camera_model_name(lens.model) << " at " << points[i].transpose();
      EXPECT_NEAR(distorted.y(), expected[i].y, 1e-12)
          << camera_model_name(lens.model) << " at " << points[i].transpose();
    }
  }
}

TEST(LensDistortion, UndistortInvertsDistortToRoundingError) {
  for (const LensDistortion& lens : {kBarrel, kFisheye})
    for (const Vec2d& p : field_points()) {
      const std::optional<Vec2d> back = lens.undistort(lens.distort(p));
      ASSERT_TRUE(back.has_value()) << camera_model_name(lens.model) << " at " << p.transpose();
      EXPECT_LT((*back - p).norm(), 1e-12) << camera_model_name(lens.model) << " at " << p.transpose();
    }
}

TEST(LensDistortion, JacobianMatchesCentralDifferences) {
  for (const LensDistortion& lens : {kBarrel, kFisheye})
    for (const Vec2d& p : field_points()) {
      const double h = 1e-6;
      Eigen::Matrix2d numeric;
      numeric.col(0) = (lens.distort(p + Vec2d(h, 0)) - lens.distort(p - Vec2d(h, 0))) / (2 * h);
      numeric.col(1) = (lens.distort(p + Vec2d(0, h)) - lens.distort(p - Vec2d(0, h))) / (2 * h);
      EXPECT_LT((lens.jacobian(p) - numeric).cwiseAbs().maxCoeff(), 1e-8) << camera_model_name(lens.model);
    }
}

// r (1 + k1 r^2) with k1 = -0.5 peaks at r = sqrt(2/3), at 0.544: nothing distorts further
// out, and a distorted point just inside has its one-to-one preimage, not the one beyond.
TEST(LensDistortion, PointsBeyondTheFoldHaveNoPreimage) {
  const LensDistortion lens{Model::opencv, -0.5};
  const double peak = std::sqrt(2.0 / 3.0) * (1.0 - 0.5 * 2.0 / 3.0);
  EXPECT_FALSE(lens.undistort(Vec2d(peak * 1.01, 0.0)).has_value());
  const std::optional<Vec2d> inside = lens.undistort(Vec2d(peak * 0.99, 0.0));
  ASSERT_TRUE(inside.has_value());
  EXPECT_LT(inside->x(), std::sqrt(2.0 / 3.0));
  // The fisheye maps at most 90 degrees off the axis to a pinhole point.
  EXPECT_FALSE(LensDistortion{Model::opencv_fisheye}.undistort(Vec2d(0.5 * kPiD + 0.01, 0)).has_value());
}

PinholeCamera distorted_camera(const LensDistortion& lens) {
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.linear() = Eigen::AngleAxisf(0.3f, Vec3(0.2f, 1.0f, 0.1f).normalized()).toRotationMatrix();
  pose.translation() = Vec3(0.1f, -0.2f, 0.5f);
  PinholeCamera camera = PinholeCamera::from_vertical_fov("lens", pose, 0.9f, 320, 240);
  camera.cx = 163.5f;
  camera.cy = 118.25f;
  camera.distortion = lens;
  camera.check_lens("test");
  return camera;
}

// Rays leave the film where OpenCV projects their points back to, with glaze's axes
// (y up, looking along -Z) turned into OpenCV's (y down, Z forward).
TEST(LensDistortion, CameraRaysProjectBackToTheirPixelsAsOpenCvProjects) {
  for (const LensDistortion& lens : {kBarrel, kFisheye}) {
    const PinholeCamera camera = distorted_camera(lens);
    const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
    for (float y : {0.5f, 60.25f, 118.25f, 239.5f})
      for (float x : {0.5f, 100.0f, 163.5f, 319.5f}) {
        const Ray ray = camera.generate_ray(x, y);
        const Vec3 local = world_to_camera * (ray.origin + 2.0f * ray.direction);
        const std::optional<Vec2> film = camera.project(local);
        ASSERT_TRUE(film.has_value());
        EXPECT_NEAR(film->x(), x, 2e-3f) << camera_model_name(lens.model);
        EXPECT_NEAR(film->y(), y, 2e-3f) << camera_model_name(lens.model);
        const cv::Point2d opencv = opencv_projection(lens, {Vec2d(local.x() / -local.z(), -local.y() / -local.z())})[0];
        EXPECT_NEAR(camera.cx + camera.fl_x * opencv.x, x, 2e-3) << camera_model_name(lens.model);
        EXPECT_NEAR(camera.cy + camera.fl_y * opencv.y, y, 2e-3) << camera_model_name(lens.model);
      }
  }
}

TEST(LensDistortion, NoLensLeavesThePinholeRaysUnchanged) {
  PinholeCamera camera = distorted_camera({});
  PinholeCamera opencv_zero = camera;
  opencv_zero.distortion.model = Model::opencv;  // all coefficients zero
  for (float y : {0.5f, 200.0f})
    for (float x : {0.5f, 300.0f})
      EXPECT_LT((camera.generate_ray(x, y).direction - opencv_zero.generate_ray(x, y).direction).norm(), 1e-6f);
}

TEST(LensDistortion, OrthographicCamerasTakeNoLens) {
  PinholeCamera camera = PinholeCamera::orthographic("ortho", Eigen::Affine3f::Identity(), 1.0f, 8, 8);
  camera.distortion = kBarrel;
  try {
    camera.check_lens("ortho");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("perspective cameras only"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace glaze
