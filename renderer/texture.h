// texture.h: an RGB image mapped over a surface by texture coordinates: bilinear
// (image_lookup.h), repeating outside [0, 1) as glTF's default sampler. Texel (0, 0) is
// at the top-left of the image with uv = (0, 0) (glTF's convention: v grows downwards in
// the image).
#pragma once

#include "renderer/image.h"

#include <string>

namespace glaze {

struct Texture {
  std::string source;  // file or description, for messages
  Image image;         // linear RGB

  RGB lookup(const Vec2& uv) const;
};

}  // namespace glaze
