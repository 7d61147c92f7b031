// shared_options.h: the options that several glaze commands take, each declared once
// here (command_line.h) so that its bounds, default and meaning cannot differ between the
// commands, and what they apply to (an environment, a picture, the preview window).
#pragma once

#include "app/command_line.h"
#include "renderer/integrator_registry.h"
#include "renderer/display.h"
#include "renderer/scene.h"
#include "renderer/sh.h"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace glaze {

// What ENV may be, wherever a command takes one.
inline constexpr const char* kEnvironmentSyntax =
    "a lat-long image (EXR, HDR, PFM, ...), an angular map or mirror-ball image (square; see --env-format), or\n"
    "procedural:NAME with NAME one of constant, office, blue-room";

// --env-format NAME: how an environment file is laid out (renderer/environment_format.h);
// by default recognised from its shape.
template <typename T>
CLI::Option* add_environment_format(CLI::App& app, T& format) {
  return add_choice(app, "--env-format NAME", format, {"auto", "latlong", "angular", "mirror_ball"},
                    "the environment file's layout: latlong (2:1), angular (Debevec's light probes) or mirror_ball; "
                    "auto: 2:1 is latlong, square with black corners angular");
}

// SCENE: the glTF scene (render, convergence, preview).
CLI::Option* add_scene(CLI::App& app, std::string& scene);
// --res WxH of a procedural map (sh, env), by default as big as a scene's.
inline constexpr Resolution kProceduralMapResolution{1024, 512};
CLI::Option* add_map_resolution(CLI::App& app, Resolution& resolution);
// --camera NAME: one of the scene's cameras (default: the first); or a camera placed with
// --look-from X,Y,Z, --look-at X,Y,Z and --fov DEG (not with --camera), what is not
// given taken from the default view (renderer/camera_placement.h).
struct CameraChoice {
  std::optional<std::string> name;
  std::vector<float> look_from, look_at;  // 3 numbers, or empty when not given
  std::optional<float> fov_degrees;
  bool placed() const { return !look_from.empty() || !look_at.empty() || fov_degrees.has_value(); }
};
// Adds the four options (`name_help` says what --camera takes); returns the placement's three.
std::vector<CLI::Option*> add_camera_choice(CLI::App& app, CameraChoice& camera, const std::string& name_help);
// The name of the camera that `choice` picks in `scene`. A placed camera ("placed") is
// added to `scene.cameras`; so is the default view ("default") when the scene has no
// camera (and --camera names none, or "default" or "all"), with a warning that says how
// it was chosen and how to place one. The film
// size (`resolution`, else the scene's) sets how wide they see.
std::string choose_camera(Scene& scene, const CameraChoice& choice, const std::optional<Resolution>& resolution);
// --res WxH of the film (default: the scene's film).
CLI::Option* add_film_resolution(CLI::App& app, std::optional<Resolution>& resolution);
// --threads N: worker threads, 0 for all cores.
CLI::Option* add_threads(CLI::App& app, int& threads);
// --seed S of the random numbers.
CLI::Option* add_seed(CLI::App& app, uint64_t& seed, const std::string& help);
// --spp N: path-traced samples per pixel.
template <typename T>
CLI::Option* add_spp(CLI::App& app, T& spp, const std::string& help) {
  return add_integer(app, "--spp N", spp, 1, 1 << 20, help);
}
// --integrator NAME, one of the registry's (path, sh).
template <typename T>
CLI::Option* add_integrator(CLI::App& app, T& integrator, const std::string& help) {
  return add_choice(app, "--integrator NAME", integrator, integrator_names(), help);
}
// --max-depth N of the path tracer.
CLI::Option* add_max_depth(CLI::App& app, int& max_depth);
// --lmax N: an SH band limit.
template <typename T>
CLI::Option* add_lmax(CLI::App& app, T& lmax, const std::string& help) {
  return add_integer(app, "--lmax N", lmax, 0, kShMaxLmax, help);
}
// --ss K: the sh integrator's K x K samples a pixel.
CLI::Option* add_supersampling(CLI::App& app, int& supersampling);

// --env ENV, --env-format NAME, --env-scale S, --env-rotation DEG: the lighting instead of
// the scene's (or the capture set's), or adjusted.
struct EnvironmentOverride {
  std::optional<std::string> source, format;
  std::optional<float> scale, rotation_degrees;
};
void add_environment_override(CLI::App& app, EnvironmentOverride& environment);

// The scene's environment with the override applied; throws glaze::Error if there is none.
EnvironmentSpec environment_spec(const Scene& scene, const EnvironmentOverride& environment);

// --exposure EV, --tone-map NAME: how radiance is shown as a picture.
void add_display_options(CLI::App& app, DisplaySettings& display);

// --frames N [--screenshot FILE.png]: show N steps in the window, then exit (headless
// runs, tests).
struct WindowOptions {
  int frames = 0;  // 0: until the window is closed
  std::string screenshot;
};
void add_window_options(CLI::App& app, WindowOptions& window);

// --lens MODEL[:NAME=VALUE,...] (render, simulate-shoot), MODEL as transforms.json's
// "camera_model" names it. Throws glaze::Error saying the syntax.
LensDistortion parse_lens(const std::string& text);

}  // namespace glaze
