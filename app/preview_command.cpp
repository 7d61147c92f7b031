// preview_command.cpp: `glaze preview`: a window that shows a glTF scene's camera as it
// renders (preview_renderer.h), with orbit/pan/zoom, integrator, exposure, tone mapping
// and false-colour views, and saving. Headless: --frames N [--screenshot FILE.png]
// shows N published steps in lockstep (the same image every run) and exits.
#include "app/commands.h"
#include "app/orbit_camera.h"
#include "app/preview_renderer.h"
#include "app/preview_window.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "renderer/camera_placement.h"
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>

namespace glaze {
namespace {

constexpr const char* kKeyHelp = R"(glaze preview keys:
  left drag            orbit about the object      right drag / shift+left   pan
  scroll / middle drag zoom                        R   back to the scene camera
  C / shift+C          next / previous scene camera
  I                    integrator: path <-> sh
  + / -   0            exposure up / down one stop; back to the start
  T                    tone mapping: clamp -> filmic -> aces
  F                    false colour: off -> relative error -> n.v
  S                    save the image: linear EXR and the PNG as shown
  H / F1               this help               Q / Esc   quit
)";

struct PreviewCommandOptions {
  std::string scene;
  CameraChoice camera;
  std::optional<Resolution> resolution;
  std::optional<std::string> integrator;  // default: sh for a single convex object, else path
  int lmax = 4, supersampling = 2;
  uint64_t seed = 0;
  int threads = 0;
  int max_depth = 8;
  EnvironmentOverride environment;
  DisplaySettings display;
  int max_spp = 4096;
  WindowOptions window;
  float spin_degrees = 0.0f;
  std::string save_dir = ".";
};

enum class FalseColour { off, relative_error, n_dot_v };

// Per pixel, |Y_sh - Y_path| / Y_path: where the analytic model departs from the path
// tracer's estimate (which is itself noisy at low spp).
std::vector<float> sh_against_path(const PreviewFrame& frame) {
  std::vector<float> values(frame.n_dot_v.size(), std::numeric_limits<float>::quiet_NaN());
  if (frame.path_spp == 0 || frame.sh_ss == 0) return values;
  for (size_t p = 0; p < values.size(); ++p) {
    const float reference = luminance(frame.path.at(int(p % frame.path.width), int(p / frame.path.width)));
    if (reference > 0.0f)
      values[p] =
          std::abs(luminance(frame.sh.at(int(p % frame.sh.width), int(p / frame.sh.width))) - reference) / reference;
  }
  return values;
}

struct ViewState {
  PreviewIntegrator integrator;
  DisplaySettings display;
  FalseColour false_colour = FalseColour::off;
};

// The linear image the integrator shows: its own, or the other's until its own exists.
const Image& shown_image(const PreviewFrame& frame, PreviewIntegrator integrator, bool* substitute = nullptr) {
  const bool sh = integrator == PreviewIntegrator::sh ? frame.sh_ss > 0 : frame.path_spp == 0 && frame.sh_ss > 0;
  if (substitute) *substitute = sh != (integrator == PreviewIntegrator::sh);
  return sh ? frame.sh : frame.path;
}

std::vector<uint8_t> picture(const PreviewFrame& frame, const ViewState& view) {
  const int w = frame.camera.width, h = frame.camera.height;
  switch (view.false_colour) {
    case FalseColour::relative_error:
      // 0.1% (dark) to 100% (bright), logarithmic.
      return false_colour_image(
          view.integrator == PreviewIntegrator::path ? frame.path_relative_error : sh_against_path(frame), w, h, 1e-3f,
          1.0f, true);
    case FalseColour::n_dot_v:
      return false_colour_image(frame.n_dot_v, w, h, 0.0f, 1.0f, false);
    case FalseColour::off:
      break;
  }
  return display_image(shown_image(frame, view.integrator), view.display);
}

std::string title(const std::string& camera, const PreviewFrame* frame, const ViewState& view,
                  const ShIntegratorOptions& sh, double elapsed) {
  char text[512];
  std::string integrator = view.integrator == PreviewIntegrator::sh
                               ? "sh lmax " + std::to_string(sh.lmax) + " ss " + std::to_string(sh.supersampling)
                               : "path";
  bool substitute = false;
  if (frame) shown_image(*frame, view.integrator, &substitute);
  if (!frame || substitute) integrator += " (rendering...)";
  const int spp = frame ? frame->path_spp : 0;
  const double rate = frame && frame->path_seconds > 0
                          ? double(spp) * frame->camera.width * frame->camera.height / frame->path_seconds / 1e6
                          : 0.0;
  const char* views[] = {"", " | relative error 0.1%..100% (log)", " | n.v 0..1"};
  const char* error_against =
      view.false_colour == FalseColour::relative_error && view.integrator == PreviewIntegrator::sh ? " against path"
                                                                                                   : "";
  std::snprintf(text, sizeof text, "glaze preview | %s | %s | %d spp, %.2f M samples/s | %.1f s | EV %+g %s%s%s",
                camera.c_str(), integrator.c_str(), spp, rate, elapsed, view.display.exposure_ev,
                tone_mapping_name(view.display.tone_mapping), views[int(view.false_colour)], error_against);
  return text;
}

int preview(const PreviewCommandOptions& args) {
  const auto launch = Clock::now();
  const int frames = args.window.frames;
  const std::string& screenshot = args.window.screenshot;
  const float spin = args.spin_degrees * std::numbers::pi_v<float> / 180.0f;
  require_display("glaze render");  // before any loading: no display fails at once

  Scene scene = load_scene(args.scene);
  const EnvironmentSpec spec = environment_spec(scene, args.environment);
  const CameraSpec* const first_camera = &scene.camera(choose_camera(scene, args.camera, args.resolution));
  ViewState view;
  view.display = args.display;
  const std::string integrator_name = args.integrator.value_or(scene.is_single_convex_object() ? "sh" : "path");
  view.integrator = preview_integrator(integrator_name);

  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);
  const RayTracer ray_tracer(scene);
  PathTracerOptions path_options;
  path_options.max_depth = args.max_depth;
  const PathTracer tracer(scene, ray_tracer, environment, path_options);

