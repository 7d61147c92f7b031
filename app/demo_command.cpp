// demo_command.cpp: `glaze demo`, the whole pipeline on the embedded default with no
// download: the paper's red sphere in the procedural office (scenes/red_sphere_office.gltf,
// embedded at build time) is path-traced into a capture set (three views, two held
// out), fitted with `invert-fit --mode material`, and the recovered material is printed
// against the true one. With --photos it starts from photographs instead: a simulated
// photo shoot of the same sphere (simulate-shoot: board photos, 8-bit brackets, a mirror
// ball) goes through `glaze captures` and then the fit. It runs the same commands a
// user would, in DIR.
#include "app/commands.h"
#include "app/embedded_scene.h"
#include "app/shared_options.h"
#include "renderer/error.h"
#include "renderer/json_input.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <vector>

namespace glaze {
namespace {

struct DemoCommandOptions {
  std::string out = "glaze-demo";
  int spp = 64;
  std::optional<Resolution> resolution;  // default 256x256, photos the simulator's 640x480
  bool photos = false;
};

// The fit's material against `truth` (R0, Rd), a row per parameter.
void print_material(const nlohmann::json& result, const nlohmann::json& truth) {
  std::printf("           recovered    true        error\n");
  std::printf("  R0       %.5f      %.5f     %+.5f\n", result["R0"].get<double>(), truth["R0"].get<double>(),
              result["R0"].get<double>() - truth["R0"].get<double>());
  const char* channel[] = {"Rd red  ", "Rd green", "Rd blue "};
  for (int c = 0; c < 3; ++c)
    std::printf("  %s %.5f      %.5f     %+.5f\n", channel[c], result["Rd"][c].get<double>(),
                truth["Rd"][c].get<double>(), result["Rd"][c].get<double>() - truth["Rd"][c].get<double>());
}

int demo_photos(const DemoCommandOptions& args, const std::filesystem::path& out, const std::string& scene) {
  const std::string shoot = (out / "shoot").string(), captures = (out / "captures").string(),
                    fit = (out / "fit").string();
  std::printf("glaze demo --photos: the red sphere in procedural:office (%s), photographed\n\n", scene.c_str());
  std::printf("1. simulate-shoot: a simulated photo shoot -> %s\n", shoot.c_str());
  std::fflush(stdout);
  // A board of 15 mm squares (1.5 sphere diameters along a row), framed to fill the
  // picture, leaves the sphere about 90 px in radius at 640x480: the probe needs the ball
  // that large (docs/notes/light-probe.md).
  std::vector<std::string> simulate = {scene, "--out", shoot, "--square", "0.015"};
  if (args.resolution) simulate.insert(simulate.end(), {"--res", to_string(*args.resolution)});
  command_simulate_shoot(simulate);
  std::printf("\n2. captures: HDR merge, registration, the sphere, the light probe -> %s\n", captures.c_str());
  std::fflush(stdout);
  command_captures({shoot, "--out", captures});
  std::printf("\n3. invert-fit --mode material under the probe -> %s\n", fit.c_str());
  std::fflush(stdout);
  command_invert_fit({captures + "/transforms.json", "--mode", "material", "--out", fit});

  const nlohmann::json truth = read_json_file(shoot + "/simulation.json", "the simulation's truth");
  const nlohmann::json report = read_json_file(captures + "/captures_report.json", "the captures' report");
  const nlohmann::json result = read_json_file(fit + "/fit.json", "the fit's result");
  std::printf("\n4. recovered against true\n");
  print_material(result, truth["object"]);
  const nlohmann::json& object = report["object"];
  double distance = 0.0;
  for (int i = 0; i < 3; ++i)
    distance += std::pow(object["center"][i].get<double>() - truth["object"]["center"][i].get<double>(), 2);
  std::printf("  sphere centre off by %.3f mm, radius by %+.3f%% (located from its outline in %zu views%s)\n",
              1e3 * std::sqrt(distance),
              100 * (object["radius"].get<double>() / truth["object"]["radius"].get<double>() - 1),
              object["views"].size(), object.value("under_probe", false) ? ", under the probe" : "");
  std::printf("  the probe covers %.1f%% of the directions; the summary of every stage is in %s/summary.txt\n",
              100 * report["probe"]["covered_fraction"].get<double>(), captures.c_str());
  return 0;
}

int demo(const DemoCommandOptions& args) {
  const std::filesystem::path out(args.out);
  create_output_folder(out, "demo");
  const std::string scene = (out / kEmbeddedSceneName).string();
  write_text_atomically(scene, kEmbeddedScene);
  if (args.photos) return demo_photos(args, out, scene);
  const std::string captures = (out / "captures").string(), fit = (out / "fit").string();
  std::printf("glaze demo: the red sphere in procedural:office (%s)\n\n1. path-traced captures -> %s\n", scene.c_str(),
              captures.c_str());
  command_render({scene, "--captures", captures, "--holdout", "novel_0,novel_1", "--spp", std::to_string(args.spp),
                  "--res", to_string(args.resolution.value_or(Resolution{256, 256}))});
  std::printf("\n2. invert-fit --mode material -> %s\n", fit.c_str());
  std::fflush(stdout);
  command_invert_fit({captures + "/transforms.json", "--mode", "material", "--out", fit});

  const nlohmann::json result = read_json_file(fit + "/fit.json", "the fit's result");
  std::printf("\n3. recovered against true\n");
  print_material(result, result["reference_material"]);
  std::printf(
      "\n  held-out views re-rendered with the recovered material, relative RMSE against their captures\n"
      "  (mostly the captures' own Monte-Carlo noise at this spp; 0 would need noise-free captures):");
  for (const auto& view : result["holdout"])
    std::printf(" %.4f", view["relative_rmse"].is_null() ? NAN : view["relative_rmse"].get<double>());
  std::printf("\n  images: the captures in %s, re-renders and residuals in %s\n", captures.c_str(), fit.c_str());
  return 0;
}

}  // namespace

CommandRun declare_demo(CLI::App& app) {
  auto args = std::make_shared<DemoCommandOptions>();
  app.description(
      "the embedded default, end to end: captures of the red sphere in the procedural office,\n"
      "fitted, recovered against true material");
  add_text(app, "--out DIR", args->out, "where the captures and the fit go");
  add_spp(app, args->spp, "samples per pixel of the captures");
  add_resolution(app, "--res WxH", args->resolution,
                 "size of the captures (default 256x256; with --photos: of the photos, default 640x480)");
  app.add_flag("--photos", args->photos,
               "start from photographs: a simulated photo shoot (simulate-shoot), turned into captures by `glaze "
               "captures`, then fitted");
  return [args] { return demo(*args); };
}

}  // namespace glaze
