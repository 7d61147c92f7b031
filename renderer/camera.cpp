#include "renderer/camera.h"

#include "renderer/error.h"

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

}  // namespace glaze
