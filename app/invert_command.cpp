// invert_command.cpp: `glaze invert-fit`: the command line. Every option is checked
// before any work; then the mode runs (invert_material.cpp, invert_lighting.cpp), with
// --preview on a thread beside the window.
#include "app/arguments.h"
#include "app/commands.h"
#include "app/invert_fit.h"
#if GLAZE_HAVE_PREVIEW
#include "app/fit_preview.h"
#include "app/preview_window.h"
#endif
#include "inverse/material_fit.h"
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/sh.h"

#include <tbb/task_arena.h>

#include <filesystem>

namespace glaze {

int command_invert_fit(const std::vector<std::string>& raw) {
  const Arguments args(raw, {"mode", "out", "points", "min-cos", "loss", "loss-scale", "lmax", "texture-res", "env",
                             "env-scale", "env-rotation", "holdout", "holdout-dir", "seed", "max-iterations", "pixel-footprint", "R0",
                             "Rd", "env-res", "ridge", "solve-res", "diffuse-lmax", "max-passes", "frames", "screenshot",
                             "exposure", "tone-map", "threads"},
                       {"preview"});
  if (args.positionals().size() != 1 || !args.has("out") || !args.has("mode"))
    throw Error("usage: glaze invert-fit DIR/transforms.json --mode material|texture|lighting|joint --out DIR (see `glaze help`)");
  const std::string mode = args.text("mode", "");
  if (mode != "material" && mode != "texture" && mode != "lighting" && mode != "joint")
    throw Error("unknown mode '" + mode + "' (known: material, texture, lighting, joint)");
  if (mode != "texture" && args.has("texture-res")) throw Error("--texture-res applies to --mode texture");
  const bool lighting = mode == "lighting" || mode == "joint";
  if (!lighting && (args.has("env-res") || args.has("ridge") || args.has("solve-res")))
    throw Error("--env-res, --solve-res and --ridge apply to --mode lighting and joint");
  if (!lighting && args.has("diffuse-lmax")) throw Error("--diffuse-lmax applies to --mode lighting and joint");
  if (mode != "lighting" && (args.has("R0") || args.has("Rd"))) throw Error("--R0 and --Rd give the known material of --mode lighting");
  if (lighting && (args.has("loss") || args.has("loss-scale")))
    throw Error("--loss and --loss-scale apply to --mode material and texture (the lighting solve is linear least squares)");
  // Every option's value is checked here, before the (long) sampling: a typo fails at once.
  if (args.has("R0") != args.has("Rd"))
    throw Error("--R0 and --Rd go together: give the whole known material (or neither, to use the capture set's)");
  if (args.has("holdout"))
    throw Error("--holdout names cameras of `glaze render --captures`; the held-out captures of invert-fit are "
                "--holdout-dir DIR (default: CAPTURES/holdout)");
  if (args.has("screenshot") && std::filesystem::path(args.text("screenshot", "")).extension() != ".png")
    throw Error("--screenshot " + args.text("screenshot", "") + ": the screenshot is a PNG (name it FILE.png)");
  if (args.has("loss-scale") && !args.has("loss")) throw Error("--loss-scale goes with --loss huber|cauchy");
  RobustLoss::parse(args.text("loss", "none"), args.real("loss-scale", 0.05f));
  args.integer("lmax", 0, 0, lighting ? 8 : kShMaxLmax);
  args.integer("pixel-footprint", 1, 1, 16);
  args.integer("max-iterations", 100, 1, 10000);
  args.integer("points", 0, 0, 1 << 26);
  args.real("min-cos", 0.2f);
  args.resolution("texture-res", {256, 128});
  args.resolution("env-res", {256, 128});
  args.resolution("solve-res", {64, 32});
  args.real("ridge", 0.0f);
  args.integer("diffuse-lmax", 16, 0, kShMaxLmax);
  if (args.has("preview")) {
    args.integer("frames", 1, 1, 1 << 20);
    parse_tone_mapping(args.text("tone-map", "filmic"));
    args.real("exposure", 0.0f);
  }
  const int threads = static_cast<int>(args.integer("threads", 0, 0, 1024));
  const std::filesystem::path out(args.text("out", ""));
  // The fit's parallel loops run in an arena of --threads workers; their sums are formed
  // in fixed chunks, so the results do not depend on it (InvertFit.ResultsDoNotDependOnThreads).
  auto invert = [&](FitPreview* preview) {
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    return arena.execute([&] {
      return lighting ? invert_fit::invert_lighting(args, out, mode == "joint", preview)
                      : invert_fit::invert_material(args, out, mode, preview);
    });
  };
  if (!args.has("preview")) {
    if (args.has("frames") || args.has("screenshot") || args.has("exposure") || args.has("tone-map"))
      throw Error("--frames, --screenshot, --exposure and --tone-map apply to --preview");
    return invert(nullptr);
  }
#if GLAZE_HAVE_PREVIEW
  require_display("invert-fit without --preview");
  if (args.has("screenshot") && !args.has("frames")) throw Error("--screenshot needs --frames N (the frame to capture)");
  DisplaySettings display;
  display.exposure_ev = args.real("exposure", 0.0f);
  display.tone_mapping = parse_tone_mapping(args.text("tone-map", "filmic"));
  FitPreview preview(display);
  int status = 1;
  preview.run([&] { status = invert(&preview); }, static_cast<int>(args.integer("frames", 0, 1, 1 << 20)),
              args.text("screenshot", ""));
  return status;
#else
  throw Error(kNoPreview);
#endif
}


}  // namespace glaze
