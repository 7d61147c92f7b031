// camera.h: the pinhole camera shared by glTF scenes and capture sets (docs/design.md §3).
//
// Intrinsics are in pixels (fl_x, fl_y, cx, cy, as nerfstudio's transforms.json); the
// pose is camera-to-world with OpenGL axes (+X right, +Y up, looking along -Z). Pixel
// (i, j), column i and row j from the top, has its centre at (i + 0.5, j + 0.5); the
// camera-space direction through film point (x, y) is ((x - cx)/fl_x, -(y - cy)/fl_y, -1).
#pragma once

#include "renderer/math.h"

#include <string>

namespace glaze {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // unit length
};

struct PinholeCamera {
  std::string name;
  Eigen::Affine3f camera_to_world = Eigen::Affine3f::Identity();  // rigid: rotation + translation
  int width = 0, height = 0;
  float fl_x = 0, fl_y = 0, cx = 0, cy = 0;

  // A camera with vertical field of view `yfov` (radians) and square pixels, centred.
  static PinholeCamera from_vertical_fov(std::string name, const Eigen::Affine3f& camera_to_world, float yfov,
                                         int width, int height);

  // The ray through film point (x, y) in pixels (x to the right, y down).
  Ray generate_ray(float x, float y) const {
    const Vec3 local((x - cx) / fl_x, -(y - cy) / fl_y, -1.0f);
    return {camera_to_world.translation(), (camera_to_world.linear() * local).normalized()};
  }
  Vec3 position() const { return camera_to_world.translation(); }
};

}  // namespace glaze