  PreviewRendererOptions options;
  options.sh.lmax = args.lmax;
  options.sh.supersampling = args.supersampling;
  options.sh.threads = options.path.threads = args.threads;
  options.path.seed = args.seed;
  options.max_spp = args.max_spp;
  options.lockstep = frames > 0;
  const std::optional<std::pair<int, int>> resolution =
      args.resolution ? std::optional(args.resolution->pair()) : std::nullopt;
  const std::filesystem::path save_dir = args.save_dir;

  size_t camera_index = size_t(first_camera - scene.cameras.data());
  const Vec3 centre = bounding_sphere(scene).centre;
  OrbitCamera orbit(scene.make_camera(scene.cameras[camera_index], resolution), centre);

  PreviewWindow window("glaze preview", orbit.camera().width, orbit.camera().height);
  PreviewRenderer renderer(scene, ray_tracer, environment, tracer, options, orbit.camera(), view.integrator);

  // Input: every change of camera restarts the accumulation; display changes only redraw.
  bool dirty = true;
  int saved = 0;
  Clock::time_point camera_changed = Clock::now();
  std::shared_ptr<const PreviewFrame> frame;
  auto move_camera = [&] {
    renderer.set_camera(orbit.camera());
    camera_changed = Clock::now();
  };
  auto select_camera = [&](size_t index) {
    camera_index = index;
    orbit = OrbitCamera(scene.make_camera(scene.cameras[camera_index], resolution), centre);
    move_camera();
  };
  auto save = [&] {
    if (!frame) return;
    std::error_code ec;
    std::filesystem::create_directories(save_dir, ec);
    // The first number not used yet: an earlier session's saves are never overwritten.
    std::string stem;
    do {
      stem = (save_dir / (std::filesystem::path(scene.path).stem().string() + "_" + scene.cameras[camera_index].name +
                          "_" + std::to_string(saved++)))
                 .string();
    } while (std::filesystem::exists(stem + ".exr") || std::filesystem::exists(stem + ".png"));
    const bool sh = &shown_image(*frame, view.integrator) == &frame->sh;
    write_image(stem + ".exr", shown_image(*frame, view.integrator),
                {{"glaze:integrator", sh ? "sh" : "path"},
                 {"glaze:spp", std::to_string(frame->path_spp)},
                 {"glaze:scene", scene.path}});
    write_picture(stem + ".png", frame->camera.width, frame->camera.height, picture(*frame, view),
                  {{"glaze:exposure", std::to_string(view.display.exposure_ev)},
                   {"glaze:tone_mapping", tone_mapping_name(view.display.tone_mapping)}});
    std::printf("saved %s.exr and %s.png\n", stem.c_str(), stem.c_str());
  };
  window.on_key = [&](int key, int mods) {
    const bool shift = mods & GLFW_MOD_SHIFT;
    switch (key) {
      case GLFW_KEY_ESCAPE:
      case GLFW_KEY_Q:
        window.close();
        break;
      case GLFW_KEY_H:
      case GLFW_KEY_F1:
        std::fputs(kKeyHelp, stdout);
        std::fflush(stdout);
        break;
      case GLFW_KEY_R:
        select_camera(camera_index);
        break;
      case GLFW_KEY_C:
        select_camera((camera_index + (shift ? scene.cameras.size() - 1 : 1)) % scene.cameras.size());
        break;
      case GLFW_KEY_I:
        view.integrator = view.integrator == PreviewIntegrator::sh ? PreviewIntegrator::path : PreviewIntegrator::sh;
        renderer.set_integrator(view.integrator);
        break;
      case GLFW_KEY_EQUAL:
      case GLFW_KEY_KP_ADD:
        view.display.exposure_ev += 1.0f;
        break;
      case GLFW_KEY_MINUS:
      case GLFW_KEY_KP_SUBTRACT:
        view.display.exposure_ev -= 1.0f;
        break;
      case GLFW_KEY_0:
      case GLFW_KEY_KP_0:
        view.display.exposure_ev = args.display.exposure_ev;
        break;
      case GLFW_KEY_T:
        view.display.tone_mapping = ToneMapping((int(view.display.tone_mapping) + 1) % 3);
        break;
      case GLFW_KEY_F:
        view.false_colour = FalseColour((int(view.false_colour) + 1) % 3);
        break;
      case GLFW_KEY_S:
        try {
          save();
        } catch (const Error& error) {  // the window stays: the user can fix the folder and retry
          std::fprintf(stderr, "glaze: error: %s\n", error.what());
        }
        break;
      default:
        return;
    }
    dirty = true;
  };
  // Mouse motion (screen units) to picture pixels.
  auto picture_scale = [&] {
    return window.picture_pixels_per_screen_unit(orbit.camera().width, orbit.camera().height);
  };
  window.on_drag = [&](double dx, double dy, int button, int mods) {
    const double scale = picture_scale();
    if (button == 2) {
      orbit.zoom(float(std::exp(0.01 * dy * scale)));
    } else if (button == 1 || (mods & GLFW_MOD_SHIFT)) {
      orbit.pan(float(dx * scale), float(dy * scale));
    } else {
      const float radians_per_pixel = std::numbers::pi_v<float> / orbit.camera().height;
      orbit.orbit(-float(dx * scale) * radians_per_pixel, float(dy * scale) * radians_per_pixel);
    }
    move_camera();
  };
  window.on_scroll = [&](double steps) {
    orbit.zoom(float(std::pow(0.9, steps)));
    move_camera();
  };

