// render_command.cpp: `glaze render`: images of a glTF scene's cameras, or a capture
// set (docs/design.md §4) for the inverse module.
#include "app/commands.h"
#include "app/shared_options.h"
#include "app/timing.h"
#include "renderer/capture_set.h"
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/integrator_registry.h"
#include "renderer/output_folder.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <iostream>
#include <sstream>

namespace glaze {
namespace {

struct RenderCommandOptions {
  std::string scene;
  std::string out;                      // FILE.exr, FILE.png, or DIR with --camera all
  std::optional<std::string> captures;  // or a capture set's DIR
  CameraChoice camera;
  std::optional<Resolution> resolution;
  std::string integrator = "path";
  // The path tracer.
  std::optional<int> spp;
  std::optional<float> time_budget;
  uint64_t seed = 0;
  int threads = 0;
  int max_depth = 8;
  std::string estimator = "mis";
  EnvironmentOverride environment;
  std::vector<std::string> holdout;
  // The sh integrator.
  int lmax = 4, supersampling = 2, refined_supersampling = 0;
  DisplaySettings display;  // of a picture
  std::string lens;         // --lens MODEL:k1=..,..: every camera seen through it
};

std::string materials_json(const Scene& scene) {
  nlohmann::json list = nlohmann::json::array();
  for (const SceneMaterial& m : scene.materials) {
    nlohmann::json entry = {{"name", m.name}, {"R0", m.R0}, {"Rd", {m.Rd[0], m.Rd[1], m.Rd[2]}}};
    if (m.texture >= 0) entry["texture"] = scene.textures[m.texture].source;
    list.push_back(entry);
  }
  return list.dump();
}

// An 8-bit picture for people (display.h) rather than radiance.
bool is_picture(const std::string& path) {
  const std::string extension = std::filesystem::path(path).extension().string();
  return extension == ".png" || extension == ".jpg" || extension == ".jpeg";
}

struct Job {
  const Scene& scene;
  const EnvironmentSpec& environment_spec;
  const Environment& environment;
  const Integrator& integrator;
  const IntegratorOptions& options;  // the integrator's, for the capture set's "renderer"
  bool progress;                     // say which camera renders
  std::optional<std::pair<int, int>> resolution;
  DisplaySettings display;  // of a picture (.png, .jpg) instead of radiance
  LensDistortion lens;

  PinholeCamera camera(const CameraSpec& spec) const {
    PinholeCamera camera = scene.make_camera(spec, resolution);
    if (lens.is_none()) return camera;
    camera.distortion = lens;
    camera.check_lens("--lens on camera '" + spec.name + "'");
    return camera;
  }

