#include "renderer/texture.h"

#include "renderer/image_lookup.h"

namespace glaze {

RGB Texture::lookup(const Vec2& uv) const {
  return bilinear(image, bilinear_footprint(uv, image.width, image.height, Wrap::repeat, Wrap::repeat));
}

}  // namespace glaze
