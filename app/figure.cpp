#include "app/figure.h"

#include "app/canvas.h"
#include "renderer/error.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace glaze {
namespace {

// The whole factor that brings max(width, height) to at most max_size.
int shrink_factor(int width, int height, int max_size) {
  const int longer = std::max(width, height);
  return std::max(1, (longer + max_size - 1) / max_size);
}

// Box filter by a whole factor (partial blocks at the edges average what they have).
// Non-finite pixels (an error image's "not compared") stay out of the averages; a block
// with none finite stays NaN.
Image shrink(const Image& image, int factor) {
  if (factor == 1) return image;
  Image small((image.width + factor - 1) / factor, (image.height + factor - 1) / factor);
  for (int y = 0; y < small.height; ++y)
    for (int x = 0; x < small.width; ++x) {
      RGB sum = RGB::Zero();
      int count = 0;
      for (int j = y * factor; j < std::min(image.height, (y + 1) * factor); ++j)
        for (int i = x * factor; i < std::min(image.width, (x + 1) * factor); ++i)
          if (const RGB c = image.at(i, j); c.allFinite()) sum += c, ++count;
      small.set(x, y, count ? RGB(sum / float(count)) : RGB::Constant(NAN));
    }
  return small;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

constexpr int kMargin = 12, kGap = 10, kTitleHeight = 40, kLineHeight = 17, kTextSize = 14;

// Width of text in pixels, roughly (DejaVu Sans averages about 0.6 em a character).
int text_width(const std::string& text, int size) {
  size_t longest = 0;
  for (const std::string& line : lines_of(text)) longest = std::max(longest, line.size());
  return int(longest) * size * 6 / 10 + 4;
}

// Enlarged by a whole factor (nearest texel, so that texels stay visible as squares)
// while the longer side stays within max_size.
Image enlarge(const Image& image, int max_size) {
  const int factor = max_size / std::max(image.width, image.height);
  if (factor < 2) return image;
  Image large(image.width * factor, image.height * factor);
  for (int y = 0; y < large.height; ++y)
    for (int x = 0; x < large.width; ++x) large.set(x, y, image.at(x / factor, y / factor));
  return large;
}

}  // namespace

FigurePanel picture_panel(const Image& image, const DisplaySettings& display, const std::string& caption,
                          int max_size) {
  const Image sized = enlarge(shrink(image, shrink_factor(image.width, image.height, max_size)), max_size);
  return {sized.width, sized.height, display_image(sized, display), caption};
}

FigurePanel error_panel(const Image& image, const Image& reference, std::span<const uint8_t> mask, float full_scale,
                        const std::string& caption, int max_size) {
  if (image.width != reference.width || image.height != reference.height ||
      mask.size() != size_t(image.width) * image.height)
    throw Error("error_panel: the image, the reference and the mask differ in size");
  double sum = 0.0;
  size_t count = 0;
  for (size_t p = 0; p < mask.size(); ++p)
    if (mask[p]) sum += reference.pixels[3 * p] + reference.pixels[3 * p + 1] + reference.pixels[3 * p + 2], count += 3;
  const double mean = count ? sum / count : 0.0;
  Image error(image.width, image.height);  // NaN where not compared
  for (size_t p = 0; p < mask.size(); ++p) {
    float worst = NAN;
    if (mask[p] && mean > 0.0) {
      worst = 0.0f;
      for (int c = 0; c < 3; ++c)
        worst = std::max(worst, float(std::abs(image.pixels[3 * p + c] - reference.pixels[3 * p + c]) / mean));
    }
    for (int c = 0; c < 3; ++c) error.pixels[3 * p + c] = worst;
  }
  const Image sized = enlarge(shrink(error, shrink_factor(image.width, image.height, max_size)), max_size);
  const int width = sized.width, height = sized.height;
  std::vector<float> values(size_t(width) * height);
  for (size_t p = 0; p < values.size(); ++p) values[p] = sized.pixels[3 * p];
  return {width, height, false_colour_image(values, width, height, 0.0f, full_scale, false), caption};
}

float exposure_for(const Image& image) {
  double sum = 0.0;
  size_t count = 0;
  for (size_t p = 0; p * 3 < image.pixels.size(); ++p) {
    const double luminance =
        0.2126 * image.pixels[3 * p] + 0.7152 * image.pixels[3 * p + 1] + 0.0722 * image.pixels[3 * p + 2];
    if (luminance > 0.0 && std::isfinite(luminance)) sum += luminance, ++count;
  }
  return count && sum > 0.0 ? float(std::log2(0.18 / (sum / count))) : 0.0f;
}

void write_figure(const std::string& path, const Figure& figure) {
  // Column widths and row heights (picture plus its caption lines) from the panels.
  size_t columns = 0;
  for (const auto& row : figure.rows) columns = std::max(columns, row.size());
  std::vector<int> column_width(columns, 0), row_height(figure.rows.size(), 0);
  for (size_t r = 0; r < figure.rows.size(); ++r)
    for (size_t c = 0; c < figure.rows[r].size(); ++c) {
      const FigurePanel& panel = figure.rows[r][c];
      column_width[c] = std::max({column_width[c], panel.width, text_width(panel.caption, 12)});
      row_height[r] = std::max(row_height[r], panel.height + kLineHeight * int(lines_of(panel.caption).size()) + 6);
    }
  int label_width = 0;
  for (const std::string& label : figure.row_labels)
    label_width = std::max(label_width, text_width(label, kTextSize) + kGap);
  int width = 2 * kMargin + label_width, height = 2 * kMargin + kTitleHeight;
  for (int w : column_width) width += w + kGap;
  for (int h : row_height) height += h + kGap;
  width = std::max(width, text_width(figure.title, 18) + 2 * kMargin);

  Canvas canvas(width, height);
  canvas.text(kMargin, kMargin + kTitleHeight / 2, figure.title, 18, Canvas::AlignX::Left);
  int y = kMargin + kTitleHeight;
  for (size_t r = 0; r < figure.rows.size(); ++r) {
    if (r < figure.row_labels.size()) {
      const std::vector<std::string> label = lines_of(figure.row_labels[r]);
      for (size_t l = 0; l < label.size(); ++l)
        canvas.text(kMargin, y + row_height[r] / 2 + int(l * kLineHeight) - int(label.size() * kLineHeight) / 2,
                    label[l], kTextSize, Canvas::AlignX::Left);
    }
    int x = kMargin + label_width;
    for (size_t c = 0; c < figure.rows[r].size(); ++c) {
      const FigurePanel& panel = figure.rows[r][c];
      canvas.paste(x, y, panel.width, panel.height, panel.srgb);
      const std::vector<std::string> caption = lines_of(panel.caption);
      for (size_t l = 0; l < caption.size(); ++l)
        canvas.text(x, y + panel.height + 4 + int(l * kLineHeight) + kLineHeight / 2, caption[l], 12,
                    Canvas::AlignX::Left);
      x += column_width[c] + kGap;
    }
    y += row_height[r] + kGap;
  }
  canvas.write(path);
  if (!canvas.text_ok()) warn(path + ": the figure has no text " + std::string(Canvas::kNoFont));
}

}  // namespace glaze
