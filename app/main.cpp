// main.cpp: the `glaze` command. Thin by design: it parses arguments, calls the
// renderer and inverse libraries, prints results, and turns glaze::Error into a clear
// message and a non-zero exit status.
#include "app/arguments.h"
#include "app/commands.h"
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/procedural_environment.h"
#include "renderer/sh.h"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace glaze {
namespace {

constexpr const char* kUsage = R"(glaze: render polished materials under environment lighting, and invert.

usage:
  glaze demo [--out DIR]         the embedded default, end to end: captures of the red
                                 sphere in the procedural office, fitted, recovered
                                 against true material (writes DIR, default glaze-demo)
  glaze sh ENV [options]         print the SH coefficients of ENV as JSON
  glaze env procedural NAME --out FILE.exr [--res WxH]
                                 write a procedural environment map
  glaze render SCENE [options] --out FILE.exr|DIR
  glaze render SCENE --captures DIR [--holdout NAME,...] [options]
                                 path-trace a glTF scene's cameras / a capture set
  glaze convergence SCENE [--camera NAME] [--ref FILE.exr | --ref-spp N] --out DIR
                                 error against run time: path tracer and sh integrator
  glaze invert-fit CAPTURES/transforms.json --mode material|texture|lighting|joint --out DIR [options]
                                 recover the material (or R0 and a diffuse texture)
                                 under known lighting, the lighting from an object of
                                 known material, or both together (joint)
  glaze preview SCENE [--camera NAME] [--integrator path|sh]
                                 a window that shows the render as it refines;
                                 orbit, pan, zoom, exposure, tone mapping (H: keys)
  glaze reproduce --out DIR [--quick]
                                 the paper's experiments end to end (Table 2,
                                 Figures 5-9, Table 3) with a report: DIR/report.md
  glaze help                     this text

ENV is a lat-long image (EXR, HDR, PFM, ...) or procedural:NAME with NAME one of
constant, office, blue-room.

options of `sh`:
  --lmax N            band limit (default 4, at most 64)
  --scale S           multiply the radiance (default 1)
  --rotation DEG      rotate the map about +Y (default 0)
  --to-world a,b,...  3x3 rotation, row-major, applied before --rotation
  --res WxH           resolution of a procedural map (default 1024x512)

