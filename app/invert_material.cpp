// invert_material.cpp: `invert-fit --mode material` (homogeneous R0 and RGB Rd: Ceres
// over R0, closed-form Rd, docs/design.md §5) and `--mode texture` (R0 and a diffuse texture
// Rd(u, v), unknown texels alpha 0) under known lighting: fit.json, the solver's report,
// per-view residuals, re-renders of every view and held-out view, texture.exr.
#include "app/invert_fit.h"
#include "inverse/capture_scene.h"
#include "inverse/fit_diagnostics.h"
#include "inverse/material_fit.h"
#include "inverse/texture_fit.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/sh.h"

#include <algorithm>
#include <cstdio>
#include <optional>

namespace glaze::invert_fit {

// --mode material and texture: the material under known lighting.
int invert_material(const InvertFitOptions& args, const std::filesystem::path& out_folder, const std::string& mode,
                    FitPreview* preview) {
  const auto start = Clock::now();
  nlohmann::json stage_seconds;

  // The known lighting: the set's, or --env.
  FitInputs in = prepare_inputs(args, stage_seconds);
  const CaptureSet& captures = in.captures;
  Scene& scene = in.scene;
  const RayTracer& tracer = *in.tracer;
  const SampleSet& samples = in.samples;
  std::optional<EnvironmentSpec> spec = capture_environment(captures);
  if (args.environment.source) {
    spec = EnvironmentSpec{*args.environment.source, spec ? spec->options : EnvironmentOptions{}};
    spec->options.format = EnvironmentFormat::automatic;  // the set's format describes the set's file
  }
  if (!spec)
    throw Error(captures.file + " names no environment: --mode " + mode +
                " needs the lighting; give --env FILE|procedural:NAME");
  if (args.environment.format)
    spec->options.format = parse_environment_format(*args.environment.format, "--env-format");
  spec->options.scale = args.environment.scale.value_or(spec->options.scale);
  spec->options.rotation_degrees = args.environment.rotation_degrees.value_or(spec->options.rotation_degrees);
  const Environment environment = make_environment(spec->source, spec->options, spec->width, spec->height);
  const DropCounts dropped = samples.total_dropped();

  // kFullBandDiffuseLmax by default: the SH truncation of the diffuse term at lmax 4 is
  // 1-3% under point-lit rooms (measured by `glaze convergence`), and it would bias Rd
  // as much.
  const auto [default_footprint, default_lmax] = capture_defaults(captures, kFullBandDiffuseLmax);
  const int lmax = args.lmax.value_or(default_lmax);
  auto stage = Clock::now();
  const int footprint = args.pixel_footprint.value_or(default_footprint);
  const std::vector<ShadingTerms> terms = shading_terms(samples, captures, tracer, environment, lmax, footprint);
  stage_seconds["shading_terms"] = seconds_since(stage);
  begin_preview(preview, in, lmax, footprint);
  const FinishPreview finish_preview{preview};

  MaterialFitOptions fit_options;
  fit_options.loss = RobustLoss::parse(args.loss, args.loss_scale);
  fit_options.max_iterations = args.max_iterations.value_or(100);
  if (preview)
    fit_options.observer = [&](const FitIterate& it) {
      show_in_preview(preview, scene, it.R0, it.Rd, borrowed(environment), iterate_label(it));
    };
  stage = Clock::now();
  // 8-bit captures weigh their samples by their codes' rounding (samples.h); others all 1.
  std::vector<float> weights;
  for (const Sample& sample : samples.samples) weights.push_back(sample.weight);
  if (std::all_of(weights.begin(), weights.end(), [](float w) { return w == 1.0f; })) weights.clear();
  MaterialFit fit = fit_material(samples.samples, terms, {}, 1, weights, fit_options);
  OutputFolder out(out_folder, "fit.json", "fit output");
  nlohmann::json result = {
      {"mode", mode}, {"R0", fit.R0}, {"lmax", lmax}, {"loss", args.loss}, {"pixel_footprint", footprint}};
  std::optional<RecoveredTexture> texture;
  if (mode == "material") {
    result["Rd"] = rgb_json(fit.Rd[0]);
    result["Rd_unclamped"] = rgb_json(fit.Rd_unclamped[0]);
    const MaterialDiagnostics diagnostics = diagnose_material(fit);
    result["Rd_constrained"] = diagnostics.Rd_constrained;
    for (const std::string& warning : diagnostics.warnings) warn(warning);
  } else {
    const auto [width, height] = args.texture_resolution;
    result["homogeneous"] = {{"R0", fit.R0}, {"Rd", rgb_json(fit.Rd[0])}};
    fit_options.observer = nullptr;  // its per-texel iterates are not one material to show
    texture = fit_texture(samples.samples, terms, width, height, fit, fit_options);
    fit = texture->fit;
    result["R0"] = fit.R0;
    const std::string file =
        out.write_image("texture.exr", texture->Rd, {{"glaze:R0", std::to_string(fit.R0)}}, texture->known);
    result["texture"] = file;
    result["texture_resolution"] = {width, height};
    result["coverage"] = texture->coverage;
    if (captures.material && !captures.material->texture.empty()) {
      // The set's own texture, when it is a file: what a known-truth experiment compares
      // with. Not fatal when it cannot be read.
      try {
        result["texture_rmse"] =
            texture_rmse(*texture, read_image(captures.material->texture), captures.material->material.Rd());
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
  if (captures.material) result["reference_material"] = material_json(*captures.material);

  // Per-view residuals over the samples, then re-renders of the inputs and held-out views.
  nlohmann::json per_view = nlohmann::json::array();
  const std::vector<ViewResidual> residuals = view_residuals(samples, terms, fit, texture ? &*texture : nullptr);
  for (size_t f = 0; f < captures.frames.size(); ++f)
    per_view.push_back({{"file", captures.frames[f].file_path},
                        {"samples", samples.per_frame[f]},
                        {"dropped", drops_json(samples.dropped[f])},
                        {"rms", residuals[f].rms},
                        {"relative_rms", residuals[f].relative_rms}});
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
  // The scene already carries the fitted material (or texture): shown as it is.
  if (preview)
    show_in_preview(preview, scene, scene.materials.front().R0, scene.materials.front().Rd, borrowed(environment),
                    "final: R0 " + std::to_string(fit.R0));
  write_renders(args, in, scene, environment, lmax, footprint, out, result);
  stage_seconds["renders"] = seconds_since(stage);
  result["stage_seconds"] = stage_seconds;
  result["seconds"] = seconds_since(start);
  write_fit(out, result, fit.full_report);

  std::printf("R0 = %.5f", fit.R0);
  if (!texture)
    std::printf(", Rd = %.5f %.5f %.5f", fit.Rd[0][0], fit.Rd[0][1], fit.Rd[0][2]);
  else
    std::printf(", texture %dx%d, %.1f%% of texels known", texture->Rd.width, texture->Rd.height,
                100 * texture->coverage);
  if (result.contains("texture_rmse"))
    std::printf(", texel RMSE against the reference %.4f", result["texture_rmse"].get<double>());
  std::printf("  (rms %.4g, %d iterations, %s)\n", fit.rms, fit.iterations,
              fit.converged ? "converged" : "NOT converged");
  if (captures.material) {
    const PolishedMaterial& truth = captures.material->material;
    std::printf("true R0 = %.5f", truth.R0());
    if (!texture) std::printf(", Rd = %.5f %.5f %.5f", truth.Rd()[0], truth.Rd()[1], truth.Rd()[2]);
    std::printf("\n");
  }
  std::printf("wrote %s (%.2f s)\n", out.file("fit.json").string().c_str(), seconds_since(start));
  return 0;
}

}  // namespace glaze::invert_fit
