// plot.h: a log-log line chart written as a PNG, for error-against-time plots that a
// person reads at a glance: labelled axes with decade ticks, a legend, optional
// horizontal reference lines. Drawn with OpenImageIO's ImageBufAlgo (lines, boxes,
// FreeType text with the DejaVu Sans font).
#pragma once

#include "renderer/math.h"

#include <string>
#include <vector>

namespace glaze {

struct PlotSeries {
  std::string label;
  std::vector<double> x, y;  // positive; points with x or y <= 0 are skipped
  RGB colour;
  bool markers = true;
};

struct PlotLine {  // a dashed horizontal line across the chart, labelled at its right end
  double y;
  std::string label;
};

struct LogLogPlot {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<PlotLine> lines;
};

// Writes the chart (atomically). Text needs a TrueType font: if none is found the chart
// is still written, without text, and a warning says to install fonts-dejavu-core.
void write_loglog_plot(const std::string& path, const LogLogPlot& plot);

}  // namespace glaze