  if (frames == 0) std::fprintf(stderr, "glaze preview: press H in the window for the keys\n");
  double first_image = -1.0;
  int shown = 0;
  uint64_t shown_version = 0;
  const auto start = Clock::now();
  auto last_title = Clock::time_point{};
  std::vector<uint8_t> pixels;
  while (!window.should_close()) {
    const std::shared_ptr<const PreviewFrame> newest =
        frames > 0 ? renderer.wait_newer(shown_version) : renderer.latest();
    if (newest && newest->version != shown_version) frame = newest, shown_version = newest->version, dirty = true;
    if (dirty && frame) {
      pixels = picture(*frame, view);
      if (first_image < 0) first_image = seconds_since(launch);
      dirty = false;
    }
    if (!pixels.empty()) window.draw(frame->camera.width, frame->camera.height, pixels);
    if (Clock::now() - last_title > std::chrono::milliseconds(250) || frames > 0) {
      window.set_title(
          title(scene.cameras[camera_index].name, frame.get(), view, options.sh, seconds_since(camera_changed)));
      last_title = Clock::now();
    }
    ++shown;
    if (frames > 0 && shown >= frames) {
      if (!screenshot.empty()) {
        int w, h;
        const std::vector<uint8_t> shot = window.read_back(w, h);
        write_picture(screenshot, w, h, shot, {{"glaze:frames", std::to_string(frames)}});
        std::printf("wrote %s (%dx%d, frame %d)\n", screenshot.c_str(), w, h, frames);
      }
      window.present();
      break;
    }
    window.present();
    if (spin != 0.0f) {
      orbit.orbit(spin, 0.0f);
      move_camera();
    }
    window.wait_events(frames > 0 ? 0.0 : 1.0 / 60.0);
  }
  const double elapsed = seconds_since(start);
  std::fprintf(stderr, "preview: first image %.3f s after launch; %d frame%s in %.2f s (%.1f frames/s)", first_image,
               shown, shown == 1 ? "" : "s", elapsed, shown / std::max(elapsed, 1e-9));
  if (frame && frame->sh_ss > 0)
    std::fprintf(stderr, "; sh %dx%d ss %d: %.1f ms an image", frame->camera.width, frame->camera.height, frame->sh_ss,
                 1e3 * frame->sh_seconds);
  if (frame && frame->path_spp > 0)
    std::fprintf(stderr, "; path %d spp at %.2f M samples/s", frame->path_spp,
                 frame->path_spp * double(frame->camera.width) * frame->camera.height / frame->path_seconds / 1e6);
  std::fprintf(stderr, "\n");
  return 0;
}

}  // namespace

