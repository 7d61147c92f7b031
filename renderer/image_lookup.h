// image_lookup.h: the bilinear lookup in an Image, the one behind environment maps,
// textures and the inverse module's samples between pixel centres, and a Catmull-Rom
// lookup for reading photographs where blur costs accuracy (the light probe).
//
// Coordinates are in pixels: texel (i, j) covers [i, i + 1) x [j, j + 1), its centre at
// (i + 0.5, j + 0.5); map coordinates (u, v) in [0, 1)^2 are (u W, v H). A lookup blends
// the four texels whose centres surround the point by their distances to it. Past the
// image's edges each axis wraps by its own mode, named as glTF samplers name them:
// repeat (the image tiles), clamp (the edge texels continue) or mirrored repeat (every
// other tile mirrored).
//
// Everything is inline, with indices worked out in float and converted last: for wrap
// modes known where it is called a lookup has no branch and no call, so that a loop of
// them vectorises (Environment::locate). Indices are exact for coordinates within 2^22
// texels of the image; farther out they still name texels of the image.
#pragma once

#include "renderer/image.h"

#include <algorithm>
#include <cmath>

namespace glaze {

enum class Wrap { repeat, clamp, mirrored_repeat };

// The four texels a lookup reads: columns x0, x1 of rows y0, y1, with the weights of
// column x1 and row y1 (x0 and y0 weigh 1 - fx and 1 - fy).
struct BilinearFootprint {
  int x0, x1, y0, y1;
  float fx, fy;
};

namespace image_lookup_detail {

// x clamped to [0, highest], NaN to 0 (std::clamp passes NaN through, and converting a
// NaN index to int is undefined): std::max(0, NaN) is 0.
[[gnu::always_inline]] inline float clamp_index(float x, float highest) { return std::min(std::max(0.0f, x), highest); }

// t mod n for a whole number t (as a float): the quotient is taken at t + 0.5, half a
// texel from where it steps, so that its rounding cannot make it step early or late.
// The clamp only matters beyond 2^22 texels, where float quotients are too coarse, and
// for infinite t (Inf - Inf is NaN).
[[gnu::always_inline]] inline float floor_mod(float t, float n) {
  const float inverse = 1.0f / n;
  return clamp_index(t - n * std::floor(t * inverse + 0.5f * inverse), n - 1.0f);
}

// The texel that whole number t names on an axis of n texels.
[[gnu::always_inline]] inline float wrap_index(float t, float n, Wrap wrap) {
  switch (wrap) {
    case Wrap::clamp:
      return clamp_index(t, n - 1.0f);
    case Wrap::repeat:
      return floor_mod(t, n);
    case Wrap::mirrored_repeat: {
      const float r = floor_mod(t, 2.0f * n);
      return r < n ? r : 2.0f * n - 1.0f - r;
    }
  }
  return t;
}

// The texel after i = wrap_index(t, n, wrap), i.e. wrap_index(t + 1, n, wrap), which
// repeating finds without a second quotient.
[[gnu::always_inline]] inline float next_index(float i, float t, float n, Wrap wrap) {
  if (wrap == Wrap::repeat) return i + 1.0f == n ? 0.0f : i + 1.0f;
  return wrap_index(t + 1.0f, n, wrap);
}

}  // namespace image_lookup_detail

// The footprint of the lookup at pixel coordinates (x, y) in a width x height image.
[[gnu::always_inline]] inline BilinearFootprint bilinear_footprint(float x, float y, int width, int height, Wrap wrap_x,
                                                                   Wrap wrap_y) {
  using namespace image_lookup_detail;
  const float xc = x - 0.5f, yc = y - 0.5f;  // in units where texel centres are whole numbers
  const float x_floor = std::floor(xc), y_floor = std::floor(yc);
  const float w = float(width), h = float(height);
  const float x0 = wrap_index(x_floor, w, wrap_x), y0 = wrap_index(y_floor, h, wrap_y);
  BilinearFootprint at;
  at.x0 = static_cast<int>(x0);
  at.x1 = static_cast<int>(next_index(x0, x_floor, w, wrap_x));
  at.y0 = static_cast<int>(y0);
  at.y1 = static_cast<int>(next_index(y0, y_floor, h, wrap_y));
  at.fx = xc - x_floor;
  at.fy = yc - y_floor;
  return at;
}

// The same at map coordinates uv.
[[gnu::always_inline]] inline BilinearFootprint bilinear_footprint(const Vec2& uv, int width, int height, Wrap wrap_u,
                                                                   Wrap wrap_v) {
  return bilinear_footprint(uv.x() * width, uv.y() * height, width, height, wrap_u, wrap_v);
}

// The value the lookup blends from `image` over footprint `at`.
[[gnu::always_inline]] inline RGB bilinear(const Image& image, const BilinearFootprint& at) {
  const RGB top = (1.0f - at.fx) * image.at(at.x0, at.y0) + at.fx * image.at(at.x1, at.y0);
  const RGB bottom = (1.0f - at.fx) * image.at(at.x0, at.y1) + at.fx * image.at(at.x1, at.y1);
  return (1.0f - at.fy) * top + at.fy * bottom;
}

// The sixteen pixels (columns x[0..3] of rows y[0..3], clamped at the edges) and their
// weights of the Catmull-Rom lookup at pixel coordinates (x, y). Catmull-Rom passes
// through every pixel centre and reproduces linear ramps, as the bilinear lookup does,
// but its blur is narrower: a bright spot a pixel or two across keeps more of its peak.
// Its weights dip below zero beside a step, so a blend of non-negative values may undershoot.
struct CubicFootprint {
  int x[4], y[4];
  float wx[4], wy[4];
};

[[gnu::always_inline]] inline CubicFootprint catmull_rom_footprint(float x, float y, int width, int height) {
  // The Catmull-Rom weights of the four samples at offsets -1, 0, 1, 2 around t in [0, 1).
  const auto weights = [](float t, float* w) {
    w[0] = ((-0.5f * t + 1.0f) * t - 0.5f) * t;
    w[1] = (1.5f * t - 2.5f) * t * t + 1.0f;
    w[2] = ((-1.5f * t + 2.0f) * t + 0.5f) * t;
    w[3] = (0.5f * t - 0.5f) * t * t;
  };
  using image_lookup_detail::clamp_index;
  const float xc = x - 0.5f, yc = y - 0.5f;
  const float x_floor = std::floor(xc), y_floor = std::floor(yc);
  CubicFootprint at;
  for (int k = 0; k < 4; ++k) {
    at.x[k] = static_cast<int>(clamp_index(x_floor - 1.0f + float(k), float(width) - 1.0f));
    at.y[k] = static_cast<int>(clamp_index(y_floor - 1.0f + float(k), float(height) - 1.0f));
  }
  weights(xc - x_floor, at.wx);
  weights(yc - y_floor, at.wy);
  return at;
}

// The value the Catmull-Rom lookup blends from `image` over footprint `at`.
inline RGB catmull_rom(const Image& image, const CubicFootprint& at) {
  RGB value = RGB::Zero();
  for (int j = 0; j < 4; ++j) {
    RGB row = RGB::Zero();
    for (int i = 0; i < 4; ++i) row += at.wx[i] * image.at(at.x[i], at.y[j]);
    value += at.wy[j] * row;
  }
  return value;
}

}  // namespace glaze
