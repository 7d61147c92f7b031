// invert_lighting.cpp: `invert-fit --mode lighting` (the lighting from an object of
// known material, paper section 6) and `--mode joint` (material and lighting together,
// section 7): fit.json with L_lm, the recovered map and its coverage mask, errors against
// the set's own lighting when it names one, and re-renders under the recovered lighting.
#include "app/invert_fit.h"
#include "inverse/capture_scene.h"
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
PolishedMaterial known_material(const Arguments& args, const CaptureSet& captures) {
  float R0 = captures.material ? captures.material->material.R0() : -1.0f;
  RGB Rd = captures.material ? captures.material->material.Rd() : RGB::Constant(-1.0f);
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

}  // namespace

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
  std::tie(options.solve_width, options.solve_height) = args.resolution("solve-res", {options.solve_width, options.solve_height});

  auto stage = Clock::now();
  // Captures from glaze's sh integrator carry a diffuse term cut at their lmax: exact for
  // the fit's model when that is at most the fit's lmax. Other captures, or sh ones that
  // do not say their lmax, get a band above any fit's: on them a second pass models the
  // diffuse term's bands up to diffuse_lmax (lighting_fit.h, joint_fit.h); 16 keeps all
  // but 0.4% of the kernel's L2 norm, as --mode material's.
  // (sh captures above the fit's lmax have their bands up to their own lmax only.)
  const int capture_lmax = capture_defaults(in.captures, kShMaxLmax + 1).second;
  const bool band_limited = capture_lmax <= lmax;
  const int diffuse_lmax =
      band_limited ? lmax : std::min(capture_lmax, static_cast<int>(args.integer("diffuse-lmax", 16, 0, kShMaxLmax)));
  LightingData data =
      gather_lighting_data(in.samples, in.captures, *in.tracer, lmax, footprint, noise_free_captures(in.captures));
  stage_seconds["gather"] = seconds_since(stage);
  begin_preview(preview, in, lmax, footprint);
  const FinishPreview finish_preview{preview};
  stage = Clock::now();
  std::optional<JointFit> joint_fit;
  JointFitOptions joint_options;
  FitObserver observer;
  // The lighting at each iterate (one per round of the joint fit) is solved here, on the
  // fit's thread: the later passes of a full-band fit replace `data`, which the preview's
  // thread must then not be reading.
  if (preview)
    observer = [&](const FitIterate& it) {
      const auto lighting = std::make_shared<const Environment>(fit_lighting(data, it.R0, it.Rd, options).map,
                                                                EnvironmentOptions{}, "lighting at the iterate");
      show_in_preview(preview, in.scene, it.R0, it.Rd, [lighting] { return lighting; }, iterate_label(it));
    };
  if (joint) {
    joint_options.max_rounds = static_cast<int>(args.integer("max-iterations", joint_options.max_rounds, 1, 10000));
    joint_options.max_passes = static_cast<int>(args.integer("max-passes", joint_options.max_passes, 1, 100));
    joint_options.band_limited_diffuse = band_limited;
    joint_fit = fit_joint_full_band(data, in.samples, diffuse_lmax, options, joint_options, observer);
  }
  const PolishedMaterial material = joint ? PolishedMaterial(joint_fit->R0, joint_fit->Rd) : known_material(args, in.captures);
  const LightingFit fit = joint ? joint_fit->lighting
                                : fit_lighting_full_band(data, in.samples, diffuse_lmax, material.R0(), material.Rd(),
                                                         options);
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
                           {"mirror_share", fit.mirror_share}, {"channel_mirror_share", rgb_json(fit.channel_mirror_share.cast<float>())}, {"multi_view_fraction", fit.multi_view_fraction},
                           {"solve", fit.map_consistent ? "map-consistent" : "sh-least-squares"}, {"samples", in.samples.samples.size()},
                           {"dropped", drops_json(in.samples.total_dropped())}, {"pixel_footprint", footprint},
                           {"band_limited_diffuse", band_limited}, {"diffuse_lmax", data.diffuse_lmax},
                           {"passes", joint ? joint_fit->passes : data.diffuse_lmax > lmax ? 2 : 1}};
  if (fit.condition > 1e6)
    warn("the lighting system is ill-conditioned (condition number " + std::to_string(fit.condition) + ", normals cover " +
         std::to_string(int(100 * data.normal_coverage)) + "% of the sphere): more views would constrain it; the ridge keeps it finite");
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
  if (options.solve_width > 0 && !fit.map_consistent)
    warn("only " + std::to_string(int(100 * fit.multi_view_fraction)) +
         "% of the reflected directions are seen from two or more views: the mirror and the diffuse term cannot be "
         "told apart there, so L_lm comes from the SH-only least squares (less accurate where the mirror dominates); "
         "add views from other directions");
  // A channel in which the mirror carries little of the light (a coloured object's own
  // colour: the diffuse dominates) has a high-resolution map of noise amplified by 1/F,
  // which the clamp at zero biases upwards; its L_lm stays sound.
  for (int c = 0; c < 3; ++c)
    if (fit.mirror_share >= 0.1 && fit.channel_mirror_share[c] < 0.1)
      warn(std::string("in the ") + (c == 0 ? "red" : c == 1 ? "green" : "blue") + " channel the mirror carries only " +
           std::to_string(std::lround(100 * fit.channel_mirror_share[c])) +
           "% of the light: that channel's high-resolution map is unreliable (noise divided by F, and biased up where it "
           "is clamped at zero); its L_lm is not");
  if (fit.mirror_share < 0.1)
    warn("the mirror reflection carries only " + std::to_string(std::lround(100 * fit.mirror_share)) +
         "% of the observed light: the object is matte-like, so only the low frequencies (the SH part) are reliable; "
         "the high-resolution map is noisy");
  // The joint fit reads R0, and with it the lighting's absolute scale, from that share:
  // measured on the white sphere in the blue room (9%), capture noise alone moves R0 by
  // about 0.015 between noise realisations, and Rd and the scale with it.
  if (joint && fit.mirror_share < 0.1)
    warn("--mode joint reads R0 and the lighting's absolute scale from the mirror reflection, which here carries only " +
         std::to_string(std::lround(100 * fit.mirror_share)) +
         "%: R0, Rd and the scale are weakly determined and capture noise can move them far (check the residual "
         "images); a known material (--mode lighting) or a glossier object pins them");

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
    if (in.captures.material) result["reference_material"] = material_json(*in.captures.material);
    for (const auto& [w, h] : {std::pair(64, 32), std::pair(128, 64), std::pair(256, 128)}) {
      if (options.width % w != 0 || options.height % h != 0) continue;
      int cells = 0;
      const double error = map_error(fit, environment, w, h, &cells);
      // No cell of this grid wholly covered (small or few views): nothing to compare.
      result["reference_map_error"][std::to_string(w) + "x" + std::to_string(h)] = {
          {"relative_rmse", cells > 0 ? nlohmann::json(error) : nlohmann::json(nullptr)}, {"cells", cells}};
    }
  }

  stage = Clock::now();
  // Shared with the preview's state, which may outlive this scope's locals.
  const auto recovered = std::make_shared<const Environment>(fit.map, EnvironmentOptions{}, "recovered lighting");
  for (SceneMaterial& m : in.scene.materials) m.R0 = material.R0(), m.Rd = material.Rd();
  show_in_preview(preview, in.scene, material.R0(), material.Rd(), [recovered] { return recovered; }, "recovered lighting");
  write_renders(args, in, in.scene, *recovered, lmax, footprint, out, result);
  // The check that needs no truth: the recovered lighting (and material) must reproduce
  // the input views. Captures with noise differ by their noise (about 5% per pixel for a
  // path tracer at 256 spp); much more means that the model misses what the cameras saw,
  // typically a light source smaller than the views resolve, and L_lm is off with it.
  double worst_view = 0.0;
  for (const auto& view : result["renders"])
    if (view["relative_rmse"].is_number()) worst_view = std::max(worst_view, view["relative_rmse"].get<double>());
  result["worst_view_relative_rmse"] = worst_view;
  if (worst_view > 0.1)
    warn("the recovered lighting reproduces the input views only to " + std::to_string(std::lround(100 * worst_view)) +
         "% relative RMSE (residual_view_*.exr shows where): the lighting has detail the captures do not resolve (a small, "
         "bright source?), so L_lm may be off by several percent; use more pixels on the object, or more views");
  if (joint && !joint_fit->passes_settled())
    warn("the joint fit's passes stopped at " + std::to_string(joint_fit->passes) + " with the last still moving R0 by " +
         std::to_string(joint_fit->pass_step) + " and Rd by " + std::to_string(joint_fit->pass_Rd_step) +
         " (solver.txt lists them): the diffuse bands above lmax, predicted from each pass's lighting and material, and "
         "the fit are not yet consistent, so R0 and Rd may be off by about that much (Rd by several times R0's step) and "
         "the scale with Rd; raise --max-passes");
  else if (joint && !joint_fit->converged)
    warn("the joint fit stopped after " + std::to_string(joint_fit->iterations) +
         " rounds with R0 still moving (solver.txt lists them): R0 and Rd are the last round's; raise --max-iterations "
         "or add views");
  stage_seconds["renders"] = seconds_since(stage);
  result["stage_seconds"] = stage_seconds;
  result["seconds"] = seconds_since(start);
  // Lighting alone is linear least squares: its report says what was solved, and how well posed.
  char linear_report[640];
  std::snprintf(linear_report, sizeof linear_report,
                "glaze lighting recovery: linear least squares (no iterations)\n"
                "  L_lm, lmax %d: %d unknowns per channel; condition number %.4g (before the ridge %.3g)\n"
                "  solve: %s at %dx%d (%.1f%% of its covered texels seen from two or more views)\n"
                "  samples %zu; mirror share %.3f (r %.3f, g %.3f, b %.3f)\n"
                "  diffuse term modelled to l = %d%s\n",
                lmax, sh_count(lmax), fit.condition, options.ridge,
                fit.map_consistent ? "map-consistent (value and gradient per texel, with L_lm)" : "SH-only least squares",
                options.solve_width, options.solve_height, 100 * fit.multi_view_fraction, in.samples.samples.size(),
                fit.mirror_share, fit.channel_mirror_share[0], fit.channel_mirror_share[1], fit.channel_mirror_share[2],
                data.diffuse_lmax, data.diffuse_lmax > lmax ? " (bands above lmax predicted by a first fit's map: 2 passes)" : "");
  write_fit(out, result, joint ? joint_fit->full_report : std::string(linear_report));
  if (joint)
    std::printf("joint: R0 = %.5f, Rd = %.5f %.5f %.5f (%d rounds, %s)\n", material.R0(), material.Rd()[0],
                material.Rd()[1], material.Rd()[2], joint_fit->iterations, joint_fit->converged ? "converged" : "NOT converged");
  std::printf("lighting: lmax %d, condition number %.3g, normals cover %.0f%%, map %dx%d covered %.1f%%, mirror share %.1f%%\n",
              lmax, fit.condition, 100 * data.normal_coverage, options.width, options.height, 100 * fit.covered_fraction,
              100 * fit.mirror_share);
  if (result.contains("reference_L_lm_error_l2"))
  {
    std::printf("against the true lighting: L_lm (l <= 2) max error %.3f%% of L00", 100 * result["reference_L_lm_error_l2"].get<double>());
    if (result.contains("reference_map_error") && result["reference_map_error"].contains("64x32") &&
        result["reference_map_error"]["64x32"]["relative_rmse"].is_number())
      std::printf("; map relative RMSE at 64x32 %.2f%% over %d covered cells",
                  100 * result["reference_map_error"]["64x32"]["relative_rmse"].get<double>(),
                  result["reference_map_error"]["64x32"]["cells"].get<int>());
    std::printf("\n");
  }
  std::printf("wrote %s (%.2f s)\n", (out / "fit.json").string().c_str(), seconds_since(start));
  return 0;
}

}  // namespace glaze::invert_fit
