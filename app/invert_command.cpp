// invert_command.cpp: `glaze invert-fit`: the command line. Every option is checked
// before any work (the options a mode does not take, in one place: the app's callback);
// then the mode runs (invert_material.cpp, invert_lighting.cpp), with --preview on a
// thread beside the window.
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
#include <memory>

namespace glaze {
namespace {

using invert_fit::InvertFitOptions;

int run_invert_fit(const InvertFitOptions& args) {
  const std::string& mode = args.mode;
  const bool lighting = mode == "lighting" || mode == "joint";
  const int threads = args.threads;
  const std::filesystem::path out(args.out);
  // The fit's parallel loops run in an arena of --threads workers; their sums are formed
  // in fixed chunks, so the results do not depend on it (InvertFit.ResultsDoNotDependOnThreads).
  auto invert = [&](FitPreview* preview) {
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    return arena.execute([&] {
      return lighting ? invert_fit::invert_lighting(args, out, mode == "joint", preview)
                      : invert_fit::invert_material(args, out, mode, preview);
    });
  };
  if (!args.preview) return invert(nullptr);
#if GLAZE_HAVE_PREVIEW
  require_display("invert-fit without --preview");
  FitPreview preview(args.display);
  int status = 1;
  preview.run([&] { status = invert(&preview); }, args.window.frames, args.window.screenshot);
  return status;
#else
  throw Error(kNoPreview);
#endif
}

}  // namespace

CommandRun declare_invert_fit(CLI::App& app) {
  auto args = std::make_shared<InvertFitOptions>();
  app.description(
      "recover the material (or R0 and a diffuse texture) under known lighting, the lighting from\n"
      "an object of known material, or both together (joint)");
  add_text(app, "CAPTURES", args->captures, "a capture set: DIR/transforms.json (glaze render --captures DIR)")
      ->required();
  add_choice(app, "--mode MODE", args->mode, {"material", "texture", "lighting", "joint"}, "what is recovered")
      ->required();
  add_text(app, "--out DIR", args->out, "where the fit goes")->required();
  add_lmax(app, args->lmax,
           "SH band limit of the diffuse term (default: the sh captures' own, else 16 for material and\n"
           "texture: exact to <0.1%; lighting and joint: of L_lm, at most 8, default 4)");
  add_integer(app, "--pixel-footprint K", args->pixel_footprint, 1, 16,
              "model each pixel as the mean of K x K rays over it (default: the sh captures' ss, else 4,\n"
              "as a camera records it; 1 for point-sampled captures)");
  add_integer(app, "--points N", args->samples.points, 0, 1 << 26,
              "N points spread over the object instead of every pixel");
  add_seed(app, args->samples.seed, "random seed of --points on a mesh");
  add_real(app, "--min-cos X", args->samples.min_cos, "drop samples seen at n.v < X");
  add_integer(app, "--max-iterations N", args->max_iterations, 1, 10000,
              "solver iterations (default 100; joint: rounds of each pass, default 20)");
  add_environment_override(app, args->environment);
  app.get_option("--env")->description(std::string("the known lighting instead of the capture set's: ") +
                                       kEnvironmentSyntax);
  add_text(app, "--holdout-dir DIR", args->holdout_dir,
           "held-out captures to re-render (default: CAPTURES/holdout, where render --captures\n"
           "--holdout NAME,... puts them)");
  // Not in the help: render's --holdout, refused below with where a fit's held-out captures are.
  CLI::Option* holdout = app.add_option_function<std::string>("--holdout", [](const std::string&) {})->group("");
  add_threads(app, args->threads)->description("worker threads (0: all cores; the results do not depend on it)");

  CLI::Option* loss = add_choice(app, "--loss NAME", args->loss, {"none", "huber", "cauchy"}, "robust loss");
  CLI::Option* loss_scale = add_real(app, "--loss-scale S", args->loss_scale, "of the robust loss (radiance)");
  loss_scale->needs(loss);
  CLI::Option* texture_resolution =
      add_resolution(app, "--texture-res WxH", args->texture_resolution, "texels of --mode texture");
  for (CLI::Option* option : {loss, loss_scale, texture_resolution}) option->group("--mode material and texture");

  CLI::Option* R0 = add_real(app, "--R0 X", args->R0, "the known material of --mode lighting (default: the set's)");
  CLI::Option* Rd = add_reals(app, "--Rd r,g,b", args->Rd, 3, "with --R0");
  CLI::Option* lighting_resolution =
      add_resolution(app, "--env-res WxH", args->lighting_resolution, "the recovered map");
  CLI::Option* solve_resolution =
      add_resolution(app, "--solve-res WxH", args->solve_resolution, "the map solved with L_lm (default 64x32)");
  CLI::Option* ridge = add_real(app, "--ridge R", args->ridge, "relative Tikhonov weight (default 1e-6)");
  CLI::Option* diffuse_lmax =
      add_integer(app, "--diffuse-lmax N", args->diffuse_lmax, 0, kShMaxLmax,
                  "0: off. For captures whose diffuse term has every band (photographs, the path tracer), a\n"
                  "second pass with the bands lmax+1..N predicted from the first pass's lighting (joint: more,\n"
                  "each from the last, while R0 or Rd moves by 1e-3; at most --max-passes) (N <= lmax: off;\n"
                  "sh captures: at most their own lmax)");
  CLI::Option* max_passes = add_integer(app, "--max-passes N", args->max_passes, 1, 100,
                                        "of --mode joint (default 12; 1: one pass): passes that end with R0 or Rd\n"
                                        "still moving are reported (fit.json passes_settled) and warned");
  for (CLI::Option* option : {R0, Rd, lighting_resolution, solve_resolution, ridge, diffuse_lmax, max_passes})
    option->group("--mode lighting and joint");

  CLI::Option* preview = app.add_flag("--preview", args->preview,
                                      "a window: each view observed, predicted and |residual| x8, updated as the\n"
                                      "solver iterates");
  preview->group("--preview");
  add_window_options(app, args->window);
  add_display_options(app, args->display);
  for (const char* name : {"--frames", "--screenshot", "--exposure", "--tone-map"})
    app.get_option(name)->needs(preview)->group("--preview");
  app.footer(
      "Writes DIR/fit.json, solver.txt (Ceres's report; for lighting, the linear solve's),\n"
      "render_view_NNN.exr and residual_view_NNN.exr (observed - predicted), texture.exr (RGBA,\n"
      "alpha 0 = unknown) for --mode texture, lighting.exr and lighting_coverage.png for --mode lighting.");

  // The options that a mode does not take, and the values that depend on the mode.
  app.callback([args, holdout, texture_resolution, lighting_resolution, solve_resolution, ridge, diffuse_lmax, R0, Rd,
                loss, loss_scale] {
    const std::string& mode = args->mode;
    const bool lighting = mode == "lighting" || mode == "joint";
    if (mode != "texture" && texture_resolution->count()) throw Error("--texture-res applies to --mode texture");
    if (!lighting && (lighting_resolution->count() || ridge->count() || solve_resolution->count()))
      throw Error("--env-res, --solve-res and --ridge apply to --mode lighting and joint");
    if (!lighting && diffuse_lmax->count()) throw Error("--diffuse-lmax applies to --mode lighting and joint");
    if (mode != "lighting" && (R0->count() || Rd->count()))
      throw Error("--R0 and --Rd give the known material of --mode lighting");
    if (lighting && (loss->count() || loss_scale->count()))
      throw Error(
          "--loss and --loss-scale apply to --mode material and texture (the lighting solve is linear least "
          "squares)");
    if (R0->count() != Rd->count())
      throw Error("--R0 and --Rd go together: give the whole known material (or neither, to use the capture set's)");
    if (holdout->count())
      throw Error(
          "--holdout names cameras of `glaze render --captures`; the held-out captures of invert-fit are "
          "--holdout-dir DIR (default: CAPTURES/holdout)");
    if (lighting && args->lmax && *args->lmax > 8)
      throw Error("--lmax: '" + std::to_string(*args->lmax) + "' is not an integer in [0, 8] (--mode " + mode + ")");
    RobustLoss::parse(args->loss, args->loss_scale);
  });
  return [args] { return run_invert_fit(*args); };
}

}  // namespace glaze
