// canvas.h: a white float canvas for the charts and figures glaze writes for people
// (`convergence`'s plot, `reproduce`'s figures): lines, boxes, text and pasted
// pictures, drawn with OpenImageIO's ImageBufAlgo (FreeType text, DejaVu Sans).
// Text needs a TrueType font; without one the canvas is drawn without text and
// text_ok() says so, so that the caller can warn once. Colours are display values in
// [0, 1] (sRGB-encoded, as they are written).
#pragma once

#include "renderer/math.h"

#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>

#include <cstdint>
#include <span>
#include <string>

namespace glaze {

class Canvas {
 public:
  using AlignX = OIIO::ImageBufAlgo::TextAlignX;
  using AlignY = OIIO::ImageBufAlgo::TextAlignY;
  static constexpr const char* kNoFont =
      "(no TrueType font found; install fonts-dejavu-core, e.g. apt-get install fonts-dejavu-core)";

  Canvas(int width, int height);

  void line(int x0, int y0, int x1, int y1, const RGB& c, int thickness = 1);
  void dashed(int x0, int y, int x1, const RGB& c);
  void box(int x0, int y0, int x1, int y1, const RGB& c, bool fill);
  void text(int x, int y, const std::string& s, int size, AlignX ax, AlignY ay = AlignY::Center);
  // Text turned 90 degrees counter-clockwise, centred on (x, y), at most `length` long.
  void vertical_text(int x, int y, const std::string& s, int size, int length);
  // An 8-bit sRGB picture (display.h), its top-left corner at (x, y).
  void paste(int x, int y, int width, int height, std::span<const uint8_t> srgb);

  bool text_ok() const { return text_ok_; }
  // Writes the canvas as an image file (PNG for people), atomically.
  void write(const std::string& path) const;

 private:
  int width_, height_;
  OIIO::ImageBuf buffer_;
  bool text_ok_ = true;
};

}  // namespace glaze
