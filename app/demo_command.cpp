// demo_command.cpp: `glaze demo`, the whole pipeline on the embedded default with no
// download: the paper's red sphere in the procedural office (scenes/red_sphere_office.gltf,
// embedded at build time) is path-traced into a capture set (three views, two held
// out), fitted with `invert-fit --mode material`, and the recovered material is printed
// against the true one. It runs the same commands a user would, in DIR.
#include "app/commands.h"
#include "app/embedded_scene.h"
#include "app/shared_options.h"
#include "renderer/error.h"
#include "renderer/json_input.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>

namespace glaze {
namespace {

struct DemoCommandOptions {
  std::string out = "glaze-demo";
  int spp = 64;
  Resolution resolution{256, 256};
};

int demo(const DemoCommandOptions& args) {
  const std::filesystem::path out(args.out);
  create_output_folder(out, "demo");
  const std::string scene = (out / kEmbeddedSceneName).string();
  write_text_atomically(scene, kEmbeddedScene);
  const std::string captures = (out / "captures").string(), fit = (out / "fit").string();
  std::printf("glaze demo: the red sphere in procedural:office (%s)\n\n1. path-traced captures -> %s\n", scene.c_str(),
              captures.c_str());
  command_render({scene, "--captures", captures, "--holdout", "novel_0,novel_1", "--spp", std::to_string(args.spp),
                  "--res", to_string(args.resolution)});
  std::printf("\n2. invert-fit --mode material -> %s\n", fit.c_str());
  std::fflush(stdout);
  command_invert_fit({captures + "/transforms.json", "--mode", "material", "--out", fit});

  const nlohmann::json result = read_json_file(fit + "/fit.json", "the fit's result");
  const nlohmann::json& truth = result["reference_material"];
  std::printf("\n3. recovered against true\n           recovered    true        error\n");
  std::printf("  R0       %.5f      %.5f     %+.5f\n", result["R0"].get<double>(), truth["R0"].get<double>(),
              result["R0"].get<double>() - truth["R0"].get<double>());
  const char* channel[] = {"Rd red  ", "Rd green", "Rd blue "};
  for (int c = 0; c < 3; ++c)
    std::printf("  %s %.5f      %.5f     %+.5f\n", channel[c], result["Rd"][c].get<double>(),
                truth["Rd"][c].get<double>(), result["Rd"][c].get<double>() - truth["Rd"][c].get<double>());
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
  add_resolution(app, "--res WxH", args->resolution, "size of the captures");
  return [args] { return demo(*args); };
}

}  // namespace glaze
