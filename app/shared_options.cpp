#include "app/shared_options.h"

#include "renderer/error.h"

#include <filesystem>
#include <limits>

namespace glaze {

CLI::Option* add_scene(CLI::App& app, std::string& scene) {
  return add_text(app, "SCENE", scene, "a glTF scene (.gltf, .glb)")->required();
}

CLI::Option* add_map_resolution(CLI::App& app, Resolution& resolution) {
  return add_resolution(app, "--res WxH", resolution, "resolution of a procedural map");
}

CLI::Option* add_camera(CLI::App& app, std::optional<std::string>& camera, const std::string& help) {
  return add_text(app, "--camera NAME", camera, help);
}

CLI::Option* add_film_resolution(CLI::App& app, std::optional<Resolution>& resolution) {
  return add_resolution(app, "--res WxH", resolution, "film size (default: the scene's film, else 512 high)");
}

CLI::Option* add_threads(CLI::App& app, int& threads) {
  return add_integer(app, "--threads N", threads, 0, 1024, "worker threads (0: all cores)");
}

CLI::Option* add_seed(CLI::App& app, uint64_t& seed, const std::string& help) {
  return add_integer(app, "--seed S", seed, 0, std::numeric_limits<int64_t>::max(), help);
}

CLI::Option* add_max_depth(CLI::App& app, int& max_depth) {
  return add_integer(app, "--max-depth N", max_depth, 1, 1000, "surface interactions per path (1 for a single sphere)");
}

CLI::Option* add_supersampling(CLI::App& app, int& supersampling) {
  return add_integer(app, "--ss K", supersampling, 1, 64, "K x K sub-pixel samples of the sh integrator");
}

void add_environment_override(CLI::App& app, EnvironmentOverride& environment) {
  add_text(app, "--env ENV", environment.source,
           std::string("the lighting instead of the scene's: ") + kEnvironmentSyntax);
  add_real(app, "--env-scale S", environment.scale, "multiply the lighting's radiance");
  add_real(app, "--env-rotation DEG", environment.rotation_degrees, "rotate the lighting about +Y");
}

EnvironmentSpec environment_spec(const Scene& scene, const EnvironmentOverride& environment) {
  EnvironmentSpec spec;
  if (environment.source) {
    spec.source = *environment.source;
  } else if (scene.environment) {
    spec = *scene.environment;
  } else {
    throw Error(scene.path +
                ": the scene names no environment (scene.extras.glaze.environment); give --env FILE or "
                "--env procedural:office");
  }
  spec.options.scale = environment.scale.value_or(spec.options.scale);
  spec.options.rotation_degrees = environment.rotation_degrees.value_or(spec.options.rotation_degrees);
  return spec;
}

void add_display_options(CLI::App& app, DisplaySettings& display) {
  add_real(app, "--exposure EV", display.exposure_ev, "exposure of the picture, in stops");
  app.add_option_function<std::string>(
         "--tone-map", [&display](const std::string& name) { display.tone_mapping = parse_tone_mapping(name); },
         "tone mapping of the picture")
      ->type_name("NAME")
      ->check(one_of({"clamp", "filmic", "aces"}))
      ->default_str(tone_mapping_name(display.tone_mapping));
}

void add_window_options(CLI::App& app, WindowOptions& window) {
  CLI::Option* frames = add_integer(app, "--frames N", window.frames, 1, 1 << 20,
                                    "show N published steps (in lockstep: always the same picture) and exit");
  frames->default_str("");
  add_text(app, "--screenshot FILE.png", window.screenshot, "write what the window shows at the last frame")
      ->needs(frames)
      ->check(CLI::Validator(
          [](std::string& file) {
            return std::filesystem::path(file).extension() == ".png"
                       ? std::string()
                       : file + ": the screenshot is a PNG (name it FILE.png)";
          },
          ""));
}

}  // namespace glaze
