// math.h: the small value types every other file speaks in.
//
// Directions and points are Eigen fixed-size vectors; colours are Eigen arrays, so
// that `a * b` on colours is component-wise. Rendering runs in float; quantities that
// sum over many terms (SH projection, quadrature) accumulate in double.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace glaze {

using Vec2 = Eigen::Vector2f;
using Vec2d = Eigen::Vector2d;
using Vec3 = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3f;
using Mat3d = Eigen::Matrix3d;
using RGB = Eigen::Array3f;
using RGBd = Eigen::Array3d;

inline constexpr float kPi = std::numbers::pi_v<float>;
inline constexpr double kPiD = std::numbers::pi;

template <typename T>
constexpr T clamp01(T x) {
  return std::clamp(x, T(0), T(1));
}

// Rec. 709 / sRGB-primaries luminance of linear RGB.
inline float luminance(const RGB& c) { return 0.2126f * c[0] + 0.7152f * c[1] + 0.0722f * c[2]; }

// atan2 for floats, |error| < 3e-7 rad (about one float ulp of 2 pi), with atan2's
// quadrant and signed-zero conventions. glibc's atan2f costs ~40 ns on the machines
// glaze runs on and sits in every environment lookup; this is a few flops and no
// branches: atan(a) for a = min/max in [0, 1] by a least-squares polynomial in a^2
// (max error 7e-9 in exact arithmetic), then the octant by selects.
inline float fast_atan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float largest = std::max(ax, ay), smallest = std::min(ax, ay);
  const float a = largest > 0.0f ? smallest / largest : 0.0f;
  const float z = a * a;
  float r = a * (0.99999987116f +
                 z * (-0.33332524003f +
                      z * (0.19984884686f +
                           z * (-0.14154806042f +
                                z * (0.10477539199f +
                                     z * (-0.071943845424f +
                                          z * (0.039345413147f + z * (-0.014152348036f + z * 0.0023981390124f))))))));
  r = ay > ax ? 0.5f * kPi - r : r;
  r = std::signbit(x) ? kPi - r : r;
  return std::copysign(r, y);
}

// sin and cos of 2 pi t, |error| < 3e-8 plus float rounding: the nearest quarter turn
// q / 4 by rounding, Taylor polynomials on the rest (|angle| <= pi / 4), then the
// quarter turn by selects. No branches and no libm call, so loops over it vectorise.
inline void sin_cos_turns(float t, float* sin_out, float* cos_out) {
  const float q = std::floor(4.0f * t + 0.5f);
  const float a = (t - 0.25f * q) * (2.0f * kPi), a2 = a * a;
  const float s = a * (1.0f - a2 / 6.0f * (1.0f - a2 / 20.0f * (1.0f - a2 / 42.0f * (1.0f - a2 / 72.0f))));
  const float c = 1.0f - a2 / 2.0f * (1.0f - a2 / 12.0f * (1.0f - a2 / 30.0f * (1.0f - a2 / 56.0f)));
  const int quarter = static_cast<int>(q) & 3;
  *sin_out = quarter == 0 ? s : quarter == 1 ? c : quarter == 2 ? -s : -c;
  *cos_out = quarter == 0 ? c : quarter == 1 ? -s : quarter == 2 ? -c : s;
}

// Rotation by `degrees` about +Y (right-handed: +Z turns towards +X).
inline Mat3 rotation_about_y(float degrees) {
  return Eigen::AngleAxisf(degrees * kPi / 180.0f, Vec3::UnitY()).toRotationMatrix();
}

// An orthonormal frame with `n` as its local +Z (Duff et al. 2017, branchless), so that
// shading code can work with cos(theta) = local z.
struct Frame {
  Vec3 s, t, n;

  static Frame from_normal(const Vec3& n) {
    const float sign = std::copysign(1.0f, n.z());
    const float a = -1.0f / (sign + n.z());
    const float b = n.x() * n.y() * a;
    return {Vec3(1.0f + sign * n.x() * n.x() * a, sign * b, -sign * n.x()), Vec3(b, sign + n.y() * n.y() * a, -n.y()),
            n};
  }
  Vec3 to_local(const Vec3& v) const { return {v.dot(s), v.dot(t), v.dot(n)}; }
  Vec3 to_world(const Vec3& v) const { return s * v.x() + t * v.y() + n * v.z(); }
};

}  // namespace glaze
