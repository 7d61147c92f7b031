#include "inverse/fit_diagnostics.h"

#include "renderer/error.h"
#include "renderer/image_error.h"
#include "renderer/latlong.h"
#include "renderer/sh.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace glaze {
namespace {

// How far L_lm (l <= 2) may stray from the recovered map's own, as a fraction of L00.
constexpr double kMapShTolerance = 0.1;

}  // namespace

MaterialDiagnostics diagnose_material(const MaterialFit& fit) {
  MaterialDiagnostics diagnostics;
  for (int c = 0; c < 3; ++c) {
    const bool constrained = fit.constraint[0][c] > 1e-12 * std::max(1.0, fit.constraint[0].maxCoeff());
    diagnostics.Rd_constrained[c] = constrained;
    if (!constrained)
      diagnostics.warnings.push_back(std::string("Rd ") + "RGB"[c] +
                                     " is not constrained by the data (no diffuse reflection seen: R0 = " +
                                     std::to_string(fit.R0) + "); it is reported as 0");
  }
  return diagnostics;
}

std::vector<ViewResidual> view_residuals(const SampleSet& samples, std::span<const ShadingTerms> terms,
                                         const MaterialFit& fit, const RecoveredTexture* texture) {
  const size_t frames = samples.per_frame.size();
  std::vector<double> squared(frames, 0.0), observed(frames, 0.0);
  for (size_t k = 0; k < samples.samples.size(); ++k) {
    const Sample& s = samples.samples[k];
    const RGB& Rd = fit.Rd[texture ? texel_of(s.uv, texture->Rd.width, texture->Rd.height) : 0];
    squared[s.frame] += (s.observed - predict(terms[k], fit.R0, Rd)).cast<double>().square().sum();
    observed[s.frame] += s.observed.cast<double>().square().sum();
  }
  std::vector<ViewResidual> views(frames);
  for (size_t f = 0; f < frames; ++f) {
    const double n = 3.0 * std::max<size_t>(samples.per_frame[f], 1);
    views[f] = {std::sqrt(squared[f] / n), observed[f] > 0 ? std::sqrt(squared[f] / observed[f]) : 0.0};
  }
  return views;
}

LightingDiagnostics diagnose_lighting(const LightingFit& fit, const LightingData& data,
                                      const LightingFitOptions& options, const JointFit* joint) {
  LightingDiagnostics diagnostics;
  std::vector<std::string>& warnings = diagnostics.warnings;
  if (fit.condition > 1e6)
    warnings.push_back("the lighting system is ill-conditioned (condition number " + std::to_string(fit.condition) +
                       ", normals cover " + std::to_string(int(100 * data.normal_coverage)) +
                       "% of the sphere): more views would constrain it; the ridge keeps it finite");
  if (options.solve_width > 0 && !fit.map_consistent)
    warnings.push_back("only " + std::to_string(int(100 * fit.multi_view_fraction)) +
                       "% of the reflected directions are seen from two or more views: the mirror and the diffuse term "
                       "cannot be told apart there, so L_lm comes from the SH-only least squares (less accurate where "
                       "the mirror dominates); add views from other directions");
  // A channel in which the mirror carries little of the light (a coloured object's own
  // colour: the diffuse dominates) has a high-resolution map of noise amplified by 1/F,
  // which the clamp at zero biases upwards; its L_lm stays sound.
  for (int c = 0; c < 3; ++c)
    if (fit.mirror_share >= 0.1 && fit.channel_mirror_share[c] < 0.1)
      warnings.push_back(std::string("in the ") +
                         (c == 0   ? "red"
                          : c == 1 ? "green"
                                   : "blue") +
                         " channel the mirror carries only " +
                         std::to_string(std::lround(100 * fit.channel_mirror_share[c])) +
                         "% of the light: that channel's high-resolution map is unreliable (noise divided by F, and "
                         "biased up where it is clamped at zero); its L_lm is not");
  if (fit.mirror_share < 0.1)
    warnings.push_back("the mirror reflection carries only " + std::to_string(std::lround(100 * fit.mirror_share)) +
                       "% of the observed light: the object is matte-like, so only the low frequencies (the SH part) "
                       "are reliable; the high-resolution map is noisy");
  // The joint fit reads R0, and with it the lighting's absolute scale, from that share:
  // the smaller it is, the further capture noise moves R0, and Rd and the scale with it
  // (docs/notes/blue-room-white-sphere.md).
  if (joint && fit.mirror_share < 0.1)
    warnings.push_back(
        "--mode joint reads R0 and the lighting's absolute scale from the mirror reflection, which here "
        "carries only " +
        std::to_string(std::lround(100 * fit.mirror_share)) +
        "%: R0, Rd and the scale are weakly determined and capture noise can move them far (check the "
        "residual images); a known material (--mode lighting) or a glossier object pins them");

  // The map's texels are the splat's where a sample sees them and the solve's L_lm
  // elsewhere: its low bands disagree with L_lm only where the splat and the solve read
  // the samples differently, so one of them is wrong (an L_lm the data do not pin down).
  const int lmax = data.lmax;
  const ShCoefficients map_sh = sh_project_latlong(fit.map, Mat3::Identity(), std::min(lmax, 2));
  for (size_t i = 0; i < map_sh.values.size(); ++i) {
    const RGBd L00 = fit.coefficients.values[0].abs().max(map_sh.values[0].abs()).max(1e-12);
    diagnostics.map_sh_disagreement = std::max(
        diagnostics.map_sh_disagreement, ((fit.coefficients.values[i] - map_sh.values[i]).abs() / L00).maxCoeff());
  }
  if (!(diagnostics.map_sh_disagreement <= kMapShTolerance))
    warnings.push_back("L_lm (l <= 2) differs from the recovered map's own by " +
                       std::to_string(std::lround(100 * diagnostics.map_sh_disagreement)) + "% of L00 (more than " +
                       std::to_string(std::lround(100 * kMapShTolerance)) +
                       "%): the data do not pin the lighting down, so L_lm and the map (which the re-renders use) "
                       "cannot both be right; check the material, or add views");

  if (joint && !joint->passes_settled())
    diagnostics.convergence_warnings.push_back(
        "the joint fit's passes stopped at " + std::to_string(joint->passes) + " with the last still moving R0 by " +
        std::to_string(joint->pass_step) + " and Rd by " + std::to_string(joint->pass_Rd_step) +
        " (solver.txt lists them): the diffuse bands above lmax, predicted from each pass's lighting and material, "
        "and the fit are not yet consistent, so R0 and Rd may be off by about that much (Rd by several times R0's "
        "step) and the scale with Rd; raise --max-passes");
  else if (joint && !joint->converged)
    diagnostics.convergence_warnings.push_back(
        "the joint fit stopped after " + std::to_string(joint->iterations) +
        " rounds with R0 still moving (solver.txt lists them): R0 and Rd are the last round's; raise --max-iterations "
        "or add views");

  char report[640];
  std::snprintf(
      report, sizeof report,
      "glaze lighting recovery: linear least squares (no iterations)\n"
      "  L_lm, lmax %d: %d unknowns per channel; condition number %.4g (before the ridge %.3g)\n"
      "  solve: %s at %dx%d (%.1f%% of its covered texels seen from two or more views)\n"
      "  samples %zu; mirror share %.3f (r %.3f, g %.3f, b %.3f)\n"
      "  diffuse term modelled to l = %d%s\n",
      lmax, sh_count(lmax), fit.condition, options.ridge,
      fit.map_consistent ? "map-consistent (value and gradient per texel, with L_lm)" : "SH-only least squares",
      options.solve_width, options.solve_height, 100 * fit.multi_view_fraction, data.observed.size(), fit.mirror_share,
      fit.channel_mirror_share[0], fit.channel_mirror_share[1], fit.channel_mirror_share[2], data.diffuse_lmax,
      data.diffuse_lmax > lmax ? " (bands above lmax predicted by a first fit's map: 2 passes)" : "");
  diagnostics.linear_report = report;
  return diagnostics;
}