  // `folder`, if given, tags the image with its run.
  void render_to(const CameraSpec& spec, const std::string& path, OutputFolder* folder = nullptr) const {
    const PinholeCamera camera = this->camera(spec);
    if (progress) std::cerr << "rendering " << spec.name << " (" << camera.width << "x" << camera.height << ")\n";
    // Each camera draws its own random streams (render.h): views of one set have
    // independent noise.
    const uint64_t camera_index = uint64_t(&scene.camera(spec.name) - scene.cameras.data());
    IntegratorResult result = integrator.render(camera, camera_index);
    const Image& image = result.image;
    const double seconds = result.seconds;
    std::map<std::string, std::string> metadata = std::move(result.metadata);
    metadata.insert({{"glaze:camera", spec.name},
                     {"glaze:scene", scene.path},
                     {"glaze:environment", environment_spec.source},
                     {"glaze:materials", materials_json(scene)},
                     {"glaze:seconds", std::to_string(seconds)}});
    if (folder) folder->tag(metadata);
    if (is_picture(path)) {
      metadata["glaze:exposure"] = std::to_string(display.exposure_ev);
      metadata["glaze:tone_mapping"] = tone_mapping_name(display.tone_mapping);
      write_picture(path, image.width, image.height, display_image(image, display), metadata);
    } else {
      write_image(path, image, metadata);
    }
    std::cerr << "wrote " << path << " (" << result.summary << ", " << seconds << " s)\n";
  }
};

void write_captures(const Job& job, const std::string& directory, const std::vector<std::string>& holdout,
                    const Environment& environment) {
  const Scene& scene = job.scene;
  std::set<const CameraSpec*> held_out_cameras;  // unknown names fail before any work
  for (const std::string& name : holdout) held_out_cameras.insert(&scene.camera(name));
  if (held_out_cameras.size() == scene.cameras.size())
    throw Error("--holdout names every camera of " + scene.path + "; leave at least one for the capture set");
  for (const CameraSpec& spec : scene.cameras) check_capture_camera(job.camera(spec));
  // Held-out views go to DIR/holdout, a set of its own. DIR's transforms.json, written
  // last, says that both are whole (output_folder.h).
  const std::filesystem::path root(directory);
  OutputFolder main_folder(root, "transforms.json", "capture set");
  std::optional<OutputFolder> holdout_folder;
  if (!holdout.empty()) holdout_folder.emplace(root / "holdout", "transforms.json", "held-out capture set");

  // The object: the analytic sphere exactly, else the scene file itself.
  CaptureSet set;
  if (scene.is_single_convex_object()) {
    const Sphere& s = scene.spheres.front();
    set.object = CaptureSphere{s.center, s.radius};
  } else {
    set.object = CaptureGltf{std::filesystem::absolute(scene.path).string()};
  }
  // The environment: a procedural one is written beside the captures (and named
  // relative to each transforms.json), a file is named by its absolute path.
  CaptureEnvironment environment_entry{{}, {}, job.environment_spec.options};
  const bool procedural = job.environment_spec.source.starts_with("procedural:");
  const std::filesystem::path environment_file = procedural ? std::filesystem::absolute(root / "environment.exr")
                                                            : std::filesystem::absolute(job.environment_spec.source);
  if (procedural) {
    main_folder.write_image(environment_file.filename().string(), environment.map(),
                            {{"glaze:environment", job.environment_spec.source}});
    environment_entry.procedural = job.environment_spec.source.substr(std::string("procedural:").size());
  }
  // The material, when the object has exactly one.
  std::set<int> used;
  for (const Sphere& s : scene.spheres) used.insert(s.material);
  for (const TriangleMesh& m : scene.meshes) used.insert(m.material);
  if (used.size() == 1) {
    const SceneMaterial& m = scene.materials[*used.begin()];
    set.material = CaptureMaterial{PolishedMaterial(m.R0, m.Rd), {}};
    if (m.texture >= 0) {
      // As an absolute path when it is a file beside the scene (not embedded data), so
      // that the fit can compare its recovered texture against it.
      const std::filesystem::path file =
          std::filesystem::absolute(std::filesystem::path(scene.path).parent_path() / scene.textures[m.texture].source);
      set.material->texture = std::filesystem::exists(file) ? file.string() : scene.textures[m.texture].source;
    }
  }
  const ShIntegratorOptions& sh = job.options.sh;
  set.renderer =
      job.integrator.name() == ShIntegrator::kName
          ? CaptureRenderer{.integrator = CaptureRenderer::Integrator::sh,
                            .supersampling = sh.supersampling,
                            .lmax = sh.lmax}
          : CaptureRenderer{.integrator = CaptureRenderer::Integrator::path, .spp = job.options.path_render.spp};

  auto render_views = [&](OutputFolder& folder, bool held_out) {
    set.frames.clear();
    set.run = folder.run();
    environment_entry.file =
        procedural ? std::filesystem::relative(environment_file, std::filesystem::absolute(folder.path())).string()
                   : environment_file.string();
    set.environment = environment_entry;
    for (const CameraSpec& spec : scene.cameras) {
      if (held_out_cameras.count(&spec) != size_t(held_out)) continue;
      char file[64];
      std::snprintf(file, sizeof file, "view_%03zu.exr", set.frames.size());
      job.render_to(spec, folder.file(file).string(), &folder);
      set.frames.push_back({file, job.camera(spec), ""});
    }
    return set;
  };
  const CaptureSet views = render_views(main_folder, false);
  if (holdout_folder) holdout_folder->finish(transforms_json(render_views(*holdout_folder, true)));
  main_folder.finish(transforms_json(views));
}

int render(const RenderCommandOptions& args) {
  Scene scene = load_scene(args.scene);
  const EnvironmentSpec spec = environment_spec(scene, args.environment);
  const std::string camera_name = choose_camera(scene, args.camera, args.resolution);
  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);
  const RayTracer ray_tracer(scene);

  PathTracerOptions path_options;
  path_options.max_depth = args.max_depth;
  path_options.estimator = parse_direct_light_estimator(args.estimator);
  path_options.black_background = args.captures.has_value();

  RenderOptions options;
  options.spp = args.spp.value_or(64);
  options.time_budget = args.time_budget.value_or(0.0f);
  options.seed = args.seed;
  options.threads = args.threads;
  options.progress = isatty(STDERR_FILENO);
  if (args.time_budget && !args.spp) options.spp = 4;  // samples per pass

  ShIntegratorOptions sh;
  sh.lmax = args.lmax;
  sh.supersampling = args.supersampling;
  sh.refined_supersampling = args.refined_supersampling;
  sh.black_background = args.captures.has_value();
  sh.threads = options.threads;
  const IntegratorOptions integrator_options{path_options, options, sh};
  const std::unique_ptr<Integrator> renderer =
      make_integrator(args.integrator, scene, ray_tracer, environment, integrator_options);
  const Job job{scene,
                spec,
                environment,
                *renderer,
                integrator_options,
                options.progress,
                args.resolution ? std::optional(args.resolution->pair()) : std::nullopt,
                args.display,
                args.lens.empty() ? LensDistortion{} : parse_lens(args.lens)};

