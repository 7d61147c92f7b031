#include "renderer/texture.h"

#include <cmath>

namespace glaze {

RGB Texture::lookup(const Vec2& uv) const {
  const int width = image.width, height = image.height;
  const float x = uv.x() * width - 0.5f, y = uv.y() * height - 0.5f;
  const float x_floor = std::floor(x), y_floor = std::floor(y);
  const float fx = x - x_floor, fy = y - y_floor;
  auto wrap = [](float coordinate, int size) {
    const int i = static_cast<int>(std::fmod(coordinate, float(size)));
    return i < 0 ? i + size : i;
  };
  const int x0 = wrap(x_floor, width), x1 = (x0 + 1) % width;
  const int y0 = wrap(y_floor, height), y1 = (y0 + 1) % height;
  const RGB top = (1.0f - fx) * image.at(x0, y0) + fx * image.at(x1, y0);
  const RGB bottom = (1.0f - fx) * image.at(x0, y1) + fx * image.at(x1, y1);
  return (1.0f - fy) * top + fy * bottom;
}

}  // namespace glaze
