// lens_distortion.h: the lens distortion models of capture sets (docs/design.md §3, §4),
// as OpenCV, COLMAP and nerfstudio define them, so that photographs are used as taken:
// rays are cast through the distortion, never the images resampled.
//
// Both models act on normalised image coordinates in OpenCV's convention, x to the right
// and y DOWN: (x, y) = ((px - cx)/fl_x, (py - cy)/fl_y) on the film, and (X/Z, Y/Z) for a
// point in OpenCV's camera frame (Z forward). distort() maps where an ideal pinhole would
// image a point to where the lens images it; undistort() is its inverse.
//
//   opencv (OPENCV, k3 optional):   r^2 = x^2 + y^2
//     x' = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//     y' = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y
//   opencv_fisheye (OPENCV_FISHEYE): theta = atan(r)
//     theta' = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),
//     (x', y') = (theta' / r) (x, y)
//
// Polynomial models hold only where they are one-to-one: a strong barrel term folds the
// image back beyond some radius. undistort() answers nothing there, and
// check_lens_covers_film() refuses a camera whose film reaches that far, so that every
// pixel of an accepted camera has exactly one ray.
#pragma once

#include "renderer/math.h"

#include <optional>
#include <string>

namespace glaze {

struct LensDistortion {
  enum class Model { none, opencv, opencv_fisheye };
  Model model = Model::none;
  // OpenCV's names. opencv uses k1 k2 k3 p1 p2; opencv_fisheye uses k1..k4.
  double k1 = 0, k2 = 0, k3 = 0, k4 = 0, p1 = 0, p2 = 0;

  bool is_none() const { return model == Model::none; }
  // Where the lens images the point an ideal pinhole images at `undistorted`.
  Vec2d distort(const Vec2d& undistorted) const;
  // The pinhole point that the lens images at `distorted`, or nothing where the model is
  // not one-to-one (beyond its fold) or the point lies 90 degrees or more off the axis.
  std::optional<Vec2d> undistort(const Vec2d& distorted) const;
  // d distort / d undistorted at `undistorted` (column-major 2x2).
  Eigen::Matrix2d jacobian(const Vec2d& undistorted) const;
};

// The model's name in transforms.json ("OPENCV", "OPENCV_FISHEYE"; "PINHOLE" for none).
std::string camera_model_name(LensDistortion::Model model);
// The model that transforms.json's "camera_model" names (PINHOLE and SIMPLE_PINHOLE are
// none), or nothing for a model glaze does not cast rays through.
std::optional<LensDistortion::Model> camera_model_from_name(const std::string& name);
// What the supported models and their coefficients are, for messages.
extern const char* const kSupportedCameraModels;

// The coefficients by OpenCV's names (k1 k2 k3 k4 p1 p2), and whether `model` uses one.
inline constexpr const char* kDistortionCoefficients[] = {"k1", "k2", "k3", "k4", "p1", "p2"};
double& coefficient(LensDistortion& lens, const std::string& name);  // name: one of kDistortionCoefficients
bool model_uses(LensDistortion::Model model, const std::string& name);

}  // namespace glaze