  if (args.captures) {
    write_captures(job, *args.captures, args.holdout, environment);
    return 0;
  }
  const std::string& out = args.out;
  if (camera_name == "all") {
    create_output_folder(out, "output");
    for (const CameraSpec& camera : scene.cameras)
      job.render_to(camera, (std::filesystem::path(out) / (camera.name + ".exr")).string());
  } else {
    job.render_to(scene.camera(camera_name), out);
  }
  return 0;
}

}  // namespace

CommandRun declare_render(CLI::App& app) {
  auto args = std::make_shared<RenderCommandOptions>();
  app.description("path-trace a glTF scene's cameras, or a capture set for invert-fit");
  add_scene(app, args->scene);
  CLI::Option* out = add_text(app, "--out FILE.exr|DIR", args->out,
                              "the image (radiance; FILE.png or .jpg: a picture, as the preview window shows it),\n"
                              "or the folder of --camera all");
  CLI::Option* captures = add_text(app, "--captures DIR", args->captures,
                                   "write a capture set of every camera for invert-fit: DIR/transforms.json and\n"
                                   "the views' EXR images (black background)");
  out->excludes(captures);
  const std::vector<CLI::Option*> placement =
      add_camera_choice(app, args->camera,
                        "which camera, by its node's or its glTF camera's name (default: the first);\n"
                        "all: every camera, DIR/NAME.exr");
  for (CLI::Option* option : placement) option->excludes(captures);
  add_film_resolution(app, args->resolution);
  add_names(app, "--holdout NAME,...", args->holdout,
            "cameras held out of the capture set: written to DIR/holdout, which invert-fit re-renders")
      ->needs(captures);
  add_text(app, "--lens MODEL:NAME=VALUE,...", args->lens,
           "see every camera through a distorting lens, as transforms.json names it:\n"
           "OPENCV:k1=..,k2=..,p1=..,p2=..(,k3=..) or OPENCV_FISHEYE:k1=..,k2=..,k3=..,k4=..\n"
           "(a capture set records it, for tests of photographs' lenses)");
  add_environment_override(app, args->environment);
  add_threads(app, args->threads);
  add_integrator(app, args->integrator,
                 "path: the Monte-Carlo path tracer; sh: the analytic SH shading model, no noise");

  const std::string path = "path tracer (--integrator path)", sh = "sh integrator (--integrator sh)";
  const std::vector<CLI::Option*> path_options = {
      add_spp(app, args->spp, "samples per pixel (default 64; with --time-budget, a pass's: default 4)"),
      add_real(app, "--time-budget SEC", args->time_budget,
               "render passes of --spp samples until SEC is spent (at most 7 days: 604800)", 0.0f, 604800.0f),
      add_max_depth(app, args->max_depth),
      add_choice(app, "--estimator NAME", args->estimator, {"mis", "bsdf", "environment"}, "direct light estimator"),
  };
  add_seed(app, args->seed, "random seed; the image depends only on it")->group(path);
  const std::vector<CLI::Option*> sh_options = {
      add_lmax(app, args->lmax, "SH band limit of the diffuse term"),
      add_supersampling(app, args->supersampling),
      add_integer(app, "--ss-refine M", args->refined_supersampling, 0, 64,
                  "M x M samples where a pixel's K x K differ by over 1% (edges, silhouettes; 0: off;\n"
                  "not with --captures: the fits model one footprint for every pixel)")
          ->excludes(captures),
  };
  for (CLI::Option* option : path_options) option->group(path);
  for (CLI::Option* option : sh_options) option->group(sh);
  add_display_options(app, args->display);
  const std::vector<CLI::Option*> picture_options = {app.get_option("--exposure"), app.get_option("--tone-map")};
  for (CLI::Option* option : picture_options) option->group("picture (--out FILE.png)");

  // The refusals that depend on values.
  app.callback([args, out, captures, path_options, sh_options, picture_options] {
    if (out->count() == 0 && captures->count() == 0) throw Error("give --out FILE.exr|DIR or --captures DIR");
    auto given = [](const std::vector<CLI::Option*>& options) {
      return std::any_of(options.begin(), options.end(), [](const CLI::Option* o) { return o->count() > 0; });
    };
    if (args->integrator != "sh" && given(sh_options))
      throw Error("--lmax, --ss and --ss-refine apply to --integrator sh");
    if (args->integrator == "sh" && given(path_options))
      throw Error("--spp, --time-budget, --estimator and --max-depth apply to --integrator path");
    if (given(picture_options) && !is_picture(args->out))
      throw Error("--exposure and --tone-map apply to a picture: --out FILE.png (an EXR keeps the radiance)");
  });
  return [args] { return render(*args); };
}

}  // namespace glaze
