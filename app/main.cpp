// main.cpp: the `glaze` command. Thin by design: it parses arguments, calls the
// renderer and inverse libraries, prints results, and turns glaze::Error into a clear
// message and a non-zero exit status.
#include "app/arguments.h"
#include "app/commands.h"
#include "renderer/environment.h"
#include "renderer/error.h"
#include "renderer/material.h"
#include "renderer/procedural_environment.h"
#include "renderer/quadrature.h"
#include "renderer/shading.h"
#include "renderer/sh.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

namespace glaze {
namespace {

constexpr const char* kUsage = R"(glaze: render polished materials under environment lighting, and invert.

usage:
  glaze demo                     the default scene: SH lighting and furnace check
  glaze sh ENV [options]         print the SH coefficients of ENV as JSON
  glaze env procedural NAME --out FILE.exr [--res WxH]
                                 write a procedural environment map
  glaze render SCENE [options] --out FILE.exr|DIR
  glaze render SCENE --captures DIR [--holdout NAME,...] [options]
                                 path-trace a glTF scene's cameras / a capture set
  glaze convergence SCENE [--camera NAME] [--ref FILE.exr | --ref-spp N] --out DIR
                                 error against run time: path tracer and sh integrator
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

options of `convergence` (also --res, --seed, --threads, --max-depth, --env...):
  --ref-spp N         path-trace the reference at N spp, in two halves whose
                      difference measures its noise (default 16384)
  --ref FILE.exr      use this reference instead (its noise is then unknown)
  --max-spp N         path tracer at 1, 2, 4, ... N spp (default ref-spp / 16)
  Writes DIR/convergence.csv (seconds, relative RMSE, max error, RMSE beyond the
  reference noise), split.csv (sh error from SH truncation and from anti-aliasing,
  kernel energy kept per lmax), summary.json (time to 1% and 0.3%) and
  convergence.png (log-log plot). sh runs lmax 2, 4, 6, 8, 12 x ss 1, 2, 4.
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

// The embedded default scene: the paper's red sphere in the procedural office.
int command_demo() {
  const PolishedMaterial red(0.0452f, RGB(0.9765f, 0.0186f, 0.0f));
  std::printf("glaze demo: red sphere (R0 = %.4f, Rd = %.4f %.4f %.4f) in procedural:office\n\n", red.R0(),
              red.Rd()[0], red.Rd()[1], red.Rd()[2]);

  const auto start = std::chrono::steady_clock::now();
  const Environment office = make_environment("procedural:office");
  const auto generated = std::chrono::steady_clock::now();
  const ShCoefficients& lighting = office.sh(4);
  const auto projected = std::chrono::steady_clock::now();
  auto milliseconds = [](auto a, auto b) { return std::chrono::duration<double, std::milli>(b - a).count(); };
  std::printf("office environment 1024x512 generated in %.0f ms; SH projection (lmax 4) in %.1f ms\n",
              milliseconds(start, generated), milliseconds(generated, projected));
  std::printf("  l  m        L_lm (R, G, B)\n");
  for (int l = 0; l <= 4; ++l)
    for (int m = -l; m <= l; ++m)
      std::printf("  %d %2d  %9.4f %9.4f %9.4f\n", l, m, lighting(l, m)[0], lighting(l, m)[1], lighting(l, m)[2]);

  // White furnace: under a constant environment of radiance 1 a material with Rd = 1
  // reflects exactly 1 in every direction. Checked two independent ways: a quadrature
  // of the BRDF over the hemisphere, and the SH shading model.
  const PolishedMaterial white(red.R0(), RGB::Ones());
  const Environment constant = make_environment("procedural:constant", {}, 64, 32);
  const ShDiffuseSum diffuse_sum(constant.sh(4));
  const QuadratureRule mu_rule = gauss_legendre(16, 0.0, 1.0);
  std::printf("\nwhite furnace (Rd = 1, R0 = %.4f, constant environment of radiance 1):\n", white.R0());
  std::printf("  mu_o     quadrature   SH model     expected\n");
  for (float mu_o : {1.0f, 0.7f, 0.3f, 0.05f}) {
    const Vec3 wo(std::sqrt(1.0f - mu_o * mu_o), 0.0f, mu_o);
    double integral = 0.0;  // f_d is independent of phi_i: integrate mu_i, times 2 pi
    for (size_t k = 0; k < mu_rule.nodes.size(); ++k) {
      const float mu_i = static_cast<float>(mu_rule.nodes[k]);
      const Vec3 wi(std::sqrt(1.0f - mu_i * mu_i), 0.0f, mu_i);
      integral += mu_rule.weights[k] * white.eval_diffuse(wo, wi)[0] * mu_i * 2.0 * kPiD;
    }
    const double quadrature = white.fresnel(mu_o) + integral;
    const Vec3 n = Vec3::UnitZ();
    const RGB sh_model = polished_radiance(white, mu_o, constant.eval(reflect(wo, n)), diffuse_sum(n));
    std::printf("  %.2f     %.6f     %.6f     1\n", mu_o, quadrature, sh_model[0]);
  }
  std::printf("\nred sphere directional albedo at mu_o = 1: %.4f %.4f %.4f\n", red.albedo(1.0f)[0],
              red.albedo(1.0f)[1], red.albedo(1.0f)[2]);
  return 0;
}

int run(const std::vector<std::string>& args) {
  if (args.empty() || args[0] == "help" || args[0] == "--help" || args[0] == "-h") {
    std::cout << kUsage;
    return args.empty() ? 2 : 0;
  }
  const std::string command = args[0];
  const std::vector<std::string> rest(args.begin() + 1, args.end());
  if (command == "demo") return command_demo();
  if (command == "sh") return command_sh(rest);
  if (command == "env") return command_env(rest);
  if (command == "render") return command_render(rest);
  if (command == "convergence") return command_convergence(rest);
  if (command == "invert-fit") return command_invert_fit(rest);
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
