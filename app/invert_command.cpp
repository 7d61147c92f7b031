// invert_command.cpp: `glaze invert-fit`: recovers a material from a capture set under
// known lighting (DESIGN §5), and writes fit.json, the solver's report, re-renders of
// every view (and of held-out views) with the recovered material, and residual images.
//
//   --mode material   homogeneous R0 and RGB Rd (nested: Ceres over R0, closed-form Rd)
//   --mode texture    R0 and a diffuse texture Rd(u, v), unknown texels alpha 0
#include "app/arguments.h"
#include "app/commands.h"
#if GLAZE_HAVE_PREVIEW
#include "app/fit_preview.h"
#include "app/preview_window.h"
#endif
#include "inverse/capture_scene.h"
#include "inverse/joint_fit.h"
#include "inverse/lighting_fit.h"
#include "inverse/material_fit.h"
#include "inverse/samples.h"
#include "inverse/texture_fit.h"
#include "renderer/display.h"
#include "renderer/error.h"
#include "renderer/image_error.h"
#include "renderer/latlong.h"
#include "renderer/sh.h"
#include "renderer/sh_integrator.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <tuple>

namespace glaze {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

nlohmann::json rgb_json(const RGB& c) { return {c[0], c[1], c[2]}; }

nlohmann::json drops_json(const DropCounts& d) {
  return {{"grazing", d.grazing}, {"silhouette", d.silhouette}, {"non_finite", d.non_finite},
          {"saturated", d.saturated}, {"masked", d.masked}, {"hidden", d.hidden}};
}

// Re-renders `frames` with the recovered material and writes them with residual images
// (observed - predicted); returns per-view figures.
nlohmann::json rerender(const std::vector<CaptureFrame>& frames, const Scene& scene, const RayTracer& tracer,
                        const Environment& environment, int lmax, int footprint, const std::filesystem::path& out,
                        const std::string& prefix) {
  nlohmann::json views = nlohmann::json::array();
  for (size_t f = 0; f < frames.size(); ++f) {
    const PinholeCamera& camera = frames[f].camera;
    const Image observed = read_image(frames[f].file_path);
    if (observed.width != camera.width || observed.height != camera.height)
      throw Error(frames[f].file_path + ": the image's size differs from its camera in transforms.json");
    // The fit's own model of a pixel (its footprint), so residuals show what the fit saw.
    const Image predicted = render_sh(scene, tracer, environment, camera, {lmax, footprint, true, 0});
    Image residual(camera.width, camera.height);
    for (size_t i = 0; i < residual.pixels.size(); ++i) residual.pixels[i] = observed.pixels[i] - predicted.pixels[i];
    char name[64];
    std::snprintf(name, sizeof name, "%s_%03zu.exr", prefix.c_str(), f);
    const std::string render_file = (out / ("render_" + std::string(name))).string();
    const std::string residual_file = (out / ("residual_" + std::string(name))).string();
    write_image(render_file, predicted, {{"glaze:integrator", "sh"}, {"glaze:lmax", std::to_string(lmax)}});
    write_image(residual_file, residual);
    nlohmann::json view = {{"file", frames[f].file_path}, {"camera", camera.name}, {"render", render_file}, {"residual", residual_file}};
    const std::vector<uint8_t> mask = interior_mask(tracer, camera);
    try {
      view["relative_rmse"] = image_error(predicted, observed, mask).relative_rmse;
    } catch (const Error&) {
      view["relative_rmse"] = nullptr;  // the object covers no whole pixel in this view
    }
    views.push_back(view);
  }
  return views;
}

// What every mode starts from: the capture set, its object in the renderer's ray
// tracer, and the samples.
struct FitInputs {
  CaptureSet captures;
  Scene scene;
  std::unique_ptr<RayTracer> tracer;
  SampleSet samples;
};

FitInputs prepare_inputs(const Arguments& args, nlohmann::json& stage_seconds) {
  FitInputs in;
  in.captures = read_transforms(args.positionals()[0]);
  in.scene = capture_object_scene(in.captures, PolishedMaterial(0.04f, RGB::Constant(0.5f)));
  in.tracer = std::make_unique<RayTracer>(in.scene);
  SampleOptions sample_options;
  sample_options.min_cos = args.real("min-cos", sample_options.min_cos);
  sample_options.points = static_cast<int>(args.integer("points", 0, 0, 1 << 26));
  sample_options.seed = static_cast<uint64_t>(args.integer("seed", 0, 0, 1L << 40));
  const auto stage = Clock::now();
  in.samples = collect_samples(in.captures, *in.tracer, in.scene, sample_options);
  stage_seconds["samples"] = seconds_since(stage);
  const DropCounts dropped = in.samples.total_dropped();
  std::printf("%zu samples from %zu views (dropped: %zu grazing, %zu silhouette, %zu not finite, %zu saturated, %zu masked, %zu hidden)\n",
              in.samples.samples.size(), in.captures.frames.size(), dropped.grazing, dropped.silhouette, dropped.non_finite,
              dropped.saturated, dropped.masked, dropped.hidden);
  return in;
}

// Writes fit.json (and the solver's report) atomically.
void write_fit(const std::filesystem::path& out, const nlohmann::json& result, const std::string& solver_report) {
  if (!solver_report.empty()) {
    std::ofstream report(out / "solver.txt");
    report << solver_report;
    if (!report) throw Error((out / "solver.txt").string() + ": could not be written");
  }
  const std::filesystem::path target = out / "fit.json", temporary = out / ".fit.json.tmp";
  {
    std::ofstream file(temporary);
    file << result.dump(2) << '\n';
    if (!file) throw Error(target.string() + ": could not be written");
  }
  std::filesystem::rename(temporary, target);
}

// Re-renders the inputs and the held-out views (CAPTURES/holdout or --holdout-dir).
void write_renders(const Arguments& args, const FitInputs& in, const Scene& scene, const Environment& environment, int lmax,
                   int footprint, const std::filesystem::path& out, nlohmann::json& result) {
  result["renders"] = rerender(in.captures.frames, scene, *in.tracer, environment, lmax, footprint, out, "view");
  const std::filesystem::path holdout = args.has("holdout-dir") ? std::filesystem::path(args.text("holdout-dir", ""))
                                                                : std::filesystem::path(in.captures.directory) / "holdout";
  if (args.has("holdout-dir") || std::filesystem::exists(holdout / "transforms.json")) {
    const CaptureSet held_out = read_transforms(holdout.string());
    result["holdout"] = rerender(held_out.frames, scene, *in.tracer, environment, lmax, footprint, out, "holdout");
  }
}

// Defaults that match how glaze rendered the captures, when transforms.json says: the sh
// integrator's K x K sub-pixel grid is exactly a footprint of K, and its lmax is the
// band its diffuse term was truncated at. Otherwise a footprint of 4 (a camera's, or the
// path tracer's, box-filtered pixel) and `otherwise_lmax`.
std::pair<int, int> capture_defaults(const CaptureSet& captures, int otherwise_lmax) {
  const nlohmann::json& r = captures.renderer;
  auto integer = [&](const char* key, int low, int high, int fallback) {
    if (!r.contains(key) || !r[key].is_number_integer()) return fallback;
    const int value = r[key].get<int>();
    return value >= low && value <= high ? value : fallback;
  };
  if (r.is_object() && r.value("integrator", "") == "sh") return {integer("ss", 1, 16, 4), integer("lmax", 0, kShMaxLmax, otherwise_lmax)};
  return {4, otherwise_lmax};
}

// The known material of --mode lighting: --R0 and --Rd, else the capture set's.
PolishedMaterial known_material(const Arguments& args, const CaptureSet& captures) {
  float R0 = -1.0f;
  RGB Rd = RGB::Constant(-1.0f);
  if (captures.material.contains("R0")) R0 = captures.material["R0"].get<float>();
  if (captures.material.contains("Rd"))
    for (int c = 0; c < 3; ++c) Rd[c] = captures.material["Rd"][c].get<float>();
  R0 = args.real("R0", R0);
  if (args.has("Rd")) {
    const std::vector<float> values = args.reals("Rd");
    if (values.size() != 3) throw Error("option --Rd needs three comma-separated numbers r,g,b");
    Rd = RGB(values[0], values[1], values[2]);
  }
  if (R0 < 0.0f || (Rd < 0.0f).any()) {
    const std::string missing = R0 < 0.0f ? (args.has("R0") ? "--R0 is negative" : "R0 is not given")
                                          : (args.has("Rd") ? "--Rd is negative" : "Rd is not given");
    throw Error(missing + ": --mode lighting needs the object's material, from the \"material\" of " + captures.directory +
                "/transforms.json or --R0 x --Rd r,g,b (each in [0, 1])");
  }
  return PolishedMaterial(R0, Rd);  // validates the ranges
}

#if GLAZE_HAVE_PREVIEW
// --preview: every capture view, observed, for the window.
void begin_preview(FitPreview* preview, const FitInputs& in, int lmax, int footprint) {
  if (!preview) return;
  std::vector<FitPreview::View> views;
  for (const CaptureFrame& frame : in.captures.frames) views.push_back({frame.camera, read_image(frame.file_path)});
  preview->begin(std::move(views), *in.tracer, lmax, footprint);
}

// The object with material (R0, Rd), under `environment`, labelled for the title.
FitPreviewState preview_state(const Scene& object, float R0, const RGB& Rd,
                              std::function<std::shared_ptr<const Environment>()> environment, const std::string& label) {
  auto scene = std::make_shared<Scene>(object);
  for (SceneMaterial& m : scene->materials) m.R0 = R0, m.Rd = Rd;
  return {scene, std::move(environment), label};
}

std::string iterate_label(const FitIterate& it) {
  char text[160];
  std::snprintf(text, sizeof text, "iteration %d: R0 %.5f, Rd %.4f %.4f %.4f, cost %.4g", it.iteration, it.R0, it.Rd[0],
                it.Rd[1], it.Rd[2], it.cost);
  return text;
}

// Waits, when the scope ends, until the preview has drawn the last state: its render
// thread reads the fit's geometry and lighting, which die with the scope.
struct FinishPreview {
  FitPreview* preview;
  ~FinishPreview() {
    if (preview) preview->finish();
  }
};
#else
struct FitPreview;
void begin_preview(FitPreview*, const FitInputs&, int, int) {}
struct FinishPreview {
  FitPreview* preview;
};
#endif

// A borrowed environment as the preview's lighting function.
std::function<std::shared_ptr<const Environment>()> borrowed(const Environment& environment) {
  return [&environment] { return std::shared_ptr<const Environment>(std::shared_ptr<const Environment>{}, &environment); };
}

// --mode lighting: the lighting from an object of known material; --mode joint: the
// material and the lighting together.
int invert_lighting(const Arguments& args, const std::filesystem::path& out, bool joint, FitPreview* preview) {
  const auto start = Clock::now();
  nlohmann::json stage_seconds;
  FitInputs in = prepare_inputs(args, stage_seconds);
  const int lmax = static_cast<int>(args.integer("lmax", 4, 0, 8));
  const int footprint = static_cast<int>(args.integer("pixel-footprint", capture_defaults(in.captures, 4).first, 1, 16));
  LightingFitOptions options;
  std::tie(options.width, options.height) = args.resolution("env-res", {256, 128});
  options.ridge = args.real("ridge", float(options.ridge));
  // The joint fit separates material from lighting by the variation within a texel of
  // the solved map, so it takes a finer one (128x64 at 512x512 captures: still dozens of
  // samples per texel); lighting alone is steadier on the coarser default.
  const std::pair<int, int> solve_default = joint ? std::pair(128, 64) : std::pair(options.solve_width, options.solve_height);
  std::tie(options.solve_width, options.solve_height) = args.resolution("solve-res", solve_default);

  auto stage = Clock::now();
  const LightingData data = gather_lighting_data(in.samples, in.captures, *in.tracer, lmax, footprint);
  stage_seconds["gather"] = seconds_since(stage);
  begin_preview(preview, in, lmax, footprint);
  const FinishPreview finish_preview{preview};
  stage = Clock::now();
  std::optional<JointFit> joint_fit;
  FitObserver observer;
#if GLAZE_HAVE_PREVIEW
  // The lighting at each iterate is solved on the preview's thread, for the newest only.
  if (preview)
    observer = [&](const FitIterate& it) {
      preview->show(preview_state(in.scene, it.R0, it.Rd, [&data, &options, it] {
        return std::make_shared<const Environment>(fit_lighting(data, it.R0, it.Rd, options).map, EnvironmentOptions{}, "lighting at the iterate");
      }, iterate_label(it)));
    };
#endif
  if (joint) joint_fit = fit_joint(data, options, static_cast<int>(args.integer("max-iterations", 100, 1, 10000)), observer);
  const PolishedMaterial material = joint ? PolishedMaterial(joint_fit->R0, joint_fit->Rd) : known_material(args, in.captures);
  const LightingFit fit = joint ? joint_fit->lighting : fit_lighting(data, material.R0(), material.Rd(), options);
  stage_seconds["fit"] = seconds_since(stage);

  std::filesystem::create_directories(out);
  const std::string map_file = (out / "lighting.exr").string(), mask_file = (out / "lighting_coverage.png").string();
  write_image(map_file, fit.map, {{"glaze:lmax", std::to_string(lmax)}});
  Image mask(fit.map.width, fit.map.height);
  for (size_t t = 0; t < fit.covered.size(); ++t)
    for (int c = 0; c < 3; ++c) mask.pixels[3 * t + c] = fit.covered[t];
  write_image(mask_file, mask);
  nlohmann::json L = nlohmann::json::array();
  for (const RGBd& v : fit.coefficients.values) L.push_back({v[0], v[1], v[2]});
  nlohmann::json result = {{"mode", joint ? "joint" : "lighting"}, {"R0", material.R0()}, {"Rd", rgb_json(material.Rd())}, {"lmax", lmax},
                           {"L_lm", L}, {"condition_number", fit.condition}, {"ridge", options.ridge},
                           {"normal_coverage", data.normal_coverage}, {"map", map_file}, {"coverage_mask", mask_file},
                           {"map_resolution", {options.width, options.height}}, {"solve_resolution", {options.solve_width, options.solve_height}}, {"covered_fraction", fit.covered_fraction},
                           {"mirror_share", fit.mirror_share}, {"multi_view_fraction", fit.multi_view_fraction},
                           {"solve", fit.map_consistent ? "map-consistent" : "sh-least-squares"}, {"samples", in.samples.samples.size()},
                           {"dropped", drops_json(in.samples.total_dropped())}, {"pixel_footprint", footprint}};
  if (fit.condition > 1e6)
    warn("the lighting system is ill-conditioned (condition number " + std::to_string(fit.condition) + ", normals cover " +
         std::to_string(int(100 * data.normal_coverage)) + "% of the sphere): more views would constrain it; the ridge keeps it finite");
  if (joint) {
    result["iterations"] = joint_fit->iterations;
    result["converged"] = joint_fit->converged;
    result["rms"] = joint_fit->rms;
    result["solver"] = joint_fit->brief_report;
  }
  if (options.solve_width > 0 && !fit.map_consistent)
    warn("only " + std::to_string(int(100 * fit.multi_view_fraction)) +
         "% of the reflected directions are seen from two or more views: the mirror and the diffuse term cannot be "
         "told apart there, so L_lm comes from the SH-only least squares (less accurate where the mirror dominates); "
         "add views from other directions");
  if (fit.mirror_share < 0.1)
    warn("the mirror reflection carries only " + std::to_string(int(100 * fit.mirror_share)) +
         "% of the observed light: the object is matte-like, so only the low frequencies (the SH part) are reliable; "
         "the high-resolution map is noisy");

  // Against the set's own lighting, when it names one: what a known-truth experiment checks.
  if (const std::optional<EnvironmentSpec> truth = capture_environment(in.captures)) {
    const Environment environment = make_environment(truth->source, truth->options, truth->width, truth->height);
    const ShCoefficients& reference = environment.sh(lmax);
    double worst = 0.0;
    for (int i = 0; i < sh_count(std::min(lmax, 2)); ++i)
      worst = std::max(worst, ((fit.coefficients.values[i] - reference.values[i]).abs() / reference.values[0].abs().max(1e-12)).maxCoeff());
    result["reference_L_lm_error_l2"] = worst;  // max |L_lm - true| / L00 over l <= 2
    // The absolute scale: recovered over true L00, per channel.
    result["reference_scale"] = rgb_json((fit.coefficients.values[0] / reference.values[0]).cast<float>());
    if (!in.captures.material.is_null()) result["reference_material"] = in.captures.material;
    for (const auto& [w, h] : {std::pair(64, 32), std::pair(128, 64), std::pair(256, 128)}) {
      if (options.width % w != 0 || options.height % h != 0) continue;
      int cells = 0;
      const double error = map_error(fit, environment, w, h, &cells);
      result["reference_map_error"][std::to_string(w) + "x" + std::to_string(h)] = {{"relative_rmse", error}, {"cells", cells}};
    }
  }

  stage = Clock::now();
  // Shared with the preview's state, which may outlive this scope's locals.
  const auto recovered = std::make_shared<const Environment>(fit.map, EnvironmentOptions{}, "recovered lighting");
  for (SceneMaterial& m : in.scene.materials) m.R0 = material.R0(), m.Rd = material.Rd();
#if GLAZE_HAVE_PREVIEW
  if (preview) preview->show({std::make_shared<Scene>(in.scene), [recovered] { return recovered; }, "recovered lighting"});
#endif
  write_renders(args, in, in.scene, *recovered, lmax, footprint, out, result);
  stage_seconds["renders"] = seconds_since(stage);
  result["stage_seconds"] = stage_seconds;
  result["seconds"] = seconds_since(start);
  write_fit(out, result, joint ? joint_fit->full_report : "");
  if (joint)
    std::printf("joint: R0 = %.5f, Rd = %.5f %.5f %.5f (%d iterations, %s)\n", material.R0(), material.Rd()[0],
                material.Rd()[1], material.Rd()[2], joint_fit->iterations, joint_fit->converged ? "converged" : "NOT converged");
  std::printf("lighting: lmax %d, condition number %.3g, normals cover %.0f%%, map %dx%d covered %.1f%%, mirror share %.1f%%\n",
              lmax, fit.condition, 100 * data.normal_coverage, options.width, options.height, 100 * fit.covered_fraction,
              100 * fit.mirror_share);
  if (result.contains("reference_L_lm_error_l2"))
  {
    std::printf("against the true lighting: L_lm (l <= 2) max error %.3f%% of L00", 100 * result["reference_L_lm_error_l2"].get<double>());
    if (result.contains("reference_map_error") && result["reference_map_error"].contains("64x32"))
      std::printf("; map relative RMSE at 64x32 %.2f%% over %d covered cells",
                  100 * result["reference_map_error"]["64x32"]["relative_rmse"].get<double>(),
                  result["reference_map_error"]["64x32"]["cells"].get<int>());
    std::printf("\n");
  }
  std::printf("wrote %s (%.2f s)\n", (out / "fit.json").string().c_str(), seconds_since(start));
  return 0;
}

// --mode material and texture: the material under known lighting.
int invert_material(const Arguments& args, const std::filesystem::path& out, const std::string& mode, FitPreview* preview) {
  const auto start = Clock::now();
  nlohmann::json stage_seconds;

  // The known lighting: the set's, or --env.
  FitInputs in = prepare_inputs(args, stage_seconds);
  const CaptureSet& captures = in.captures;
  Scene& scene = in.scene;
  const RayTracer& tracer = *in.tracer;
  const SampleSet& samples = in.samples;
  std::optional<EnvironmentSpec> spec = capture_environment(captures);
  if (args.has("env")) spec = EnvironmentSpec{args.text("env", ""), spec ? spec->options : EnvironmentOptions{}};
  if (!spec)
    throw Error(captures.directory + "/transforms.json names no environment: --mode " + mode +
                " needs the lighting; give --env FILE|procedural:NAME");
  spec->options.scale = args.real("env-scale", spec->options.scale);
  spec->options.rotation_degrees = args.real("env-rotation", spec->options.rotation_degrees);
  const Environment environment = make_environment(spec->source, spec->options, spec->width, spec->height);
  const DropCounts dropped = samples.total_dropped();

  // lmax 16 by default: the SH truncation of the diffuse term at lmax 4 is 1-3% under
  // point-lit rooms (measured by `glaze convergence`), and it would bias Rd as much.
  const auto [default_footprint, default_lmax] = capture_defaults(captures, 16);
  const int lmax = static_cast<int>(args.integer("lmax", default_lmax, 0, kShMaxLmax));
  auto stage = Clock::now();
  const int footprint = static_cast<int>(args.integer("pixel-footprint", default_footprint, 1, 16));
  const std::vector<ShadingTerms> terms = shading_terms(samples, captures, tracer, environment, lmax, footprint);
  stage_seconds["shading_terms"] = seconds_since(stage);
  begin_preview(preview, in, lmax, footprint);
  const FinishPreview finish_preview{preview};

  MaterialFitOptions fit_options;
  fit_options.loss = RobustLoss::parse(args.text("loss", "none"), args.real("loss-scale", 0.05f));
  fit_options.max_iterations = static_cast<int>(args.integer("max-iterations", 100, 1, 10000));
#if GLAZE_HAVE_PREVIEW
  if (preview)
    fit_options.observer = [&](const FitIterate& it) {
      preview->show(preview_state(scene, it.R0, it.Rd, borrowed(environment), iterate_label(it)));
    };
#endif
  stage = Clock::now();
  MaterialFit fit = fit_material(samples.samples, terms, {}, 1, {}, fit_options);
  std::filesystem::create_directories(out);
  nlohmann::json result = {{"mode", mode}, {"R0", fit.R0}, {"lmax", lmax}, {"loss", args.text("loss", "none")},
                           {"pixel_footprint", footprint}};
  std::optional<RecoveredTexture> texture;
  if (mode == "material") {
    result["Rd"] = rgb_json(fit.Rd[0]);
    result["Rd_unclamped"] = rgb_json(fit.Rd_unclamped[0]);
    // A channel no sample's diffuse term reaches (R0 = 1: a pure mirror) is unknown.
    result["Rd_constrained"] = nlohmann::json::array();
    for (int c = 0; c < 3; ++c) {
      const bool constrained = fit.constraint[0][c] > 1e-12 * std::max(1.0, fit.constraint[0].maxCoeff());
      result["Rd_constrained"].push_back(constrained);
      if (!constrained)
        warn(std::string("Rd ") + "RGB"[c] + " is not constrained by the data (no diffuse reflection seen: R0 = " +
             std::to_string(fit.R0) + "); it is reported as 0");
    }
  } else {
    const auto [width, height] = args.resolution("texture-res", {256, 128});
    result["homogeneous"] = {{"R0", fit.R0}, {"Rd", rgb_json(fit.Rd[0])}};
    fit_options.observer = nullptr;  // its per-texel iterates are not one material to show
    texture = fit_texture(samples.samples, terms, width, height, fit, fit_options);
    fit = texture->fit;
    result["R0"] = fit.R0;
    const std::string file = (out / "texture.exr").string();
    write_image(file, texture->Rd, {{"glaze:R0", std::to_string(fit.R0)}}, texture->known);
    result["texture"] = file;
    result["texture_resolution"] = {width, height};
    result["coverage"] = texture->coverage;
    if (captures.material.contains("texture")) {
      // The set's own texture, when it is a file (relative paths against the set): what
      // a known-truth experiment compares with. Not fatal when it cannot be read.
      RGB factor = RGB::Ones();
      if (captures.material.contains("Rd"))
        for (int c = 0; c < 3; ++c) factor[c] = captures.material["Rd"][c].get<float>();
      std::filesystem::path reference(captures.material["texture"].get<std::string>());
      if (reference.is_relative()) reference = std::filesystem::path(captures.directory) / reference;
      try {
        result["texture_rmse"] = texture_rmse(*texture, read_image(reference.string()), factor);
      } catch (const Error& error) {
        warn(std::string("the capture set's texture cannot be compared: ") + error.what());
      }
    }
  }
  stage_seconds["fit"] = seconds_since(stage);
  result["rms"] = fit.rms;
  result["samples"] = samples.samples.size();
  result["dropped"] = drops_json(dropped);
  result["iterations"] = fit.iterations;
  result["converged"] = fit.converged;
  result["solver"] = fit.brief_report;
  if (!captures.material.is_null()) result["reference_material"] = captures.material;

  // Per-view residuals over the samples, then re-renders of the inputs and held-out views.
  nlohmann::json per_view = nlohmann::json::array();
  {
    std::vector<double> squared(captures.frames.size(), 0.0), observed(captures.frames.size(), 0.0);
    for (size_t k = 0; k < samples.samples.size(); ++k) {
      const Sample& s = samples.samples[k];
      const RGB& Rd = fit.Rd[texture ? texel_of(s.uv, texture->Rd.width, texture->Rd.height) : 0];
      squared[s.frame] += (s.observed - predict(terms[k], fit.R0, Rd)).cast<double>().square().sum();
      observed[s.frame] += s.observed.cast<double>().square().sum();
    }
    for (size_t f = 0; f < captures.frames.size(); ++f) {
      const double n = 3.0 * std::max<size_t>(samples.per_frame[f], 1);
      per_view.push_back({{"file", captures.frames[f].file_path}, {"samples", samples.per_frame[f]},
                          {"dropped", drops_json(samples.dropped[f])}, {"rms", std::sqrt(squared[f] / n)},
                          {"relative_rms", observed[f] > 0 ? std::sqrt(squared[f] / observed[f]) : 0.0}});
    }
  }
  result["views"] = per_view;

  stage = Clock::now();
  for (SceneMaterial& m : scene.materials) {
    m.R0 = fit.R0;
    m.Rd = texture ? RGB::Ones() : fit.Rd[0];
    if (texture) {
      m.texture = 0;  // unknown texels render black: nothing is invented
      scene.textures = {Texture{"recovered texture", texture->Rd}};
    }
  }
#if GLAZE_HAVE_PREVIEW
  if (preview) preview->show({std::make_shared<Scene>(scene), borrowed(environment), "final: R0 " + std::to_string(fit.R0)});
#endif
  write_renders(args, in, scene, environment, lmax, footprint, out, result);
  stage_seconds["renders"] = seconds_since(stage);
  result["stage_seconds"] = stage_seconds;
  result["seconds"] = seconds_since(start);
  write_fit(out, result, fit.full_report);

  std::printf("R0 = %.5f", fit.R0);
  if (!texture) std::printf(", Rd = %.5f %.5f %.5f", fit.Rd[0][0], fit.Rd[0][1], fit.Rd[0][2]);
  else std::printf(", texture %dx%d, %.1f%% of texels known", texture->Rd.width, texture->Rd.height, 100 * texture->coverage);
  if (result.contains("texture_rmse")) std::printf(", texel RMSE against the reference %.4f", result["texture_rmse"].get<double>());
  std::printf("  (rms %.4g, %d iterations, %s)\n", fit.rms, fit.iterations, fit.converged ? "converged" : "NOT converged");
  if (!captures.material.is_null() && captures.material.contains("R0")) {
    std::printf("true R0 = %.5f", captures.material["R0"].get<double>());
    if (captures.material.contains("Rd") && !texture)
      std::printf(", Rd = %.5f %.5f %.5f", captures.material["Rd"][0].get<double>(), captures.material["Rd"][1].get<double>(),
                  captures.material["Rd"][2].get<double>());
    std::printf("\n");
  }
  std::printf("wrote %s (%.2f s)\n", (out / "fit.json").string().c_str(), seconds_since(start));
  return 0;
}

}  // namespace

