// figure.h: figures for people, as `glaze reproduce` writes them: a titled grid of
// pictures (renders, maps, error images) with a caption under each and a label before
// each row, written as one PNG. Pictures go through the one display transform
// (renderer/display.h); errors through its false-colour ramp.
#pragma once

#include "renderer/display.h"
#include "renderer/image.h"

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace glaze {

struct FigurePanel {
  int width = 0, height = 0;
  std::vector<uint8_t> srgb;  // row-major, 3 bytes a pixel
  std::string caption;        // lines separated by '\n'
};

// `image` under `display`, brought to at most `max_size` pixels on its longer side by
// a whole factor: shrunk by box filtering, or a small one (a texture) enlarged with
// nearest texels.
FigurePanel picture_panel(const Image& image, const DisplaySettings& display, const std::string& caption,
                          int max_size = 256);

// |image - reference| / (reference's mean over the mask), per pixel the largest over the
// channels, in false colour from 0 (dark) to `full_scale` (yellow); pixels outside the
// mask (1 = compared) are black. Sized as picture_panel sizes its picture.
FigurePanel error_panel(const Image& image, const Image& reference, std::span<const uint8_t> mask, float full_scale,
                        const std::string& caption, int max_size = 256);

// An exposure (EV) that shows `image`'s mean over positive pixels as mid-grey, the same
// for every panel that shares it so that they compare.
float exposure_for(const Image& image);

struct Figure {
  std::string title;
  std::vector<std::string> row_labels;  // one per row, or empty
  std::vector<std::vector<FigurePanel>> rows;
};

// Writes the figure as a PNG, atomically. Without a TrueType font it is written without
// text, with a warning.
void write_figure(const std::string& path, const Figure& figure);

}  // namespace glaze
