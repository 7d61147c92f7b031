#include "renderer/camera.h"

#include "renderer/error.h"

namespace glaze {

PinholeCamera PinholeCamera::from_vertical_fov(std::string name, const Eigen::Affine3f& camera_to_world, float yfov,
                                               int width, int height) {
  if (!(yfov > 0.0f && yfov < kPi))
    throw Error("camera '" + name + "': vertical field of view must be in (0, pi) radians, got " +
                std::to_string(yfov));
  if (width <= 0 || height <= 0) throw Error("camera '" + name + "': film size must be positive");
  PinholeCamera camera;
  camera.name = std::move(name);
  camera.camera_to_world = camera_to_world;
  camera.width = width;
  camera.height = height;
  camera.fl_y = 0.5f * height / std::tan(0.5f * yfov);
  camera.fl_x = camera.fl_y;
  camera.cx = 0.5f * width;
  camera.cy = 0.5f * height;
  return camera;
}

}  // namespace glaze
