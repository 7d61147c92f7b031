// render_command.cpp: `glaze render`: images of a glTF scene's cameras, or a capture
// set (DESIGN §4) for the inverse module.
#include "app/arguments.h"
#include "app/timing.h"
#include "app/commands.h"
#include "app/scene_options.h"
#include "renderer/capture_set.h"
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/path_tracer.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"
#include "renderer/scene.h"
#include "renderer/sh_integrator.h"

#include <nlohmann/json.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <set>
#include <iostream>

namespace glaze {
namespace {

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
  const RayTracer& ray_tracer;
  const PathTracer& tracer;
  RenderOptions options;
  std::optional<ShIntegratorOptions> sh;  // set: the sh integrator, else the path tracer
  std::optional<std::pair<int, int>> resolution;
  DisplaySettings display;  // of a picture (.png, .jpg) instead of radiance

  void render_to(const CameraSpec& spec, const std::string& path) const {
    const PinholeCamera camera = scene.make_camera(spec, resolution);
    if (options.progress) std::cerr << "rendering " << spec.name << " (" << camera.width << "x" << camera.height << ")\n";
    std::map<std::string, std::string> metadata = {{"glaze:camera", spec.name},
                                                   {"glaze:scene", scene.path},
                                                   {"glaze:environment", environment_spec.source},
                                                   {"glaze:materials", materials_json(scene)}};
    const auto start = std::chrono::steady_clock::now();
    Image image;
    std::string summary;
    if (sh) {
      image = render_sh(scene, ray_tracer, environment, camera, *sh);
      metadata["glaze:integrator"] = "sh";
      metadata["glaze:lmax"] = std::to_string(sh->lmax);
      metadata["glaze:ss"] = std::to_string(sh->supersampling);
      summary = "sh, lmax " + std::to_string(sh->lmax) + ", ss " + std::to_string(sh->supersampling);
      if (sh->refined_supersampling > 0) {
        metadata["glaze:ss_refined"] = std::to_string(sh->refined_supersampling);
        summary += " refined " + std::to_string(sh->refined_supersampling);
      }
    } else {
      // Each camera draws its own random streams (render.h): views of one set have
      // independent noise.
      RenderOptions view_options = options;
      view_options.camera = uint64_t(&scene.camera(spec.name) - scene.cameras.data());
      RenderResult result = render(tracer, camera, view_options);
      image = std::move(result.image);
      metadata["glaze:integrator"] = "path";
      metadata["glaze:spp"] = std::to_string(result.spp);
      metadata["glaze:seed"] = std::to_string(options.seed);
      metadata["glaze:max_depth"] = std::to_string(tracer.max_depth());
      summary = std::to_string(result.spp) + " spp";
    }
    const double seconds = seconds_since(start);
    metadata["glaze:seconds"] = std::to_string(seconds);
    if (is_picture(path)) {
      metadata["glaze:exposure"] = std::to_string(display.exposure_ev);
      metadata["glaze:tone_mapping"] = tone_mapping_name(display.tone_mapping);
      write_picture(path, image.width, image.height, display_image(image, display), metadata);
    } else {
      write_image(path, image, metadata);
    }
    std::cerr << "wrote " << path << " (" << summary << ", " << seconds << " s)\n";
  }
};

void write_captures(const Job& job, const std::string& directory, const std::vector<std::string>& holdout,
                    const Environment& environment) {
  const Scene& scene = job.scene;
  for (const std::string& name : holdout) scene.camera(name);  // unknown names fail before any work
  const std::filesystem::path root(directory);
  std::filesystem::create_directories(root / (holdout.empty() ? "" : "holdout"));

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
  const std::filesystem::path environment_file =
      procedural ? std::filesystem::absolute(root / "environment.exr") : std::filesystem::absolute(job.environment_spec.source);
  if (procedural) {
    write_image(environment_file.string(), environment.map(), {{"glaze:environment", job.environment_spec.source}});
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
      const std::filesystem::path file = std::filesystem::absolute(std::filesystem::path(scene.path).parent_path() / scene.textures[m.texture].source);
      set.material->texture = std::filesystem::exists(file) ? file.string() : scene.textures[m.texture].source;
    }
  }
  set.renderer = job.sh ? CaptureRenderer{.integrator = CaptureRenderer::Integrator::sh,
                                          .supersampling = job.sh->supersampling,
                                          .lmax = job.sh->lmax}
                        : CaptureRenderer{.integrator = CaptureRenderer::Integrator::path, .spp = job.options.spp};

