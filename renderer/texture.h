// texture.h: an RGB image mapped over a surface by texture coordinates, read as a glTF
// sampler says: bilinear (image_lookup.h) or nearest, each axis repeating, clamped or
// mirrored outside [0, 1) (repeating by default). Texel (0, 0) is at the top-left of the
// image with uv = (0, 0) (glTF's convention: v grows downwards in the image). There are no
// mipmaps: a renderer that averages many samples per pixel filters minification itself.
#pragma once

#include "renderer/image.h"
#include "renderer/image_lookup.h"

#include <string>

namespace glaze {

struct Texture {
  std::string source;  // file or description, for messages
  Image image;         // linear RGB
  Wrap wrap_u = Wrap::repeat, wrap_v = Wrap::repeat;
  bool nearest = false;  // the nearest texel instead of the bilinear blend

  // Any coordinate reads inside the image: non-finite ones read texel (0, 0), huge ones
  // (1e30, 3e38) are reduced to the first tile before they are scaled to texels.
  RGB lookup(const Vec2& uv) const;
};

}  // namespace glaze
