#include "renderer/texture.h"

#include <cmath>

namespace glaze {
namespace {

// `u` reduced so that scaling it by the image size stays finite and exact enough: a
// non-finite one reads the origin; one farther than 2^20 from the image (where a float
// has no more than 3 fractional bits) is first brought into the image's first tile (or
// pair of tiles, when mirrored), so that a coordinate of 3e38 cannot overflow to Inf.
float reduced(float u, Wrap wrap) {
  if (!std::isfinite(u)) return 0.0f;
  if (std::abs(u) <= 1048576.0f) return u;
  switch (wrap) {
    case Wrap::clamp:
      return u < 0.0f ? 0.0f : 1.0f;
    case Wrap::repeat:
      return u - std::floor(u);
    case Wrap::mirrored_repeat:
      return u - 2.0f * std::floor(0.5f * u);
  }
  return 0.0f;
}

}  // namespace

RGB Texture::lookup(const Vec2& uv) const {
  const Vec2 at(reduced(uv.x(), wrap_u), reduced(uv.y(), wrap_v));
  BilinearFootprint footprint = bilinear_footprint(at, image.width, image.height, wrap_u, wrap_v);
  if (nearest) {  // the texel whose square holds the point: the nearer of each pair of centres
    footprint.fx = footprint.fx < 0.5f ? 0.0f : 1.0f;
    footprint.fy = footprint.fy < 0.5f ? 0.0f : 1.0f;
  }
  return bilinear(image, footprint);
}

}  // namespace glaze