  for (bool held_out : {false, true}) {
    set.frames.clear();
    const std::filesystem::path folder = held_out ? root / "holdout" : root;
    environment_entry.file = procedural
                                 ? std::filesystem::relative(environment_file, std::filesystem::absolute(folder)).string()
                                 : environment_file.string();
    set.environment = environment_entry;
    for (const CameraSpec& spec : scene.cameras) {
      const bool is_holdout = std::find(holdout.begin(), holdout.end(), spec.name) != holdout.end();
      if (is_holdout != held_out) continue;
      char file[64];
      std::snprintf(file, sizeof file, "view_%03zu.exr", set.frames.size());
      job.render_to(spec, (folder / file).string());
      set.frames.push_back({file, scene.make_camera(spec, job.resolution), ""});
    }
    if (!set.frames.empty()) write_transforms(folder.string(), set);
  }
}

}  // namespace

int command_render(const std::vector<std::string>& raw) {
  const Arguments args(raw, {"camera", "res", "spp", "time-budget", "seed", "threads", "integrator", "max-depth", "env",
                             "env-scale", "env-rotation", "estimator", "out", "captures", "holdout", "lmax", "ss", "ss-refine", "exposure",
                             "tone-map"});
  if (args.positionals().size() != 1 || (args.has("out") == args.has("captures")))
    throw Error("usage: glaze render SCENE [--camera NAME|all] --out FILE.exr|DIR, or glaze render SCENE --captures DIR");
  const std::string integrator = args.text("integrator", "path");
  if (integrator != "path" && integrator != "sh") throw Error("unknown integrator '" + integrator + "' (known: path, sh)");
  if (integrator != "sh" && (args.has("lmax") || args.has("ss") || args.has("ss-refine")))
    throw Error("--lmax, --ss and --ss-refine apply to --integrator sh");
  // A capture set's pixels must have the one K x K footprint that the fits model
  // (invert-fit --pixel-footprint).
  if (args.has("ss-refine") && args.has("captures"))
    throw Error("--ss-refine makes pixels' footprints differ, which the fits do not model: leave it out with --captures");
  if (integrator == "sh" && (args.has("spp") || args.has("time-budget") || args.has("estimator") || args.has("max-depth")))
    throw Error("--spp, --time-budget, --estimator and --max-depth apply to --integrator path");
  if (args.has("holdout") && !args.has("captures")) throw Error("--holdout applies to --captures");
  if ((args.has("exposure") || args.has("tone-map")) && !is_picture(args.text("out", "")))
    throw Error("--exposure and --tone-map apply to a picture: --out FILE.png (an EXR keeps the radiance)");

  const Scene scene = load_scene(args.positionals()[0]);
  const EnvironmentSpec spec = environment_spec(scene, args);
  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);
  const RayTracer ray_tracer(scene);

  PathTracerOptions path_options;
  path_options.max_depth = static_cast<int>(args.integer("max-depth", 8, 1, 1000));
  path_options.estimator = parse_direct_light_estimator(args.text("estimator", "mis"));
  path_options.black_background = args.has("captures");
  const PathTracer tracer(scene, ray_tracer, environment, path_options);

  RenderOptions options;
  options.spp = static_cast<int>(args.integer("spp", 64, 1, 1 << 20));
  options.time_budget = args.real("time-budget", 0.0f);
  if (options.time_budget < 0.0) throw Error("option --time-budget must be >= 0 seconds");
  options.seed = static_cast<uint64_t>(args.integer("seed", 0, 0, std::numeric_limits<long>::max()));
  options.threads = static_cast<int>(args.integer("threads", 0, 0, 1024));
  options.progress = isatty(STDERR_FILENO);
  if (args.has("time-budget") && !args.has("spp")) options.spp = 4;  // samples per pass

  if (scene.cameras.empty()) throw Error(scene.path + ": the scene has no camera");
  std::optional<ShIntegratorOptions> sh;
  if (integrator == "sh") {
    sh.emplace();
    sh->lmax = static_cast<int>(args.integer("lmax", 4, 0, kShMaxLmax));
    sh->supersampling = static_cast<int>(args.integer("ss", 2, 1, 64));
    sh->refined_supersampling = static_cast<int>(args.integer("ss-refine", 0, 0, 64));
    sh->black_background = args.has("captures");
    sh->threads = options.threads;
  }
  DisplaySettings display;
  display.exposure_ev = args.real("exposure", 0.0f);
  display.tone_mapping = parse_tone_mapping(args.text("tone-map", "filmic"));
  const Job job{scene, spec, environment, ray_tracer, tracer, options, sh,
                args.has("res") ? std::optional(args.resolution("res", {0, 0})) : std::nullopt, display};

  if (args.has("captures")) {
    write_captures(job, args.text("captures", ""), args.names("holdout"), environment);
    return 0;
  }
  const std::string camera_name = args.text("camera", scene.cameras.front().name);
  const std::string out = args.text("out", "");
  if (camera_name == "all") {
    std::filesystem::create_directories(out);
    for (const CameraSpec& camera : scene.cameras) job.render_to(camera, (std::filesystem::path(out) / (camera.name + ".exr")).string());
  } else {
    job.render_to(scene.camera(camera_name), out);
  }
  return 0;
}

}  // namespace glaze
