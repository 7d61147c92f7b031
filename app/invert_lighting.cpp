// invert_lighting.cpp: `invert-fit --mode lighting` (the lighting from an object of
// known material, paper section 6) and `--mode joint` (material and lighting together,
// section 7): fit.json with L_lm, the recovered map and its coverage mask, errors against
// the set's own lighting when it names one, and re-renders under the recovered lighting.
#include "app/invert_fit.h"
#include "inverse/capture_scene.h"
#include "inverse/fit_diagnostics.h"
#include "inverse/joint_fit.h"
#include "inverse/lighting_fit.h"
#include "renderer/error.h"
#include "renderer/image.h"
#include "renderer/material.h"
#include "renderer/sh.h"

#include <cmath>
#include <cstdio>
#include <optional>
#include <tuple>

namespace glaze::invert_fit {
namespace {

// The known material of --mode lighting: --R0 and --Rd, else the capture set's.
PolishedMaterial known_material(const InvertFitOptions& args, const CaptureSet& captures) {
  float R0 = captures.material ? captures.material->material.R0() : -1.0f;
  RGB Rd = captures.material ? captures.material->material.Rd() : RGB::Constant(-1.0f);
  R0 = args.R0.value_or(R0);
  if (!args.Rd.empty()) Rd = RGB(args.Rd[0], args.Rd[1], args.Rd[2]);
  if (R0 < 0.0f || (Rd < 0.0f).any()) {
    const std::string missing = R0 < 0.0f ? (args.R0 ? "--R0 is negative" : "R0 is not given")
                                          : (!args.Rd.empty() ? "--Rd is negative" : "Rd is not given");
    throw Error(missing + ": --mode lighting needs the object's material, from the \"material\" of " + captures.file +
                " or --R0 x --Rd r,g,b (each in [0, 1])");
  }
  const PolishedMaterial material(R0, Rd);  // validates the ranges
  // With R0 = 0 a channel of Rd = 0 reflects only at grazing angles (F = (1 - mu)^5), where
  // few samples are kept and the silhouettes' errors count most: measured, L00 off by 8%.
  if (R0 == 0.0f) {
    const std::string where =
        (args.R0 || !args.Rd.empty() ? std::string("--R0 and --Rd") : captures.file) + ": R0 = 0 and Rd = 0";
    if ((Rd == 0.0f).all())
      throw Error(where +
                  ": the object reflects light only at grazing angles, which does not determine the "
                  "lighting; --mode lighting needs an object that reflects (R0 > 0 or Rd > 0)");
    for (int c = 0; c < 3; ++c)
      if (Rd[c] == 0.0f)
        warn(where + " in the " +
             (c == 0   ? "red"
              : c == 1 ? "green"
                       : "blue") +
             " channel: it reflects light only at grazing angles, so that channel's L_lm is weakly determined (off "
             "by several percent)");
  }
  return material;
}

}  // namespace

LightingProblem lighting_problem(const InvertFitOptions& args, const FitInputs& in) {
  LightingProblem problem;
  problem.lmax = args.lmax.value_or(4);
  problem.footprint = args.pixel_footprint.value_or(capture_defaults(in.captures, 4).first);
  LightingFitOptions& options = problem.options;
  std::tie(options.width, options.height) = args.lighting_resolution.pair();
  options.ridge = args.ridge.value_or(float(options.ridge));
  std::tie(options.solve_width, options.solve_height) =
      args.solve_resolution.value_or(Resolution{options.solve_width, options.solve_height}).pair();
  // Captures from glaze's sh integrator carry a diffuse term cut at their lmax: exact for
  // the fit's model when that is at most the fit's lmax. Other captures, or sh ones that
  // do not say their lmax, get a band above any fit's: on them a second pass models the
  // diffuse term's bands up to diffuse_lmax (lighting_fit.h, joint_fit.h), by default
  // kFullBandDiffuseLmax, as --mode material's.
  // (sh captures above the fit's lmax have their bands up to their own lmax only.)
  const int capture_lmax = capture_defaults(in.captures, kShMaxLmax + 1).second;
  problem.band_limited = capture_lmax <= problem.lmax;
  problem.diffuse_lmax = problem.band_limited ? problem.lmax : std::min(capture_lmax, args.diffuse_lmax);
  problem.data = gather_lighting_data(in.samples, in.captures, *in.tracer, problem.lmax, problem.footprint,
                                      noise_free_captures(in.captures));
  return problem;
}

JointFit solve_joint(LightingProblem& problem, const SampleSet& samples, const InvertFitOptions& args,
                     const FitObserver& observer) {
  JointFitOptions joint_options;
  joint_options.max_rounds = args.max_iterations.value_or(joint_options.max_rounds);
  joint_options.max_passes = args.max_passes.value_or(joint_options.max_passes);
  joint_options.band_limited_diffuse = problem.band_limited;
  return fit_joint_full_band(problem.data, samples, problem.diffuse_lmax, problem.options, joint_options, observer);
}

// --mode lighting: the lighting from an object of known material; --mode joint: the
// material and the lighting together.
int invert_lighting(const InvertFitOptions& args, const std::filesystem::path& out_folder, bool joint,
                    FitPreview* preview) {
  const auto start = Clock::now();
  nlohmann::json stage_seconds;
  FitInputs in = prepare_inputs(args, stage_seconds);
  auto stage = Clock::now();
  LightingProblem problem = lighting_problem(args, in);
  const int lmax = problem.lmax, footprint = problem.footprint;
  const LightingFitOptions& options = problem.options;
  LightingData& data = problem.data;
  stage_seconds["gather"] = seconds_since(stage);
  begin_preview(preview, in, lmax, footprint);
  const FinishPreview finish_preview{preview};
  stage = Clock::now();
  std::optional<JointFit> joint_fit;
  FitObserver observer;
  // The lighting at each iterate (one per round of the joint fit) is solved here, on the
  // fit's thread: the later passes of a full-band fit replace `data`, which the preview's
  // thread must then not be reading.
  if (preview)
    observer = [&](const FitIterate& it) {
      const auto lighting = std::make_shared<const Environment>(fit_lighting(data, it.R0, it.Rd, options).map,
                                                                EnvironmentOptions{}, "lighting at the iterate");
      show_in_preview(
          preview, in.scene, it.R0, it.Rd, [lighting] { return lighting; }, iterate_label(it));
    };
  if (joint) joint_fit = solve_joint(problem, in.samples, args, observer);
  const PolishedMaterial material =
      joint ? PolishedMaterial(joint_fit->R0, joint_fit->Rd) : known_material(args, in.captures);
  const LightingFit fit =
      joint ? joint_fit->lighting
            : fit_lighting_full_band(data, in.samples, problem.diffuse_lmax, material.R0(), material.Rd(), options);
  stage_seconds["fit"] = seconds_since(stage);
  // Made before anything is written, so that a map the renderer refuses (a texel beyond
  // what float carries through a render, environment.h) leaves no lighting.exr. Shared
  // with the preview's state, which may outlive this scope's locals.
  const auto recovered = std::make_shared<const Environment>(fit.map, EnvironmentOptions{}, "recovered lighting");
  OutputFolder out(out_folder, "fit.json", "fit output");

  const std::string map_file = out.write_image("lighting.exr", fit.map, {{"glaze:lmax", std::to_string(lmax)}});
  Image mask(fit.map.width, fit.map.height);
  for (size_t t = 0; t < fit.covered.size(); ++t)
    for (int c = 0; c < 3; ++c) mask.pixels[3 * t + c] = fit.covered[t];
  const std::string mask_file = out.write_image("lighting_coverage.png", mask);
  nlohmann::json L = nlohmann::json::array();
  for (const RGBd& v : fit.coefficients.values) L.push_back({v[0], v[1], v[2]});
  nlohmann::json result = {{"mode", joint ? "joint" : "lighting"},
                           {"R0", material.R0()},
                           {"Rd", rgb_json(material.Rd())},
                           {"lmax", lmax},
                           {"L_lm", L},
                           {"condition_number", fit.condition},
                           {"ridge", options.ridge},
                           {"normal_coverage", data.normal_coverage},
                           {"map", map_file},
                           {"coverage_mask", mask_file},
                           {"map_resolution", {options.width, options.height}},
                           {"solve_resolution", {options.solve_width, options.solve_height}},
                           {"covered_fraction", fit.covered_fraction},
                           {"mirror_share", fit.mirror_share},
                           {"channel_mirror_share", rgb_json(fit.channel_mirror_share.cast<float>())},
                           {"multi_view_fraction", fit.multi_view_fraction},
                           {"solve", fit.map_consistent ? "map-consistent" : "sh-least-squares"},
                           {"samples", in.samples.samples.size()},
                           {"dropped", drops_json(in.samples.total_dropped())},
                           {"pixel_footprint", footprint},
                           {"band_limited_diffuse", problem.band_limited},
                           {"diffuse_lmax", data.diffuse_lmax},
                           {"passes", joint                      ? joint_fit->passes
                                      : data.diffuse_lmax > lmax ? 2
                                                                 : 1}};
  const LightingDiagnostics diagnostics = diagnose_lighting(fit, data, options, joint ? &*joint_fit : nullptr);
  result["map_sh_disagreement"] = diagnostics.map_sh_disagreement;
  for (const std::string& warning : diagnostics.warnings) warn(warning);
  if (joint) {
    result["iterations"] = joint_fit->iterations;
    result["evaluations"] = joint_fit->evaluations;
    result["converged"] = joint_fit->converged;
    result["passes_settled"] = joint_fit->passes_settled();
    result["last_pass_R0_step"] = joint_fit->pass_step;
    result["last_pass_Rd_step"] = joint_fit->pass_Rd_step;
    result["rms"] = joint_fit->rms;
    result["solver"] = joint_fit->brief_report;
  } else {
    // A linear least-squares solve: no iterations, and converged when it is finite.
    result["iterations"] = 0;
    result["converged"] = std::isfinite(fit.rms);
    result["rms"] = fit.rms;
  }

  // Against the set's own lighting, when it names one: what a known-truth experiment checks.
  if (const std::optional<EnvironmentSpec> truth = capture_environment(in.captures)) {
    const Environment environment = make_environment(truth->source, truth->options, truth->width, truth->height);
    const LightingComparison comparison = compare_lighting(fit, environment);
    result["reference_L_lm_error_l2"] = comparison.L_lm_error_l2;
    result["reference_scale"] = rgb_json(comparison.scale.cast<float>());
    if (in.captures.material) result["reference_material"] = material_json(*in.captures.material);
    for (const LightingComparison::MapError& error : comparison.map_errors)
      result["reference_map_error"][std::to_string(error.width) + "x" + std::to_string(error.height)] = {
          {"relative_rmse", error.cells > 0 ? nlohmann::json(error.relative_rmse) : nlohmann::json(nullptr)},
          {"cells", error.cells}};
  }

  stage = Clock::now();
  for (SceneMaterial& m : in.scene.materials) m.R0 = material.R0(), m.Rd = material.Rd();
  show_in_preview(
      preview, in.scene, material.R0(), material.Rd(), [recovered] { return recovered; }, "recovered lighting");
  write_renders(args, in, in.scene, *recovered, lmax, footprint, out, result);
  double worst_view = 0.0;
  for (const auto& view : result["renders"])
    if (view["relative_rmse"].is_number()) worst_view = std::max(worst_view, view["relative_rmse"].get<double>());
  result["worst_view_relative_rmse"] = worst_view;
  if (const std::optional<std::string> warning = reproduction_warning(worst_view)) warn(*warning);
  for (const std::string& warning : diagnostics.convergence_warnings) warn(warning);
  stage_seconds["renders"] = seconds_since(stage);
  result["stage_seconds"] = stage_seconds;
  result["seconds"] = seconds_since(start);
  write_fit(out, result, joint ? joint_fit->full_report : diagnostics.linear_report);
  if (joint)
    std::printf("joint: R0 = %.5f, Rd = %.5f %.5f %.5f (%d rounds, %s)\n", material.R0(), material.Rd()[0],
                material.Rd()[1], material.Rd()[2], joint_fit->iterations,
                joint_fit->converged ? "converged" : "NOT converged");
  std::printf(
      "lighting: lmax %d, condition number %.3g, normals cover %.0f%%, map %dx%d covered %.1f%%, mirror share %.1f%%\n",
      lmax, fit.condition, 100 * data.normal_coverage, options.width, options.height, 100 * fit.covered_fraction,
      100 * fit.mirror_share);
  if (result.contains("reference_L_lm_error_l2")) {
    std::printf("against the true lighting: L_lm (l <= 2) max error %.3f%% of L00",
                100 * result["reference_L_lm_error_l2"].get<double>());
    if (result.contains("reference_map_error") && result["reference_map_error"].contains("64x32") &&
        result["reference_map_error"]["64x32"]["relative_rmse"].is_number())
      std::printf("; map relative RMSE at 64x32 %.2f%% over %d covered cells",
                  100 * result["reference_map_error"]["64x32"]["relative_rmse"].get<double>(),
                  result["reference_map_error"]["64x32"]["cells"].get<int>());
    std::printf("\n");
  }
  std::printf("wrote %s (%.2f s)\n", out.file("fit.json").string().c_str(), seconds_since(start));
  return 0;
}

}  // namespace glaze::invert_fit