std::optional<std::string> reproduction_warning(double worst_view_relative_rmse) {
  // Captures with noise differ by their noise (about 5% per pixel for a path tracer at
  // 256 spp); much more means that the model misses what the cameras saw, typically a
  // light source smaller than the views resolve, and L_lm is off with it.
  if (!(worst_view_relative_rmse > 0.1)) return std::nullopt;
  return "the recovered lighting reproduces the input views only to " +
         std::to_string(std::lround(100 * worst_view_relative_rmse)) +
         "% relative RMSE (residual_view_*.exr shows where): the lighting has detail the captures do not resolve (a "
         "small, bright source?), so L_lm may be off by several percent; use more pixels on the object, or more views";
}

LightingComparison compare_lighting(const LightingFit& fit, const Environment& truth) {
  const int lmax = fit.coefficients.lmax;
  const ShCoefficients& reference = truth.sh(lmax);
  LightingComparison comparison;
  const RGBd L00 = reference.values[0].abs().max(1e-12);
  for (int i = 0; i < sh_count(std::min(lmax, 2)); ++i)
    comparison.L_lm_error_l2 =
        std::max(comparison.L_lm_error_l2, ((fit.coefficients.values[i] - reference.values[i]).abs() / L00).maxCoeff());
  comparison.scale = fit.coefficients.values[0] / reference.values[0];
  for (const auto& [width, height] : {std::pair(64, 32), std::pair(128, 64), std::pair(256, 128)}) {
    if (fit.map.width % width != 0 || fit.map.height % height != 0) continue;
    LightingComparison::MapError error{width, height};
    error.relative_rmse = map_error(fit, truth, width, height, &error.cells);
    comparison.map_errors.push_back(error);
  }
  return comparison;
}

AppearanceError appearance_error(const Image& rendered, const Image& truth, std::span<const uint8_t> mask) {
  RGBd rendered_sum = RGBd::Zero(), truth_sum = RGBd::Zero();
  for (size_t p = 0; p < mask.size(); ++p)
    if (mask[p])
      for (int c = 0; c < 3; ++c)
        rendered_sum[c] += rendered.pixels[3 * p + c], truth_sum[c] += truth.pixels[3 * p + c];
  return {image_error(rendered, truth, mask).relative_rmse, (rendered_sum / truth_sum.max(1e-30)).cast<float>()};
}

double rank_correlation(std::span<const std::pair<double, double>> pairs) {
  if (pairs.size() < 2) throw Error("rank_correlation needs two or more pairs");
  auto ranks = [&](bool second) {
    std::vector<double> rank(pairs.size());
    for (size_t i = 0; i < pairs.size(); ++i)
      for (size_t j = 0; j < pairs.size(); ++j)
        if ((second ? pairs[j].second < pairs[i].second : pairs[j].first < pairs[i].first)) rank[i] += 1.0;
    return rank;
  };
  const std::vector<double> a = ranks(false), b = ranks(true);
  double d2 = 0.0;
  for (size_t i = 0; i < a.size(); ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
  const double n = double(a.size());
  return 1.0 - 6.0 * d2 / (n * (n * n - 1.0));
}

}  // namespace glaze
