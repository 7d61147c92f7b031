// sphere_intersection.h: the ray-sphere root, the one formula behind every analytic
// sphere hit: RayTracer's (a ray at a time) and the path tracer's single-sphere kernel
// (16 rays at a time, where the compiler turns the same inline code into SIMD).
//
// In double: the inverse fits depend on exact normals. Written with selects instead of
// early returns so that a loop over rays that calls it vectorises.
#pragma once

#include "renderer/math.h"

#include <cmath>
#include <limits>

namespace glaze {

// Nearest root t in (t_min, t_max) of |o + t d - c| = r, given oc = o - c; NaN if none.
inline double sphere_hit_distance(double oc_x, double oc_y, double oc_z, double d_x, double d_y, double d_z,
                                  double radius, double t_min, double t_max) {
  const double a = d_x * d_x + d_y * d_y + d_z * d_z;
  const double half_b = oc_x * d_x + oc_y * d_y + oc_z * d_z;
  const double c = oc_x * oc_x + oc_y * oc_y + oc_z * oc_z - radius * radius;
  const double discriminant = half_b * half_b - a * c;
  // Numerically stable roots (no cancellation between -b and sqrt(disc)).
  const double q = -(half_b + std::copysign(std::sqrt(std::max(discriminant, 0.0)), half_b));
  const double t0 = q / a, t1 = q != 0.0 ? c / q : t0;
  const double near = std::min(t0, t1), far = std::max(t0, t1);
  const double t = near > t_min && near < t_max ? near : far;
  const bool hit = discriminant >= 0.0 && t > t_min && t < t_max;
  return hit ? t : std::numeric_limits<double>::quiet_NaN();
}

inline double sphere_hit_distance(const Vec3& origin, const Vec3& direction, const Vec3& center, float radius,
                                  double t_min, double t_max) {
  const Vec3d oc = (origin - center).cast<double>();
  return sphere_hit_distance(oc.x(), oc.y(), oc.z(), direction.x(), direction.y(), direction.z(), radius, t_min, t_max);
}

}  // namespace glaze
