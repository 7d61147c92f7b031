// fit_diagnostics.h: what a fit's result says about how far it can be trusted: the
// figures `glaze invert-fit` reports beside the result, the warnings it prints (as text,
// for the caller to print), and comparisons with the truth where a capture set knows it
// (known-truth experiments: the set's own lighting, or a recovered material rendered in
// other lighting against its true appearance there).
//
// The fits return what they solved; judging that is kept here, apart from the solvers
// and from the command that prints and writes it, so that each judgement is made once.
#pragma once

#include "inverse/joint_fit.h"
#include "inverse/lighting_fit.h"
#include "inverse/material_fit.h"
#include "inverse/samples.h"
#include "inverse/texture_fit.h"
#include "renderer/environment.h"
#include "renderer/image.h"

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace glaze {

// --- The material under known lighting (--mode material, texture). ---

struct MaterialDiagnostics {
  // Per channel: whether any sample's diffuse term reaches it (not where R0 = 1, a pure
  // mirror); an unconstrained channel's Rd is reported as 0.
  std::array<bool, 3> Rd_constrained{};
  std::vector<std::string> warnings;
};
// Of a homogeneous fit (its group 0).
MaterialDiagnostics diagnose_material(const MaterialFit& fit);

// The fit's residual over one view's samples: a view that stands out is misregistered
// or sees something the model lacks.
struct ViewResidual {
  double rms = 0.0;           // over the view's samples and channels
  double relative_rms = 0.0;  // against the observations' own (0 for a black view)
};
// Per frame of `samples`. With `texture` (whose fit `fit` is) each sample's Rd is its
// texel's, else the homogeneous fit's.
std::vector<ViewResidual> view_residuals(const SampleSet& samples, std::span<const ShadingTerms> terms,
                                         const MaterialFit& fit, const RecoveredTexture* texture = nullptr);

// --- The lighting (--mode lighting, joint). ---

struct LightingDiagnostics {
  // About the solve: how well posed, and how much of the light the mirror carries.
  std::vector<std::string> warnings;
  // A joint fit whose passes or rounds stopped before they settled.
  std::vector<std::string> convergence_warnings;
  // --mode lighting's solver report (a linear solve: what was solved, and how well posed).
  std::string linear_report;
  // max over l <= 2 and the channels of |L_lm - the map's own L_lm| / L00 (the larger of
  // the two L00): the re-renders use the map, fit.json's L_lm the solve, and where the data
  // pin the lighting down both agree. Measured: 1.7-2.8% on fits whose L_lm is within
  // 1.1% of the truth; 25% on the studio map at 128x128, whose L_lm is 12% off.
  double map_sh_disagreement = 0.0;
};
// `joint`: the joint fit that `fit` is the lighting of, else null (known material).
LightingDiagnostics diagnose_lighting(const LightingFit& fit, const LightingData& data,
                                      const LightingFitOptions& options, const JointFit* joint);

// The check that needs no truth: the recovered lighting (and material) must reproduce
// the input views, up to their noise. Says so when the worst view's relative RMSE is far
// above that.
std::optional<std::string> reproduction_warning(double worst_view_relative_rmse);

// The recovered lighting against the true one.
struct LightingComparison {
  double L_lm_error_l2 = 0.0;  // max over l <= 2 and the channels of |L_lm - true| / |true L00|
  RGBd scale = RGBd::Ones();   // the absolute scale: recovered over true L00, per channel
  struct MapError {
    int width = 0, height = 0;  // the comparison grid
    int cells = 0;              // its cells that the recovered map covers wholly (0: none compared)
    double relative_rmse = 0.0;
  };
  // On the grids 64x32, 128x64 and 256x128, those that divide the recovered map.
  std::vector<MapError> map_errors;
};
LightingComparison compare_lighting(const LightingFit& fit, const Environment& truth);

// --- A recovered material rendered in other lighting, against its true appearance. ---

struct AppearanceError {
  double relative_rmse = 0.0;
  RGB colour_ratio = RGB::Ones();  // mean rendered over mean true over the mask, per channel
};
AppearanceError appearance_error(const Image& rendered, const Image& truth, std::span<const uint8_t> mask);

// Spearman's rank correlation of paired values (tied values share the lowest rank): +1
// when the second rises with the first. Needs two or more pairs.
double rank_correlation(std::span<const std::pair<double, double>> pairs);

}  // namespace glaze
