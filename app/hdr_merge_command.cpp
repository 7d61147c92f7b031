// hdr_merge_command.cpp: `glaze hdr-merge`, exposure brackets merged into linear HDR
// images (docs/design.md §7; inverse/photos/). The camera response of 8-bit photos is
// recovered once from every bracket given, or read from --response; 16-bit and raw
// photos are linear. Writes NAME.exr per bracket (R, G, B and A: 0 where saturated in
// every exposure), response.json and response.png, and last hdr_merge.json.
#include "app/commands.h"
#include "app/photo_outputs.h"
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

  const CameraResponse response = bracket_response(brackets, args.response);
  nlohmann::json report = {{"response", response_json(response)}, {"brackets", nlohmann::json::array()}};
  write_response(out, response, report);
  for (const Bracket& bracket : brackets)
    report["brackets"].push_back(write_merged(out, bracket, read_and_merge(bracket, response), response));
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
