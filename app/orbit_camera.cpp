#include "app/orbit_camera.h"

#include <algorithm>
#include <cmath>

namespace glaze {
namespace {

Vec3 forward_of(const PinholeCamera& camera) { return -camera.camera_to_world.linear().col(2); }

}  // namespace

OrbitCamera::OrbitCamera(const PinholeCamera& camera, const Vec3& scene_centre) : camera_(camera) {
  const Vec3 forward = forward_of(camera);
  const Vec3 to_centre = scene_centre - camera.position();
  // A centre behind the camera (or at it) gives no pivot on the axis: use its distance.
  const float along = to_centre.dot(forward);
  distance_ = along > 1e-3f * std::max(1.0f, to_centre.norm()) ? along : std::max(to_centre.norm(), 1.0f);
  pivot_ = camera.position() + distance_ * forward;
}

void OrbitCamera::place() { camera_.camera_to_world.translation() = pivot_ - distance_ * forward_of(camera_); }

void OrbitCamera::orbit(float yaw, float pitch) {
  const Vec3 up(0.0f, 1.0f, 0.0f);
  const Mat3 rotation = camera_.camera_to_world.linear();
  // The view axis's elevation stays within 89 degrees of the horizon: the pitch is
  // clamped, so that no step, however large, carries the view over a pole.
  constexpr float kLimit = 89.0f * kPi / 180.0f;
  const Vec3 forward = -rotation.col(2);
  const float elevation = std::asin(std::clamp(forward.dot(up), -1.0f, 1.0f));
  // (A scene camera already beyond the limit may only turn back towards the horizon.)
  const float limit = std::max(kLimit, std::abs(elevation));
  const float applied = elevation - std::clamp(elevation - pitch, -limit, limit);
  // About the horizontal axis across the view (the camera's right axis unless it is
  // rolled), which changes the elevation by exactly the angle; a camera looking straight
  // up or down has none, and turns about its right axis.
  const Vec3 across = forward.cross(up);
  const Vec3 axis = across.norm() > 1e-6f ? Vec3(across.normalized()) : Vec3(rotation.col(0));
  const Mat3 pitched = Eigen::AngleAxisf(-applied, axis).toRotationMatrix() * rotation;
  camera_.camera_to_world.linear() = Eigen::AngleAxisf(yaw, up).toRotationMatrix() * pitched;
  place();
}

void OrbitCamera::pan(float dx, float dy) {
  const Mat3 rotation = camera_.camera_to_world.linear();
  // One pixel at depth d spans d / fl in world units; orthographic, 1 / fl at any depth.
  const float depth = camera_.projection == Projection::orthographic ? 1.0f : distance_;
  pivot_ += rotation.col(0) * (-dx * depth / camera_.fl_x) + rotation.col(1) * (dy * depth / camera_.fl_y);
  place();
}

void OrbitCamera::zoom(float factor) {
  if (!(factor > 0.0f) || !std::isfinite(factor)) return;
  if (camera_.projection == Projection::orthographic) {
    // Moving an orthographic camera changes nothing it sees (or clips the object): it
    // magnifies instead, as moving a pinhole closer does at the pivot.
    camera_.fl_x /= factor;
    camera_.fl_y /= factor;
    return;
  }
  distance_ = std::clamp(distance_ * factor, 1e-4f, 1e6f);
  place();
}

}  // namespace glaze
