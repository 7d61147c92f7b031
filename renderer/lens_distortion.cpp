#include "renderer/lens_distortion.h"

#include "renderer/error.h"

#include <algorithm>
#include <cmath>

namespace glaze {
namespace {

// The fisheye model's angle polynomial theta' (theta) and its derivative.
double fisheye_angle(const LensDistortion& d, double theta) {
  const double t2 = theta * theta;
  return theta * (1.0 + t2 * (d.k1 + t2 * (d.k2 + t2 * (d.k3 + t2 * d.k4))));
}
double fisheye_angle_slope(const LensDistortion& d, double theta) {
  const double t2 = theta * theta;
  return 1.0 + t2 * (3.0 * d.k1 + t2 * (5.0 * d.k2 + t2 * (7.0 * d.k3 + t2 * 9.0 * d.k4)));
}

// Newton's method converges quadratically from the distorted point for any lens a
// camera is built with; the iteration cap only bounds the work for points beyond a fold.
constexpr int kNewtonSteps = 50;
constexpr double kTolerance = 1e-14;

}  // namespace

Vec2d LensDistortion::distort(const Vec2d& p) const {
  const double x = p.x(), y = p.y(), r2 = x * x + y * y;
  switch (model) {
    case Model::none:
      return p;
    case Model::opencv: {
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
              y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
    }
    case Model::opencv_fisheye: {
      const double r = std::sqrt(r2);
      if (r < 1e-12) return p;  // theta'/r -> 1 on the axis
      return p * (fisheye_angle(*this, std::atan(r)) / r);
    }
  }
  return p;
}

Eigen::Matrix2d LensDistortion::jacobian(const Vec2d& p) const {
  const double x = p.x(), y = p.y(), r2 = x * x + y * y;
  Eigen::Matrix2d j = Eigen::Matrix2d::Identity();
  switch (model) {
    case Model::none:
      break;
    case Model::opencv: {
      const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
      const double slope = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);  // d radial / d (r^2)
      const double cross = 2.0 * x * y * slope + 2.0 * p1 * x + 2.0 * p2 * y;
      j << radial + 2.0 * x * x * slope + 2.0 * p1 * y + 6.0 * p2 * x, cross,  //
          cross, radial + 2.0 * y * y * slope + 6.0 * p1 * y + 2.0 * p2 * x;
      break;
    }
    case Model::opencv_fisheye: {
      const double r = std::sqrt(r2);
      if (r < 1e-12) break;
      // (x', y') = s(r) (x, y) with s = theta'/r: J = s I + (ds/dr / r) (x, y)(x, y)^T.
      const double theta = std::atan(r), scale = fisheye_angle(*this, theta) / r;
      const double scale_slope = (fisheye_angle_slope(*this, theta) / (1.0 + r2) - scale) / r;
      j = scale * Eigen::Matrix2d::Identity() + (scale_slope / r) * p * p.transpose();
      break;
    }
  }
  return j;
}

std::optional<Vec2d> LensDistortion::undistort(const Vec2d& target) const {
  if (model == Model::none) return target;
  if (model == Model::opencv_fisheye) {
    // Radially symmetric: solve theta' (theta) = |target| for theta in [0, pi/2).
    const double distorted = target.norm();
    if (distorted < 1e-12) return target;
    double theta = std::min(distorted, 1.5);
    for (int step = 0; step < kNewtonSteps; ++step) {
      const double slope = fisheye_angle_slope(*this, theta);
      if (!(slope > 0.0)) return std::nullopt;  // beyond the fold
      const double delta = (fisheye_angle(*this, theta) - distorted) / slope;
      theta -= delta;
      if (!(theta >= 0.0 && theta < 0.5 * kPiD)) return std::nullopt;
      if (std::abs(delta) <= kTolerance * (1.0 + theta)) {
        if (!(fisheye_angle_slope(*this, theta) > 0.0)) return std::nullopt;
        return Vec2d(target * (std::tan(theta) / distorted));
      }
    }
    return std::nullopt;
  }
  Vec2d p = target;
  for (int step = 0; step < kNewtonSteps; ++step) {
    const Eigen::Matrix2d j = jacobian(p);
    const double det = j.determinant();
    if (!(det > 0.0)) return std::nullopt;  // beyond the fold, or a mirrored lens
    const Vec2d delta = j.inverse() * (distort(p) - target);
    p -= delta;
    if (!p.allFinite()) return std::nullopt;
    if (delta.norm() <= kTolerance * (1.0 + p.norm()))
      return jacobian(p).determinant() > 0.0 ? std::optional<Vec2d>(p) : std::nullopt;
  }
  return std::nullopt;
}

std::string camera_model_name(LensDistortion::Model model) {
  switch (model) {
    case LensDistortion::Model::none:
      return "PINHOLE";
    case LensDistortion::Model::opencv:
      return "OPENCV";
    case LensDistortion::Model::opencv_fisheye:
      return "OPENCV_FISHEYE";
  }
  return "PINHOLE";
}

std::optional<LensDistortion::Model> camera_model_from_name(const std::string& name) {
  if (name == "PINHOLE" || name == "SIMPLE_PINHOLE") return LensDistortion::Model::none;
  if (name == "OPENCV") return LensDistortion::Model::opencv;
  if (name == "OPENCV_FISHEYE") return LensDistortion::Model::opencv_fisheye;
  return std::nullopt;
}

const char* const kSupportedCameraModels =
    "glaze casts rays through PINHOLE, SIMPLE_PINHOLE, OPENCV (k1 k2 p1 p2, optional k3) and OPENCV_FISHEYE "
    "(k1 k2 k3 k4) cameras";

double& coefficient(LensDistortion& lens, const std::string& name) {
  if (name == "k1") return lens.k1;
  if (name == "k2") return lens.k2;
  if (name == "k3") return lens.k3;
  if (name == "k4") return lens.k4;
  if (name == "p1") return lens.p1;
  if (name == "p2") return lens.p2;
  throw Error("\"" + name + "\" is not a lens distortion coefficient (k1 k2 k3 k4 p1 p2)");
}

bool model_uses(LensDistortion::Model model, const std::string& name) {
  switch (model) {
    case LensDistortion::Model::none:
      return false;
    case LensDistortion::Model::opencv:
      return name == "k1" || name == "k2" || name == "k3" || name == "p1" || name == "p2";
    case LensDistortion::Model::opencv_fisheye:
      return name == "k1" || name == "k2" || name == "k3" || name == "k4";
  }
  return false;
}

}  // namespace glaze