CommandRun declare_preview(CLI::App& app) {
  auto args = std::make_shared<PreviewCommandOptions>();
  app.description(
      "a window that shows the render as it refines; orbit, pan, zoom, exposure, tone mapping\n"
      "(press H in the window for the keys)");
  add_scene(app, args->scene);
  add_camera_choice(app, args->camera,
                    "the camera to start from, by its node's or its glTF camera's name (default: the first)");
  add_film_resolution(app, args->resolution);
  add_integrator(app, args->integrator,
                 "shown first (default: sh for a single convex object, else path); the other follows in the\n"
                 "background (key I switches)");
  add_lmax(app, args->lmax, "SH band limit of the sh integrator's diffuse term");
  add_supersampling(app, args->supersampling);
  add_integer(app, "--max-spp N", args->max_spp, 1, 1 << 24, "path passes stop here");
  add_seed(app, args->seed, "random seed of the path tracer");
  add_threads(app, args->threads);
  add_max_depth(app, args->max_depth);
  add_environment_override(app, args->environment);
  add_display_options(app, args->display);
  add_text(app, "--save-dir DIR", args->save_dir, "where key S saves NAME_CAMERA_N.exr and .png");
  add_window_options(app, args->window);
  add_real(app, "--spin DEG", args->spin_degrees, "turn the camera DEG degrees about the object after every frame");
  app.footer("Without a display (DISPLAY unset) it fails at once; headless: xvfb-run.");
  return [args] { return preview(*args); };
}

}  // namespace glaze