int command_invert_fit(const std::vector<std::string>& raw) {
  const Arguments args(raw, {"mode", "out", "points", "min-cos", "loss", "loss-scale", "lmax", "texture-res", "env",
                             "env-scale", "env-rotation", "holdout", "holdout-dir", "seed", "max-iterations", "pixel-footprint", "R0",
                             "Rd", "env-res", "ridge", "solve-res", "frames", "screenshot", "exposure", "tone-map"},
                       {"preview"});
  if (args.positionals().size() != 1 || !args.has("out") || !args.has("mode"))
    throw Error("usage: glaze invert-fit DIR/transforms.json --mode material|texture|lighting|joint --out DIR (see `glaze help`)");
  const std::string mode = args.text("mode", "");
  if (mode != "material" && mode != "texture" && mode != "lighting" && mode != "joint")
    throw Error("unknown mode '" + mode + "' (known: material, texture, lighting, joint)");
  if (mode != "texture" && args.has("texture-res")) throw Error("--texture-res applies to --mode texture");
  const bool lighting = mode == "lighting" || mode == "joint";
  if (!lighting && (args.has("env-res") || args.has("ridge") || args.has("solve-res")))
    throw Error("--env-res, --solve-res and --ridge apply to --mode lighting and joint");
  if (mode != "lighting" && (args.has("R0") || args.has("Rd"))) throw Error("--R0 and --Rd give the known material of --mode lighting");
  if (lighting && (args.has("loss") || args.has("loss-scale")))
    throw Error("--loss and --loss-scale apply to --mode material and texture (the lighting solve is linear least squares)");
  // Every option's value is checked here, before the (long) sampling: a typo fails at once.
  if (args.has("holdout"))
    throw Error("--holdout names cameras of `glaze render --captures`; the held-out captures of invert-fit are "
                "--holdout-dir DIR (default: CAPTURES/holdout)");
  if (args.has("screenshot") && std::filesystem::path(args.text("screenshot", "")).extension() != ".png")
    throw Error("--screenshot " + args.text("screenshot", "") + ": the screenshot is a PNG (name it FILE.png)");
  if (args.has("loss-scale") && !args.has("loss")) throw Error("--loss-scale goes with --loss huber|cauchy");
  RobustLoss::parse(args.text("loss", "none"), args.real("loss-scale", 0.05f));
  args.integer("lmax", 0, 0, lighting ? 8 : kShMaxLmax);
  args.integer("pixel-footprint", 1, 1, 16);
  args.integer("max-iterations", 100, 1, 10000);
  args.integer("points", 0, 0, 1 << 26);
  args.real("min-cos", 0.2f);
  args.resolution("texture-res", {256, 128});
  args.resolution("env-res", {256, 128});
  args.resolution("solve-res", {64, 32});
  args.real("ridge", 0.0f);
  if (args.has("preview")) {
    args.integer("frames", 1, 1, 1 << 20);
    parse_tone_mapping(args.text("tone-map", "filmic"));
    args.real("exposure", 0.0f);
  }
  const std::filesystem::path out(args.text("out", ""));
  auto invert = [&](FitPreview* preview) {
    return lighting ? invert_lighting(args, out, mode == "joint", preview) : invert_material(args, out, mode, preview);
  };
  if (!args.has("preview")) {
    if (args.has("frames") || args.has("screenshot") || args.has("exposure") || args.has("tone-map"))
      throw Error("--frames, --screenshot, --exposure and --tone-map apply to --preview");
    return invert(nullptr);
  }
#if GLAZE_HAVE_PREVIEW
  require_display();
  if (args.has("screenshot") && !args.has("frames")) throw Error("--screenshot needs --frames N (the frame to capture)");
  DisplaySettings display;
  display.exposure_ev = args.real("exposure", 0.0f);
  display.tone_mapping = parse_tone_mapping(args.text("tone-map", "filmic"));
  FitPreview preview(display);
  int status = 1;
  preview.run([&] { status = invert(&preview); }, static_cast<int>(args.integer("frames", 0, 1, 1 << 20)),
              args.text("screenshot", ""));
  return status;
#else
  throw Error(kNoPreview);
#endif
}

}  // namespace glaze
