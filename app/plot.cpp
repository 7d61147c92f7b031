#include "app/plot.h"

#include "app/canvas.h"

#include "renderer/error.h"
#include "renderer/image.h"

#include <cmath>
#include <cstdio>

namespace glaze {
namespace {

constexpr int kWidth = 960, kHeight = 640;
constexpr int kLeft = 100, kRight = 250, kTop = 60, kBottom = 80;  // margins around the chart area

// Decade range [floor(log10 min), ceil(log10 max)] of the positive values, at least one decade.
std::pair<int, int> decades(const std::vector<double>& values) {
  double low = INFINITY, high = -INFINITY;
  for (double v : values)
    if (v > 0.0 && std::isfinite(v)) low = std::min(low, v), high = std::max(high, v);
  if (!(low <= high)) return {0, 1};
  const int first = static_cast<int>(std::floor(std::log10(low))), last = static_cast<int>(std::ceil(std::log10(high)));
  return {first, std::max(last, first + 1)};
}

std::string decade_label(int exponent) {
  char text[32];
  if (exponent >= -3 && exponent <= 4)
    std::snprintf(text, sizeof text, "%g", std::pow(10.0, exponent));
  else
    std::snprintf(text, sizeof text, "1e%d", exponent);
  return text;
}

}  // namespace

void write_loglog_plot(const std::string& path, const LogLogPlot& plot) {
  std::vector<double> xs, ys;
  for (const PlotSeries& s : plot.series) {
    xs.insert(xs.end(), s.x.begin(), s.x.end());
    ys.insert(ys.end(), s.y.begin(), s.y.end());
  }
  for (const PlotLine& l : plot.lines) ys.push_back(l.y);
  const auto [x_first, x_last] = decades(xs);
  const auto [y_first, y_last] = decades(ys);
  const int right = kWidth - kRight, bottom = kHeight - kBottom;
  auto px = [&](double x) {
    return kLeft + static_cast<int>(std::lround((std::log10(x) - x_first) / (x_last - x_first) * (right - kLeft)));
  };
  auto py = [&](double y) {
    return bottom - static_cast<int>(std::lround((std::log10(y) - y_first) / (y_last - y_first) * (bottom - kTop)));
  };
  using AlignX = OIIO::ImageBufAlgo::TextAlignX;
  using AlignY = OIIO::ImageBufAlgo::TextAlignY;
  Canvas canvas(kWidth, kHeight);
  const RGB grid(0.88f, 0.88f, 0.88f), minor(0.95f, 0.95f, 0.95f), axis(0.0f, 0.0f, 0.0f);

  // Grid: decades and their 2..9 subdivisions; decade labels on both axes.
  for (int e = x_first; e <= x_last; ++e) {
    for (int k = 2; k <= 9 && e < x_last; ++k)
      canvas.line(px(k * std::pow(10.0, e)), kTop, px(k * std::pow(10.0, e)), bottom, minor);
    canvas.line(px(std::pow(10.0, e)), kTop, px(std::pow(10.0, e)), bottom, grid);
    canvas.text(px(std::pow(10.0, e)), bottom + 18, decade_label(e), 15, AlignX::Center);
  }
  for (int e = y_first; e <= y_last; ++e) {
    for (int k = 2; k <= 9 && e < y_last; ++k)
      canvas.line(kLeft, py(k * std::pow(10.0, e)), right, py(k * std::pow(10.0, e)), minor);
    canvas.line(kLeft, py(std::pow(10.0, e)), right, py(std::pow(10.0, e)), grid);
    canvas.text(kLeft - 8, py(std::pow(10.0, e)), decade_label(e), 15, AlignX::Right);
  }
  canvas.box(kLeft, kTop, right, bottom, axis, false);
  canvas.text((kLeft + right) / 2, 28, plot.title, 20, AlignX::Center);
  canvas.text((kLeft + right) / 2, bottom + 50, plot.x_label, 17, AlignX::Center);
  canvas.vertical_text(30, (kTop + bottom) / 2, plot.y_label, 17, kHeight);

  // Reference lines, then the series with their legend entries.
  int legend_y = kTop + 12;
  for (const PlotLine& l : plot.lines) {
    if (!(l.y > 0.0)) continue;
    canvas.dashed(kLeft, py(l.y), right, RGB(0.45f, 0.45f, 0.45f));
    canvas.text(right - 6, py(l.y) - 10, l.label, 13, AlignX::Right);
  }
  for (const PlotSeries& s : plot.series) {
    int previous_x = 0, previous_y = 0;
    bool has_previous = false;
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i) {
      if (!(s.x[i] > 0.0 && s.y[i] > 0.0 && std::isfinite(s.x[i]) && std::isfinite(s.y[i]))) continue;
      const int x = px(s.x[i]), y = py(s.y[i]);
      if (has_previous) canvas.line(previous_x, previous_y, x, y, s.colour, 2);
      if (s.markers) canvas.box(x - 3, y - 3, x + 3, y + 3, s.colour, true);
      previous_x = x, previous_y = y, has_previous = true;
    }
    canvas.line(right + 16, legend_y, right + 46, legend_y, s.colour, 3);
    canvas.text(right + 54, legend_y, s.label, 14, AlignX::Left, AlignY::Center);
    legend_y += 22;
  }
  canvas.write(path);
  if (!canvas.text_ok()) warn(path + ": the plot has no text " + std::string(Canvas::kNoFont));
}

}  // namespace glaze
