// hdr_merge_command.cpp: `glaze hdr-merge`, exposure brackets merged into linear HDR
// images (docs/design.md §7; inverse/photos/). The camera response of 8-bit photos is
// recovered once from every bracket given, or read from --response; 16-bit and raw
// photos are linear. Writes NAME.exr per bracket (R, G, B and A: 0 where saturated in
// every exposure), response.json and response.png, and last hdr_merge.json.
#include "app/commands.h"
#include "app/plot.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "inverse/photos/bracket.h"
#include "inverse/photos/bracket_alignment.h"
#include "inverse/photos/camera_response.h"
#include "inverse/photos/hdr_merge.h"
#include "renderer/error.h"
#include "renderer/output_folder.h"

#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <set>

namespace glaze {
namespace {

namespace fs = std::filesystem;

struct HdrMergeOptions {
  std::vector<std::string> folders;
  std::string out;
  std::optional<std::string> response;
  int threads = 0;
};

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3f%%", 100.0 * fraction);
  return text;
}

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

int hdr_merge(const HdrMergeOptions& args) {
  std::vector<Bracket> brackets;
  std::set<std::string> names;
  for (const std::string& folder : args.folders)
    for (Bracket& bracket : find_brackets(folder)) {
      if (!names.insert(bracket.name()).second)
        throw Error(bracket.folder.string() + ": another bracket is named " + bracket.name() +
                    " too; each writes NAME.exr, so merge them into different --out folders");
      brackets.push_back(std::move(bracket));
    }
  OutputFolder out(args.out, "hdr_merge.json", "HDR output");
  const auto start = Clock::now();

  // The response: read, linear (16-bit and raw photos), or recovered from samples of
  // every bracket. The last bracket decoded stays decoded, to be merged first.
  std::optional<CameraResponse> response;
  if (args.response) response = read_response(*args.response);
  std::optional<BracketPhotos> decoded;
  std::vector<ResponseSamples> samples;
  for (size_t k = 0; k < brackets.size() && !response; ++k) {
    const Bracket& bracket = brackets[k];
    std::cerr << "reading " << bracket.folder.string() << " (" << bracket.exposures.size() << " exposures, "
              << bracket.exposures.front().exposure << " to " << bracket.exposures.back().exposure << " s)\n";
    decoded = read_bracket(bracket);
    const PhotoCodes& photo = decoded->photos.front();
    if (!photo.linear) {
      samples.push_back(sample_bracket(*decoded));
      continue;
    }
    if (!samples.empty())
      throw Error(bracket.folder.string() + ": holds linear " + std::to_string(photo.bits) +
                  "-bit photos, the brackets before it 8-bit ones; merge them separately");
    response = linear_response(photo.bits);  // merge_bracket refuses a bracket stored otherwise
  }
  if (!response) {
    response = recover_response(samples);
    std::cerr << "camera response recovered (Debevec and Malik) from " << response->samples << " sample pixels of "
              << samples.size() << " bracket(s); well constrained from code " << response->well_constrained[1][0]
              << " to " << response->well_constrained[1][1] << " (green)\n";
  }

  nlohmann::json report = {{"response", response_json(*response)}, {"brackets", nlohmann::json::array()}};
  if (response->method != ResponseMethod::kLinear) {
    out.write_text("response.json", response_json(*response).dump(2) + "\n");
    plot_response(out.file("response.png").string(), *response);
    report["response_file"] = "response.json";
  }
  for (size_t k = brackets.size(); k-- > 0;) {  // the last first: it may be decoded already
    const Bracket& bracket = brackets[k];
    BracketPhotos photos =
        decoded && decoded->bracket.folder == bracket.folder ? std::move(*decoded) : read_bracket(bracket);
    decoded.reset();
    const std::vector<ExposureShift> shifts = bracket_shifts(photos, *response);
    warn_misaligned(photos, shifts);
    const HdrMerge merge = merge_bracket(photos, *response);
    warn_coverage(bracket, merge);
    nlohmann::json exposures = nlohmann::json::array();
    for (size_t j = 0; j < bracket.exposures.size(); ++j)
      exposures.push_back({{"file", bracket.exposures[j].file.string()},
                           {"exposure", bracket.exposures[j].exposure},
                           {"shift", {shifts[j].dx, shifts[j].dy}}});
    const std::string file = bracket.name() + ".exr";
    out.write_image(file, merge.radiance,
                    {{"glaze:saturated_fraction", std::to_string(merge.saturated_fraction())},
                     {"glaze:underexposed_fraction", std::to_string(merge.underexposed_fraction())},
                     {"glaze:response", method_name(response->method)},
                     {"glaze:exposures", std::to_string(bracket.exposures.size())}},
                    merge.alpha);
    report["brackets"].push_back({{"name", bracket.name()},
                                  {"folder", bracket.folder.string()},
                                  {"image", file},
                                  {"exposures", exposures},
                                  {"saturated_fraction", merge.saturated_fraction()},
                                  {"underexposed_fraction", merge.underexposed_fraction()}});
    std::cerr << bracket.name() << ": " << bracket.exposures.size() << " exposures merged, "
              << percent(merge.saturated_fraction()) << " saturated in every exposure (alpha 0), "
              << percent(merge.underexposed_fraction()) << " underexposed in every exposure -> "
              << out.file(file).string() << "\n";
  }
  report["run"] = out.run();
  out.finish(report.dump(2) + "\n");
  std::cerr << "wrote " << brackets.size() << " HDR image(s) and hdr_merge.json to " << args.out << " ("
            << seconds_since(start) << " s)\n";
  return 0;
}

}  // namespace

CommandRun declare_hdr_merge(CLI::App& app) {
  auto args = std::make_shared<HdrMergeOptions>();
  app.description("merge exposure brackets into linear HDR images (EXR with alpha 0 where saturated)");
  add_text(app, "FOLDER", args->folders,
           "a bracket's folder (its photos but board.*; exposures.json or EXIF exposure times), or a shoot "
           "holding view_*/ and probe_*/ brackets")
      ->required()
      ->default_str("");
  add_text(app, "--out DIR", args->out, "the output folder: NAME.exr per bracket, response.json/png, hdr_merge.json")
      ->required();
  add_text(app, "--response FILE.json", args->response, "a response.json to use instead of recovering one");
  add_threads(app, args->threads)->description("worker threads (0: all cores; the results do not depend on it)");
  return [args] {
    tbb::task_arena arena(args->threads > 0 ? args->threads : tbb::task_arena::automatic);
    return arena.execute([&] { return hdr_merge(*args); });
  };
}

}  // namespace glaze
