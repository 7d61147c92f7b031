// camera.h: the camera model shared by glTF scenes and capture sets (docs/design.md §3):
// a pinhole (perspective projection), optionally seen through a distorting lens
// (lens_distortion.h), or an orthographic projection.
//
// Intrinsics are in pixels (fl_x, fl_y, cx, cy, as nerfstudio's transforms.json); the
// pose is camera-to-world with OpenGL axes (+X right, +Y up, looking along -Z). Pixel
// (i, j), column i and row j from the top, has its centre at (i + 0.5, j + 0.5), and film
// point (x, y) has the camera-space offset (u, v) = ((x - cx)/fl_x, -(y - cy)/fl_y).
// Perspective: every ray starts at the camera's position, along (u, v, -1). Orthographic:
// fl_x and fl_y are pixels per world unit, and the ray starts on the film plane at
// (u, v, 0), along -Z. The two share the intrinsics so that film size, principal point
// and square pixels mean one thing for both. A lens moves where each ray meets the film:
// generate_ray() undistorts the film point first and project() distorts last, so that
// photographs are compared with renders pixel for pixel, never resampled.
#pragma once

#include "renderer/lens_distortion.h"
#include "renderer/math.h"

#include <optional>
#include <string>

namespace glaze {

struct Ray {
  Vec3 origin;
  Vec3 direction;  // unit length
};

enum class Projection { perspective, orthographic };

struct PinholeCamera {
  std::string name;
  Eigen::Affine3f camera_to_world = Eigen::Affine3f::Identity();  // rigid: rotation + translation
  int width = 0, height = 0;
  float fl_x = 0, fl_y = 0, cx = 0, cy = 0;
  Projection projection = Projection::perspective;
  LensDistortion distortion;  // perspective cameras only

  // A perspective camera with vertical field of view `yfov` (radians) and square pixels, centred.
  static PinholeCamera from_vertical_fov(std::string name, const Eigen::Affine3f& camera_to_world, float yfov,
                                         int width, int height);
  // An orthographic camera whose film is 2 `ymag` world units high, square pixels, centred.
  static PinholeCamera orthographic(std::string name, const Eigen::Affine3f& camera_to_world, float ymag, int width,
                                    int height);

  // The ray through film point (x, y) in pixels (x to the right, y down).
  Ray generate_ray(float x, float y) const {
    Vec3 local((x - cx) / fl_x, -(y - cy) / fl_y, -1.0f);
    if (projection == Projection::orthographic)
      return {camera_to_world * Vec3(local.x(), local.y(), 0.0f), -camera_to_world.linear().col(2).normalized()};
    if (!distortion.is_none()) local = undistorted_direction(local);
    return {camera_to_world.translation(), (camera_to_world.linear() * local).normalized()};
  }
  // The film point that camera-space point `local` projects to (generate_ray's inverse),
  // or nothing when it is behind the camera (perspective) or the film plane (orthographic).
  std::optional<Vec2> project(const Vec3& local) const {
    if (!(local.z() < 0.0f)) return std::nullopt;
    if (projection == Projection::orthographic) return Vec2(cx + fl_x * local.x(), cy - fl_y * local.y());
    Vec2d image(local.x() / -local.z(), -local.y() / -local.z());  // OpenCV's axes: y down
    if (!distortion.is_none()) image = distortion.distort(image);
    return Vec2(cx + fl_x * float(image.x()), cy + fl_y * float(image.y()));
  }
  Vec3 position() const { return camera_to_world.translation(); }

  // Throws glaze::Error (naming `where`) unless the lens model is one-to-one over the
  // whole film, so that every pixel has exactly one ray, and the camera is perspective
  // when it has a lens.
  void check_lens(const std::string& where) const;

 private:
  // The pinhole direction (x, y, -1) of the distorted film offset `local` (x, y, -1).
  Vec3 undistorted_direction(const Vec3& local) const;
};

}  // namespace glaze
