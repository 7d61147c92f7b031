#include "renderer/camera.h"

#include "renderer/error.h"

#include <sstream>

namespace glaze {
namespace {

PinholeCamera centred(std::string name, const Eigen::Affine3f& camera_to_world, int width, int height) {
  if (width <= 0 || height <= 0) throw Error("camera '" + name + "': film size must be positive");
  PinholeCamera camera;
  camera.name = std::move(name);
  camera.camera_to_world = camera_to_world;
  camera.width = width;
  camera.height = height;
  camera.cx = 0.5f * width;
  camera.cy = 0.5f * height;
  return camera;
}

}  // namespace

PinholeCamera PinholeCamera::from_vertical_fov(std::string name, const Eigen::Affine3f& camera_to_world, float yfov,
                                               int width, int height) {
  if (!(yfov > 0.0f && yfov < kPi))
    throw Error("camera '" + name + "': vertical field of view must be in (0, pi) radians, got " +
                std::to_string(yfov));
  PinholeCamera camera = centred(std::move(name), camera_to_world, width, height);
  camera.fl_y = 0.5f * height / std::tan(0.5f * yfov);
  camera.fl_x = camera.fl_y;
  return camera;
}

PinholeCamera PinholeCamera::orthographic(std::string name, const Eigen::Affine3f& camera_to_world, float ymag,
                                          int width, int height) {
  if (!(ymag > 0.0f && std::isfinite(ymag)))
    throw Error("camera '" + name + "': orthographic ymag (half the view's height) must be positive, got " +
                std::to_string(ymag));
  PinholeCamera camera = centred(std::move(name), camera_to_world, width, height);
  camera.projection = Projection::orthographic;
  camera.fl_y = 0.5f * height / ymag;
  camera.fl_x = camera.fl_y;
  return camera;
}

Vec3 PinholeCamera::undistorted_direction(const Vec3& local) const {
  // check_lens() has made sure that the whole film has an inverse; a film point outside
  // it (an outer sub-pixel of a footprint at the border) keeps the pinhole's ray.
  const std::optional<Vec2d> image = distortion.undistort(Vec2d(local.x(), -local.y()));
  if (!image) return local;
  return Vec3(float(image->x()), -float(image->y()), -1.0f);
}

void PinholeCamera::check_lens(const std::string& where) const {
  if (distortion.is_none()) return;
  if (projection != Projection::perspective)
    throw Error(where + ": lens distortion is for perspective cameras only, not orthographic ones");
  // The models' folds are rings about the axis, so the film's border and a grid inside it
  // find them; the border is walked pixel by pixel.
  const auto one_to_one = [&](double x, double y) {
    const Vec2d film((x - cx) / fl_x, (y - cy) / fl_y);
    const std::optional<Vec2d> image = distortion.undistort(film);
    return image && (distortion.distort(*image) - film).norm() <= 1e-9 * (1.0 + film.norm());
  };
  const auto refuse = [&](double x, double y) {
    std::ostringstream message;
    message << where << ": the " << camera_model_name(distortion.model) << " lens model (k1 " << distortion.k1
            << ", k2 " << distortion.k2 << ", k3 " << distortion.k3 << ", k4 " << distortion.k4 << ", p1 "
            << distortion.p1 << ", p2 " << distortion.p2 << ") folds back before film point (" << x << ", " << y
            << ") of the " << width << "x" << height
            << " film: pixels there would have no ray or two; check the coefficients and the focal length they were "
               "calibrated with";
    throw Error(message.str());
  };
  for (int i = 0; i <= width; ++i)
    for (const double y : {0.0, double(height)})
      if (!one_to_one(i, y)) refuse(i, y);
  for (int j = 0; j <= height; ++j)
    for (const double x : {0.0, double(width)})
      if (!one_to_one(x, j)) refuse(x, j);
  constexpr int kGrid = 32;
  for (int j = 1; j < kGrid; ++j)
    for (int i = 1; i < kGrid; ++i)
      if (!one_to_one(double(width) * i / kGrid, double(height) * j / kGrid))
        refuse(double(width) * i / kGrid, double(height) * j / kGrid);
}

}  // namespace glaze
