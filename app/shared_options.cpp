#include "app/shared_options.h"

#include "renderer/camera_placement.h"
#include "renderer/error.h"

#include <cmath>
#include <cstdio>
#include <sstream>
#include <filesystem>
#include <limits>

namespace glaze {

CLI::Option* add_scene(CLI::App& app, std::string& scene) {
  return add_text(app, "SCENE", scene, "a glTF scene (.gltf, .glb)")->required();
}

CLI::Option* add_map_resolution(CLI::App& app, Resolution& resolution) {
  return add_resolution(app, "--res WxH", resolution, "resolution of a procedural map");
}

namespace {

std::string unique_camera_name(const Scene& scene, std::string name) {
  for (const CameraSpec& camera : scene.cameras)
    if (camera.name == name) name += "_" + std::to_string(scene.cameras.size());
  return name;
}

// As the options take them: 4 significant digits, comma-separated.
std::string number_text(float x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", x);
  return text;
}
std::string point_text(const Vec3& p) {
  return number_text(p.x()) + "," + number_text(p.y()) + "," + number_text(p.z());
}

}  // namespace

std::vector<CLI::Option*> add_camera_choice(CLI::App& app, CameraChoice& camera, const std::string& name_help) {
  CLI::Option* name = add_text(app, "--camera NAME", camera.name, name_help);
  const std::vector<CLI::Option*> placement = {
      add_reals(app, "--look-from X,Y,Z", camera.look_from, 3,
                "place a camera at this point instead (default: in front of the scene and above it,\n"
                "far enough to see all of it)"),
      add_reals(app, "--look-at X,Y,Z", camera.look_at, 3,
                "the point the placed camera looks at, +Y up (default: the scene's centre)"),
      add_real(app, "--fov DEG", camera.fov_degrees,
               "vertical field of view (default " + number_text(kDefaultViewYfovDegrees) + ")", 0.0f, 180.0f),
  };
  for (CLI::Option* option : placement) option->excludes(name)->group("camera placement");
  return placement;
}

std::string choose_camera(Scene& scene, const CameraChoice& choice, const std::optional<Resolution>& resolution) {
  const std::pair<int, int> film = resolution ? resolution->pair() : scene.film.value_or(std::pair(1, 1));
  const float aspect = float(film.first) / float(film.second);
  auto vec3 = [](const std::vector<float>& v) {
    return v.empty() ? std::nullopt : std::optional(Vec3(v[0], v[1], v[2]));
  };
  if (choice.placed()) {
    const CameraPlacement placement{
        vec3(choice.look_from), vec3(choice.look_at),
        choice.fov_degrees ? std::optional(*choice.fov_degrees * kPi / 180.0f) : std::nullopt};
    scene.cameras.push_back(place_camera(scene, placement, aspect, unique_camera_name(scene, "placed")));
    return scene.cameras.back().name;
  }
  // The default view, unless --camera names another (whose error then lists none).
  if (scene.cameras.empty() && (!choice.name || *choice.name == "all" || *choice.name == "default")) {
    scene.cameras.push_back(place_camera(scene, {}, aspect, "default"));
    const BoundingSphere bounds = bounding_sphere(scene);
    const Vec3 from = scene.cameras.back().camera_to_world.translation();
    const std::string fov = number_text(kDefaultViewYfovDegrees);
    warn(scene.path + ": the file has no camera; the default view frames the scene's bounding sphere (centre " +
         point_text(bounds.centre) + ", radius " + number_text(bounds.radius) + ") from the front (+Z), " +
         number_text(kDefaultViewElevationDegrees) + " degrees above, with a " + fov +
         "-degree vertical field of view: --look-from " + point_text(from) + " --look-at " + point_text(bounds.centre) +
         " --fov " + fov + "; change those to place the camera");
  }
  return choice.name ? *choice.name : scene.cameras.front().name;
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
  add_environment_format(app, environment.format);
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
                ": the scene names no environment (scene.extras.glaze.environment, which files from other tools "
                "lack); give the lighting with --env FILE (a lat-long map: .hdr, .exr; or a light probe) or --env "
                "procedural:office");
  }
  if (environment.format) spec.options.format = parse_environment_format(*environment.format, "--env-format");
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

// --lens MODEL[:NAME=VALUE,...], MODEL as transforms.json's "camera_model" names it.
LensDistortion parse_lens(const std::string& text) {
  const std::string usage =
      "--lens takes MODEL[:NAME=VALUE,...], e.g. OPENCV:k1=-0.1,k2=0.02 or OPENCV_FISHEYE:k1=0.05; ";
  const size_t colon = text.find(':');
  const std::string name = text.substr(0, colon);
  const std::optional<LensDistortion::Model> model = camera_model_from_name(name);
  if (!model) throw Error(usage + "\"" + name + "\" is not a camera model (" + kSupportedCameraModels + ")");
  LensDistortion lens;
  lens.model = *model;
  std::stringstream terms(colon == std::string::npos ? "" : text.substr(colon + 1));
  for (std::string term; std::getline(terms, term, ',');) {
    const size_t equals = term.find('=');
    const std::string key = term.substr(0, equals);
    if (equals == std::string::npos || !model_uses(*model, key))
      throw Error(usage + "\"" + term + "\" is not NAME=VALUE with a coefficient of " + name + " (" +
                  kSupportedCameraModels + ")");
    size_t used = 0;
    double value = NAN;
    try {
      value = std::stod(term.substr(equals + 1), &used);
    } catch (const std::exception&) {
    }
    if (!std::isfinite(value) || used != term.size() - equals - 1)
      throw Error(usage + "\"" + term + "\" does not give " + key + " a finite number");
    coefficient(lens, key) = value;
  }
  return lens;
}

}  // namespace glaze
