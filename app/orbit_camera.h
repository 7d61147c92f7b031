// orbit_camera.h: the preview window's interactive camera: orbit about a pivot, pan
// and zoom, starting from (and returning to) a scene's pinhole camera.
//
// It starts as the scene camera exactly (roll included). The pivot is the point on the
// view axis nearest to the scene's centre, so orbiting turns the object in place. Orbit
// turns the pose about the world's up axis (+Y, docs/design.md §3) and about the horizontal axis
// across the view through the pivot; pitch stops 1 degree short of the poles so that "up" stays
// defined.
// Pan moves camera and pivot in the image plane, by image pixels at the pivot's depth
// (the point under the cursor follows it); zoom moves the camera along its axis (an
// orthographic camera magnifies instead).
#pragma once

#include "renderer/camera.h"

namespace glaze {

class OrbitCamera {
 public:
  OrbitCamera(const PinholeCamera& camera, const Vec3& scene_centre);

  // Yaw about world +Y and pitch about the horizontal axis across the view, in radians: positive yaw
  // moves the camera to its right round the pivot, positive pitch moves it up.
  void orbit(float yaw, float pitch);
  // Shifts the view by (dx, dy) image pixels at the pivot's depth (x right, y down).
  void pan(float dx, float dy);
  // Multiplies the distance to the pivot by `factor` (> 0; < 1 moves closer); an
  // orthographic camera's view size instead.
  void zoom(float factor);

  const PinholeCamera& camera() const { return camera_; }
  const Vec3& pivot() const { return pivot_; }
  float distance() const { return distance_; }

 private:
  void place();  // puts the camera at distance_ from the pivot along its axis

  PinholeCamera camera_;
  Vec3 pivot_;
  float distance_;
};

}  // namespace glaze