options of `render`:
  --camera NAME|all   which camera (default: the first); all writes DIR/NAME.exr
  --res WxH           film size (default: the scene's film, else 512 high)
  --spp N             samples per pixel (default 64)
  --time-budget SEC   render passes of --spp samples (default 4) until SEC is spent
  --seed S            random seed (default 0); the image depends only on it
  --threads N         worker threads (default: all cores)
  --max-depth N       surface interactions per path (default 8; 1 for a single sphere)
  --estimator E       direct light: mis (default), bsdf or environment
  --env ENV           replace the scene's environment
  --env-scale S, --env-rotation DEG   adjust it
  --integrator path   the Monte-Carlo path tracer (default)
  --integrator sh     the analytic SH shading model (DESIGN section 2), no noise:
    --lmax N          SH band limit of the diffuse term (default 4)
    --ss K            K x K sub-pixel samples (default 2)
    --ss-refine M     M x M where a pixel's K x K samples differ by over 1%
                      (edges, silhouettes; default 0: off; not with --captures)

  --out FILE.png      a picture instead of radiance: --exposure EV (default 0)
                      and --tone-map clamp|filmic|aces (default filmic), as the
                      preview window shows it

options of `preview` (also --res, --seed, --threads, --max-depth, --env..., --lmax, --ss):
  --integrator I      shown first: sh (default for a single convex object) or path;
                      the other follows in the background (key I switches)
  --exposure EV, --tone-map clamp|filmic|aces   how it is shown (default 0, filmic)
  --max-spp N         path passes stop here (default 4096)
  --save-dir DIR      where key S saves NAME_CAMERA_N.exr and .png (default .)
  --frames N          show N published steps (one path pass or the sh image each,
                      in lockstep, so always the same picture) and exit;
    --screenshot F.png  write what the window shows at the last one
    --spin DEG        turn the camera DEG degrees about the object after every frame
  Without a display (DISPLAY unset) it fails at once; headless: xvfb-run.

options of `invert-fit`:
  --env ENV, --env-scale S, --env-rotation DEG   the lighting (default: the set's)
  --lmax N            SH band limit of the diffuse term (default 16: exact to <0.1%)
  --pixel-footprint K model each pixel as the mean of K x K rays over it (default 4,
                      as a camera records it; 1 for point-sampled captures)
  --points N          N points spread over the object instead of every pixel
  --min-cos X         drop samples seen at n.v < X (default 0.2)
  --loss L            none (default), huber or cauchy, with --loss-scale S
                      (radiance; default 0.05)
  --texture-res WxH   texels of --mode texture (default 256x128)
  --holdout-dir DIR   held-out captures to re-render (default: CAPTURES/holdout,
                      where render --captures --holdout NAME,... puts them)
  --mode lighting:    --R0 x --Rd r,g,b (default: the set's material), --lmax N
                      (default 4), --env-res WxH (recovered map, default 256x128),
                      --solve-res WxH (map solved with L_lm, default 64x32),
                      --ridge R (relative Tikhonov weight, default 1e-6),
                      --diffuse-lmax N (default 16; 0: off): for captures whose diffuse
                      term has every band (photographs, the path tracer), a second pass
                      with the bands lmax+1..N predicted from the first pass's lighting
                      (joint: more, each from the last, while R0 or Rd moves by 1e-3;
                      at most --max-passes) (N <= lmax: off; sh captures: at most their
                      own lmax)
  --mode joint:       as lighting, without the material (full-band captures: Rd from
                      the solve map turned by 0, 1/4, 1/2, 3/4 of a texel in azimuth),
                      --max-iterations N (rounds of each pass, default 20),
                      --max-passes N (default 12; 1: one pass): passes that end with R0
                      or Rd still moving are reported (fit.json passes_settled) and warned
  --threads N         worker threads (default: all cores; the results do not depend on it)
  --preview           a window: each view observed, predicted and |residual| x8,
                      updated as the solver iterates (--frames N --screenshot F.png,
                      --exposure, --tone-map as for preview)
  Writes DIR/fit.json, solver.txt (Ceres's report; for lighting, the linear
  solve's), render_view_NNN.exr and residual_view_NNN.exr (observed - predicted), texture.exr (RGBA, alpha 0 = unknown) for --mode texture,
  lighting.exr and lighting_coverage.png for --mode lighting.

options of `reproduce`:
  --quick             the reduced run (160x160 captures, 64x32 textures, 128x64
                      maps, a small convergence study): minutes, not the full hour
  --env-res WxH       maps recovered by the lighting and joint fits (default 256x128)
  --res WxH, --spp N  captures (default 512x512, 256 spp)
  --seed S            of the captures' path tracer (default 0)
  --texture-res WxH   textures of the textured sphere (default 256x128)
  --lighting L,...    office, blue-room, map files or names under
                      $GLAZE_DATA_DIR/envmaps (default: office, blue-room and
                      --real-maps, default st_fagans_interior_1k.hdr,lebombo_1k.hdr,
                      where present: absent ones are skipped, saying so)
  --scenes DIR        glaze's scenes folder (default ./scenes, else the source tree's)
  --no-convergence    leave out the error-against-run-time study
  --threads N         worker threads (default: all cores)
  Writes DIR/report.md (tables and figures side by side), DIR/results.json (every
  number), DIR/figures/*.png, and the captures and fits behind them.

options of `convergence` (also --res, --seed, --threads, --max-depth, --env...):
  --ref-spp N         path-trace the reference at N spp, in two halves whose
                      difference measures its noise (default 16384)
  --ref FILE.exr      use this reference instead, with --ref-noise X its relative
                      noise as summary.json of the run that made it says (default 0)
  --max-spp N         path tracer at 1, 2, 4, ... N spp (default ref-spp / 16)
  Writes DIR/convergence.csv (seconds, relative RMSE, max error, RMSE beyond the
  reference noise), split.csv (sh error from SH truncation and from anti-aliasing,
  kernel energy kept per lmax), summary.json (time to 1% and 0.3%) and
  convergence.png (log-log plot). sh runs lmax 2, 4, 6, 8, 12 x ss 1, 2, 4, and ss 1
  and 2 refined to 8 (--ss-refine 8).
)";

EnvironmentOptions environment_options(const Arguments& args) {
  EnvironmentOptions options;
  options.scale = args.real("scale", 1.0f);
  options.rotation_degrees = args.real("rotation", 0.0f);
  if (args.has("to-world")) {
    const std::vector<float> values = args.reals("to-world");
    if (values.size() != 9) throw Error("option --to-world needs 9 comma-separated numbers (row-major 3x3)");
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) options.to_world(r, c) = values[r * 3 + c];
  }
  return options;
}

nlohmann::json sh_json(const ShCoefficients& coefficients) {
  nlohmann::json values = nlohmann::json::array();
  for (const RGBd& c : coefficients.values) values.push_back({c[0], c[1], c[2]});
  return {{"lmax", coefficients.lmax}, {"L_lm", values}};
}

int command_sh(const std::vector<std::string>& raw) {
  const Arguments args(raw, {"lmax", "scale", "rotation", "to-world", "res"});
  if (args.positionals().size() != 1) throw Error("usage: glaze sh ENV [--lmax N] (see `glaze help`)");
  const std::string& spec = args.positionals()[0];
  if (args.has("res") && !spec.starts_with("procedural:"))
    throw Error("option --res sets the resolution of a procedural map; " + spec + " is a file");
  const auto [width, height] = args.resolution("res", {1024, 512});
  const int lmax = static_cast<int>(args.integer("lmax", 4, 0, kShMaxLmax));
  const Environment environment = make_environment(spec, environment_options(args), width, height);
  std::cout << sh_json(environment.sh(lmax)).dump() << '\n';
  return 0;
}

int command_env(const std::vector<std::string>& raw) {
  const Arguments args(raw, {"out", "res"});
  if (args.positionals().size() != 2 || args.positionals()[0] != "procedural" || !args.has("out"))
    throw Error("usage: glaze env procedural NAME --out FILE.exr [--res WxH]");
  const auto [width, height] = args.resolution("res", {1024, 512});
  const std::string& name = args.positionals()[1];
  write_image(args.text("out", ""), make_procedural_environment(name, width, height),
              {{"glaze:environment", "procedural:" + name}});
  std::cerr << "wrote " << args.text("out", "") << " (" << width << "x" << height << ")\n";
  return 0;
}

int run(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "help" || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  for (const std::string& arg : rest)
    if (arg == "--help" || arg == "-h") {  // `glaze render --help`: the one help text
      std::cout << kUsage;
      return 0;
    }
  if (command == "demo") return command_demo(rest);
  if (command == "sh") return command_sh(rest);
  if (command == "env") return command_env(rest);
  if (command == "render") return command_render(rest);
  if (command == "convergence") return command_convergence(rest);
  if (command == "invert-fit") return command_invert_fit(rest);
  if (command == "reproduce") return command_reproduce(rest);
  if (command == "preview") {
#if GLAZE_HAVE_PREVIEW
    return command_preview(rest);
#else
    throw Error(kNoPreview);
#endif
  }
  throw Error("unknown command '" + command + "' (see `glaze help`)");
}

}  // namespace
}  // namespace glaze

int main(int argc, char** argv) {
  try {
    return glaze::run(std::vector<std::string>(argv + 1, argv + argc));
  } catch (const glaze::Error& error) {
    std::cerr << "glaze: error: " << error.what() << '\n';
    return 1;
  } catch (const std::exception& error) {
    std::cerr << "glaze: internal error: " << error.what() << '\n';
    return 3;
  }
}
