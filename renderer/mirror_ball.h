// mirror_ball.h: a light probe's geometry. A camera ray reflected exactly off a mirror
// ball, as the photo-shoot simulator renders it and the probe builder inverts it.
//
// The cameras of a shoot stand a few ball diameters away, so their rays fan out over the
// ball: each pixel's ray is reflected where it meets the ball, never approximated by an
// orthographic view (docs/design.md §7).
#pragma once

#include "renderer/math.h"
#include "renderer/sphere_intersection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace glaze {

struct MirrorBall {
  Vec3d center = Vec3d::Zero();
  double radius = 0.0;
};

struct BallReflection {
  Vec3d point;           // where the ray meets the ball
  Vec3d normal;          // the ball's outward normal there
  Vec3d direction;       // the reflected ray's direction (unit): the environment it sees
  double cos_incidence;  // cosine between the normal and the way back to the camera, in (0, 1]
};

// The reflection of the ray origin + t direction (direction of unit length) off `ball`,
// or nothing when the ray misses it or starts inside it.
inline std::optional<BallReflection> reflect_off_ball(const Vec3d& origin, const Vec3d& direction,
                                                      const MirrorBall& ball) {
  const Vec3d oc = origin - ball.center;
  if (!(oc.squaredNorm() > ball.radius * ball.radius)) return std::nullopt;
  const double t = sphere_hit_distance(oc.x(), oc.y(), oc.z(), direction.x(), direction.y(), direction.z(), ball.radius,
                                       0.0, std::numeric_limits<double>::infinity());
  if (std::isnan(t)) return std::nullopt;
  BallReflection hit;
  hit.point = origin + t * direction;
  hit.normal = (hit.point - ball.center) / ball.radius;
  hit.cos_incidence = std::clamp(-hit.normal.dot(direction), 0.0, 1.0);
  hit.direction = (direction + 2.0 * hit.cos_incidence * hit.normal).normalized();
  return hit;
}

}  // namespace glaze
