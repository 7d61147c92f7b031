#include "renderer/texture.h"

namespace glaze {

RGB Texture::lookup(const Vec2& uv) const {
  const Vec2 at = uv.allFinite() ? uv : Vec2::Zero();
  BilinearFootprint footprint = bilinear_footprint(at, image.width, image.height, wrap_u, wrap_v);
  if (nearest) {  // the texel whose square holds the point: the nearer of each pair of centres
    footprint.fx = footprint.fx < 0.5f ? 0.0f : 1.0f;
    footprint.fy = footprint.fy < 0.5f ? 0.0f : 1.0f;
  }
  return bilinear(image, footprint);
}

}  // namespace glaze
