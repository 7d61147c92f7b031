// environment_commands.cpp: `glaze sh` (the SH coefficients of an environment map, as
// JSON), `glaze env` (a procedural map written to a file) and `glaze env-convert` (an
// environment rewritten as a lat-long map, an angular map or a mirror-ball image).
#include "app/commands.h"
#include "app/shared_options.h"
#include "renderer/environment.h"
#include "renderer/environment_format.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/procedural_environment.h"
#include "renderer/sh.h"

#include <nlohmann/json.hpp>

#include <iostream>
#include <memory>

namespace glaze {
namespace {

struct ShCommandOptions {
  std::string environment;
  int lmax = 4;
  EnvironmentOptions options;  // --scale, --rotation, and --to-world's matrix
  std::vector<float> to_world;
  std::string format = "auto";
  Resolution resolution = kProceduralMapResolution;
};

struct EnvConvertOptions {
  std::string environment, format = "auto", to, out;
  std::optional<int> size;
  Resolution resolution = kProceduralMapResolution;
};

struct EnvCommandOptions {
  std::string kind, name, out;
  Resolution resolution = kProceduralMapResolution;
};

nlohmann::json sh_json(const ShCoefficients& coefficients) {
  nlohmann::json values = nlohmann::json::array();
  for (const RGBd& c : coefficients.values) values.push_back({c[0], c[1], c[2]});
  return {{"lmax", coefficients.lmax}, {"L_lm", values}};
}

int sh(ShCommandOptions args) {
  if (!args.to_world.empty())
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) args.options.to_world(r, c) = args.to_world[r * 3 + c];
  args.options.format = parse_environment_format(args.format, "--env-format");
  const Environment environment =
      make_environment(args.environment, args.options, args.resolution.width, args.resolution.height);
  std::cout << sh_json(environment.sh(args.lmax)).dump() << '\n';
  return 0;
}

int env(const EnvCommandOptions& args) {
  const auto [width, height] = args.resolution;
  write_image(args.out, make_procedural_environment(args.name, width, height),
              {{"glaze:environment", "procedural:" + args.name}});
  std::cerr << "wrote " << args.out << " (" << width << "x" << height << ")\n";
  return 0;
}

int env_convert(const EnvConvertOptions& args) {
  // Through Environment, which reads any format and repairs non-finite texels; unoriented.
  EnvironmentOptions options;
  options.format = parse_environment_format(args.format, "--env-format");
  const Environment environment =
      make_environment(args.environment, options, args.resolution.width, args.resolution.height);
  const EnvironmentFormat to = parse_environment_format(args.to, "--to");
  const Image& map = environment.map();
  Image image = map;
  if (to != EnvironmentFormat::latlong) image = latlong_to_probe(map, to, args.size.value_or(map.width));
  write_image(args.out, image, {{"glaze:environment", args.environment}, {"glaze:environment_format", args.to}});
  std::cerr << "wrote " << args.out << " (" << args.to << ", " << image.width << "x" << image.height << ")\n";
  return 0;
}

}  // namespace

CommandRun declare_sh(CLI::App& app) {
  auto args = std::make_shared<ShCommandOptions>();
  app.description("print the SH coefficients of an environment map as JSON");
  add_text(app, "ENV", args->environment, kEnvironmentSyntax)->required();
  add_environment_format(app, args->format);
  add_lmax(app, args->lmax, "band limit");
  add_real(app, "--scale S", args->options.scale, "multiply the radiance");
  add_real(app, "--rotation DEG", args->options.rotation_degrees, "rotate the map about +Y");
  add_reals(app, "--to-world a,b,...", args->to_world, 9, "3x3 rotation, row-major, applied before --rotation");
  CLI::Option* resolution = add_map_resolution(app, args->resolution);
  app.callback([args, resolution] {
    if (resolution->count() > 0 && !args->environment.starts_with("procedural:"))
      throw Error("option --res sets the resolution of a procedural map; " + args->environment + " is a file");
  });
  return [args] { return sh(*args); };
}

CommandRun declare_env(CLI::App& app) {
  auto args = std::make_shared<EnvCommandOptions>();
  app.description("write a procedural environment map");
  add_choice(app, "KIND", args->kind, {"procedural"}, "what kind of map")->required();
  add_text(app, "NAME", args->name, "the procedural map: constant, office or blue-room")->required();
  add_text(app, "--out FILE.exr", args->out, "the map's file")->required();
  add_map_resolution(app, args->resolution);
  return [args] { return env(*args); };
}

CommandRun declare_env_convert(CLI::App& app) {
  auto args = std::make_shared<EnvConvertOptions>();
  app.description("rewrite an environment as a lat-long map, an angular map (light probe) or a mirror-ball image");
  add_text(app, "ENV", args->environment, kEnvironmentSyntax)->required();
  add_environment_format(app, args->format);
  add_choice(app, "--to FORMAT", args->to, {"latlong", "angular", "mirror_ball"}, "the layout to write")->required();
  add_text(app, "--out FILE.exr", args->out, "the file written")->required();
  add_integer(app, "--size N", args->size, 1, 65536,
              "pixels across a probe image (default: the map's width, which keeps its resolution)");
  CLI::Option* resolution = add_map_resolution(app, args->resolution);
  app.callback([args, resolution] {
    if (resolution->count() > 0 && !args->environment.starts_with("procedural:"))
      throw Error("option --res sets the resolution of a procedural map; " + args->environment + " is a file");
    if (args->size && args->to == "latlong")
      throw Error("option --size sets a probe image's size; a lat-long map keeps the resolution it was read at");
  });
  return [args] { return env_convert(*args); };
}

}  // namespace glaze
