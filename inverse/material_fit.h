// material_fit.h: the nested material fits under known lighting (docs/design.md §5, paper
// section 5): an outer Ceres bounded nonlinear least squares over R0 in [0, 1]; for each
// R0 the closed-form bounded linear least squares for Rd per channel (diffuse_solve.h),
// either one Rd for the whole object (homogeneous) or one per texel group (texture).
//
// Derivatives: the residual functor is templated and runs the inner solve on Ceres's
// Jets, so the Jacobian Ceres sees is d/dR0 of the residual *through* Rd(R0). With a
// robust loss the inner solve is iteratively reweighted (IRLS) and the weights at the
// inner optimum are held fixed when differentiating: by the envelope theorem the gradient
// of the outer objective does not depend on how the inner minimiser moves.
#pragma once

#include "inverse/fit_progress.h"
#include "inverse/samples.h"
#include "renderer/environment.h"
#include "renderer/shading.h"

#include <array>

#include <span>
#include <string>
#include <vector>

namespace glaze {

// What the shading model needs per sample that does not depend on the material, per
// channel (shading.h): L(r), g L(r) and g E(n) with E the SH diffuse sum (unclamped, so
// the model stays linear in the lighting). Computed once; every fit iteration reuses it.
//
// A pixel sample models its pixel as a camera (and glaze's path tracer) records it: the
// mean over its footprint, here `footprint` x `footprint` rays at the centres of a grid
// (the sh integrator's --ss positions). The mirror term is averaged over those rays; the
// diffuse term, smooth across a pixel, takes E at the centre normal. footprint 1 is the
// centre ray alone. A point sample, read bilinearly between four pixel centres, is
// modelled as the same bilinear blend of those four pixels' models.
using ShadingTerms = std::array<ShadingBasis<float>, 3>;
std::vector<ShadingTerms> shading_terms(const SampleSet& samples, const CaptureSet& captures, const RayTracer& tracer,
                                        const Environment& environment, int lmax, int footprint);

struct RobustLoss {
  enum class Kind { none, huber, cauchy } kind = Kind::none;
  // Residuals (in radiance) beyond about this size are down-weighted.
  double scale = 0.0;
  static RobustLoss parse(const std::string& name, double scale);  // "none", "huber", "cauchy"
};

struct MaterialFitOptions {
  RobustLoss loss;
  int max_iterations = 100;
  FitObserver observer;  // optional: told R0 and (group 0's) Rd after every iteration
};

struct MaterialFit {
  float R0 = 0.0f;
  std::vector<RGB> Rd;            // per group
  std::vector<RGB> Rd_unclamped;  // per group: far outside [0, 1] means misfit
  std::vector<RGBd> constraint;   // per group and channel: sum of w b^2 (0: unconstrained)
  double rms = 0.0;               // root mean square residual over samples and channels
  int iterations = 0;
  bool converged = false;
  std::string brief_report, full_report;  // Ceres's solver summary
};

// `group[k]` is the Rd group of sample k (empty: one group for all), `weights[k]` its
// weight (empty: all 1). Throws glaze::Error if the samples carry no light at all.
MaterialFit fit_material(std::span<const Sample> samples, std::span<const ShadingTerms> terms,
                         std::span<const int> group, int groups, std::span<const float> weights,
                         const MaterialFitOptions& options);

// The model's prediction for one sample (one shading routine: shading.h).
RGB predict(const ShadingTerms& terms, float R0, const RGB& Rd);

}  // namespace glaze
