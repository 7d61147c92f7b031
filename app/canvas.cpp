#include "app/canvas.h"

#include "renderer/image.h"

#include <cstdlib>
#include <vector>

namespace glaze {

Canvas::Canvas(int width, int height)
    : width_(width), height_(height), buffer_(OIIO::ImageSpec(width, height, 3, OIIO::TypeDesc::FLOAT)) {
  const float white[3] = {1, 1, 1};
  OIIO::ImageBufAlgo::fill(buffer_, white);
}

void Canvas::line(int x0, int y0, int x1, int y1, const RGB& c, int thickness) {
  const float colour[3] = {c[0], c[1], c[2]};
  for (int t = 0; t < thickness; ++t) {  // thicker lines as parallel offsets
    const int o = t - thickness / 2;
    const bool steep = std::abs(y1 - y0) > std::abs(x1 - x0);
    OIIO::ImageBufAlgo::render_line(buffer_, x0 + (steep ? o : 0), y0 + (steep ? 0 : o), x1 + (steep ? o : 0),
                                    y1 + (steep ? 0 : o), colour);
  }
}

void Canvas::dashed(int x0, int y, int x1, const RGB& c) {
  for (int x = x0; x < x1; x += 12) line(x, y, std::min(x + 6, x1), y, c);
}

void Canvas::box(int x0, int y0, int x1, int y1, const RGB& c, bool fill) {
  const float colour[3] = {c[0], c[1], c[2]};
  OIIO::ImageBufAlgo::render_box(buffer_, x0, y0, x1, y1, colour, fill);
}

void Canvas::text(int x, int y, const std::string& s, int size, AlignX ax, AlignY ay) {
  const float black[3] = {0, 0, 0};
  if (!text_ok_ || s.empty()) return;
  text_ok_ = OIIO::ImageBufAlgo::render_text(buffer_, x, y, s, size, "DejaVuSans", black, ax, ay);
  if (!text_ok_) (void)buffer_.geterror();
}

// OIIO draws text horizontally only, so it is drawn on its own buffer and rotated into place.
void Canvas::vertical_text(int x, int y, const std::string& s, int size, int length) {
  if (!text_ok_ || s.empty()) return;
  const int thickness = 2 * size + 6;
  OIIO::ImageBuf label(OIIO::ImageSpec(length, thickness, 3, OIIO::TypeDesc::FLOAT));
  const float white[3] = {1, 1, 1}, black[3] = {0, 0, 0};
  OIIO::ImageBufAlgo::fill(label, white);
  text_ok_ = OIIO::ImageBufAlgo::render_text(label, length / 2, thickness / 2, s, size, "DejaVuSans", black,
                                             AlignX::Center, AlignY::Center);
  if (!text_ok_) return;
  // Label pixel (i, j) goes to (x - thickness/2 + j, y + length/2 - i).
  std::vector<float> pixel(3);
  for (int j = 0; j < thickness; ++j)
    for (int i = 0; i < length; ++i) {
      label.getpixel(i, j, pixel.data(), 3);
      if (pixel[0] < 0.99f) buffer_.setpixel(x - thickness / 2 + j, y + length / 2 - i, pixel.data(), 3);
    }
}

void Canvas::paste(int x, int y, int width, int height, std::span<const uint8_t> srgb) {
  float pixel[3];
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) {
      if (x + i < 0 || x + i >= width_ || y + j < 0 || y + j >= height_) continue;
      const uint8_t* p = &srgb[(size_t(j) * width + i) * 3];
      for (int c = 0; c < 3; ++c) pixel[c] = p[c] / 255.0f;
      buffer_.setpixel(x + i, y + j, pixel, 3);
    }
}

void Canvas::write(const std::string& path) const {
  std::vector<uint8_t> pixels(size_t(width_) * height_ * 3);
  buffer_.get_pixels(OIIO::ROI(0, width_, 0, height_, 0, 1, 0, 3), OIIO::TypeDesc::UINT8, pixels.data());
  write_picture(path, width_, height_, pixels);
}

}  // namespace glaze
