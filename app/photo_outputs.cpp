#include "app/photo_outputs.h"

#include "app/plot.h"

#include <cmath>
#include <cstdio>
#include <iostream>

namespace glaze {

namespace {

// The response curve as a chart: normalised code against relative exposure, log-log.
void plot_response(const std::string& path, const CameraResponse& response) {
  LogLogPlot plot{"camera response (" + method_name(response.method) + ")", "relative exposure", "code / 255", {}, {}};
  const RGB colours[3] = {RGB(0.85f, 0.1f, 0.1f), RGB(0.1f, 0.6f, 0.1f), RGB(0.1f, 0.2f, 0.85f)};
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    PlotSeries series{names[c], {}, {}, colours[c], false};
    for (int z = response.well_constrained[c][0]; z <= response.well_constrained[c][1]; ++z) {
      series.x.push_back(std::exp(response.log_exposure[c][z]));
      series.y.push_back(z / 255.0);
    }
    plot.series.push_back(series);
  }
  write_loglog_plot(path, plot);
}

}  // namespace

std::string percent_text(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f%%", 100.0 * fraction);
  return text;
}

void write_response(OutputFolder& out, const CameraResponse& response, nlohmann::json& report) {
  if (response.method == ResponseMethod::kLinear) return;
  out.write_text("response.json", response_json(response).dump(2) + "\n");
  plot_response(out.file("response.png").string(), response);
  report["response_file"] = "response.json";
}

nlohmann::json write_merged(OutputFolder& out, const Bracket& bracket, const MergedBracket& merged,
                            const CameraResponse& response) {
  const HdrMerge& merge = merged.merge;
  nlohmann::json exposures = nlohmann::json::array();
  for (size_t j = 0; j < bracket.exposures.size(); ++j)
    exposures.push_back({{"file", bracket.exposures[j].file.string()},
                         {"exposure", bracket.exposures[j].exposure},
                         {"shift", {merged.shifts[j].dx, merged.shifts[j].dy}}});
  const std::string file = bracket.name() + ".exr";
  out.write_image(file, merge.radiance,
                  {{"glaze:saturated_fraction", std::to_string(merge.saturated_fraction())},
                   {"glaze:underexposed_fraction", std::to_string(merge.underexposed_fraction())},
                   {"glaze:response", method_name(response.method)},
                   {"glaze:exposures", std::to_string(bracket.exposures.size())}},
                  merge.alpha);
  std::cerr << bracket.name() << ": " << bracket.exposures.size() << " exposures merged, "
            << percent_text(merge.saturated_fraction()) << " saturated in every exposure (alpha 0), "
            << percent_text(merge.underexposed_fraction()) << " underexposed in every exposure -> "
            << out.file(file).string() << "\n";
  return {{"name", bracket.name()},
          {"folder", bracket.folder.string()},
          {"image", file},
          {"exposures", exposures},
          {"saturated_fraction", merge.saturated_fraction()},
          {"underexposed_fraction", merge.underexposed_fraction()}};
}

}  // namespace glaze
