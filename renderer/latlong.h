// latlong.h: the lat-long parameterisation of directions (docs/design.md §3), in a map's own
// frame: u = atan2(d.x, -d.z) / (2 pi) mod 1, v = acos(d.y) / pi, row 0 at +Y.
#pragma once

#include "renderer/math.h"

#include <algorithm>
#include <cmath>

namespace glaze {

// Unit direction of map coordinates uv; also gives sin(theta) if asked (samplers need it).
inline Vec3 latlong_to_direction(const Vec2& uv, float* sin_theta_out = nullptr) {
  const float theta = uv.y() * kPi, phi = uv.x() * 2.0f * kPi;
  const float sin_theta = std::sin(theta);
  if (sin_theta_out) *sin_theta_out = sin_theta;
  return {sin_theta * std::sin(phi), std::cos(theta), -sin_theta * std::cos(phi)};
}

// d need not be normalised. theta comes from atan2, which keeps full relative precision
// near the poles where acos(d.y) loses it (that matters to sampling densities there).
// Also gives sin(theta) if asked, accurate near the poles too. Free of branches and of
// Eigen's SSE scalar square root, so that loops over many directions vectorise.
inline Vec2 direction_to_latlong(const Vec3& d, float* sin_theta_out = nullptr) {
  float u = fast_atan2(d.x(), -d.z()) * (0.5f / kPi);
  if (u < 0.0f) u += 1.0f;
  if (u >= 1.0f) u = 0.0f;  // u = -0 rounds onto 1
  const float rho = std::sqrt(d.x() * d.x() + d.z() * d.z());
  if (sin_theta_out) *sin_theta_out = rho / std::sqrt(rho * rho + d.y() * d.y());  // not d.norm(): see below
  const float v = fast_atan2(rho, d.y()) / kPi;
  return {u, std::min(v, 1.0f)};
}

// The texel of a width x height lat-long map that contains map coordinates uv (row-major
// index; u wraps around, v is clamped to the map).
// Worked out in float (exact for any map size) and converted last, so that a loop of
// lookups vectorises.
inline int texel_of(const Vec2& uv, int width, int height) {
  const float i = std::clamp(std::floor((uv.x() - std::floor(uv.x())) * width), 0.0f, float(width - 1));
  const float j = std::clamp(std::floor(uv.y() * height), 0.0f, float(height - 1));
  return static_cast<int>(j) * width + static_cast<int>(i);
}

// The exact solid angle of a texel in row j of a width x height lat-long map.
inline double latlong_texel_solid_angle(int j, int width, int height) {
  return 2.0 * kPiD / width * (std::cos(kPiD * j / height) - std::cos(kPiD * (j + 1) / height));
}

}  // namespace glaze
