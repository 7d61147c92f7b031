// joint_fit.h: material and lighting together (docs/design.md §5, paper section 7).
//
// Why the scale is determined: the mirror term is F(n.v) L(r) with F = R0 + (1 - R0)
// (1 - n.v)^5 fixed in shape by R0 alone, and every direction is reflected towards
// several views at different n.v. A lighting scaled by s would need F / s at every n.v
// at once, which no R0 gives: near grazing the coat is a mirror of strength ~1 whatever
// R0 is. So the Fresnel-weighted coat pins R0, with it the lighting's absolute scale,
// and with that Rd. (A Lambertian or microfacet fit has no such anchor: brighter light
// and darker paint look the same.)
//
// The fit, in two steps:
// 1. R0 and the diffuse field d = 21/(20 pi) (1 - R0) Rd L_lm, from the views' agreement
//    (cross_view.h): the lighting is eliminated between views, not discretised, so no
//    representation error enters. The misfit, minimised over d (linear), is a function
//    of R0 alone: a bounded one-dimensional search (a grid, then Brent's method), in
//    rounds that re-estimate the robust scale until R0 settles.
// 2. Rd per channel, in closed form at that R0: the lighting's absolute level against d.
//    When the captures' diffuse term is band-limited at the fit's lmax (glaze's `sh`
//    integrator), the level is L_00 of the views' own mirror estimates (o - c.d) / F,
//    which is then exact but for the views' sampling of sources smaller than their
//    pixels' spacing (joint_fit.cpp, kMirrorIntegralWidth). Otherwise (photographs, the
//    path tracer: the diffuse term has every band) the unmodelled bands, divided by
//    F ~ R0 near the normal, would bias that estimate; there Rd minimises the
//    map-consistent lighting solve's misfit (lighting_fit.h), which weights the mirror
//    by F^2, summed over the solve map turned by four fractions of a texel
//    (joint_fit.cpp, TurnedMapSystems, says why).
//
// Full-band captures need one more thing: both steps model the diffuse term up to the
// fit's lmax, and under small bright sources the bands above it (about 5% of the diffuse
// term at lmax 4) are as large as a diffuse object's whole mirror reflection, which is
// what R0 is read from. fit_joint_full_band predicts those bands (up to diffuse_lmax)
// from the lighting the first fit recovers at its material (predict_diffuse_bands in
// lighting_fit.h says why that lighting is good enough), takes them off the
// observations and fits again from the first R0; and again from each new fit's lighting
// while a pass still moves R0 or Rd by 1e-3 or more (at most max_passes); once R0 has
// settled, a pass keeps it and solves Rd and the lighting alone. Each pass's better
// lighting predicts the bands better, so R0 and Rd converge over a few passes
// (docs/notes/joint-passes.md).
#pragma once

#include "inverse/fit_progress.h"
#include "inverse/lighting_fit.h"
#include "inverse/samples.h"

#include <optional>
#include <string>

namespace glaze {

// Full-band captures: the passes have settled when the last one moved R0 by under this
// (joint_fit.cpp says why two passes usually are enough for R0) ...
inline constexpr double kJointPassTolerance = 1e-3;
// ... and the last moved Rd by under this in every channel.
inline constexpr double kJointPassRdTolerance = 1e-3;

struct JointFit {
  float R0 = 0.0f;
  RGB Rd = RGB::Zero();
  LightingFit lighting;       // at the recovered material
  int iterations = 0;         // rounds of step 1 (robust scale, then the search for R0)
  int evaluations = 0;        // of the robust misfit
  bool converged = false;     // the last pass's rounds, and the passes (below), settled
  int passes = 1;             // of the fit (fit_joint_full_band: each predicts the bands for the next)
  double pass_step = 0.0;     // how far the last pass moved R0 from the one before (0: one pass)
  double pass_Rd_step = 0.0;  // and Rd, in its channel that moved most
  // Else the passes stopped at max_passes with R0 or Rd still moving.
  bool passes_settled() const { return pass_step < kJointPassTolerance && pass_Rd_step < kJointPassRdTolerance; }
  double rms = 0.0;  // of the map-consistent model over samples and channels
  std::string brief_report, full_report;
};

struct JointFitOptions {
  int max_rounds = 20;
  // Full-band captures: the most passes (fit_joint_full_band) before the fit stops with
  // R0 or Rd still moving (converged false). 12 leaves room beyond the white sphere in the
  // blue room, whose first pass starts furthest off and which takes the most passes to
  // settle (docs/notes/joint-passes.md, "How many passes"); passes past the point of
  // settling are never run.
  int max_passes = 12;
  // The captures' diffuse term is band-limited at the fit's lmax (see above).
  bool band_limited_diffuse = false;
  // The search for R0 starts there, near enough to skip the coarse grid (clamped to R0's
  // bounds).
  std::optional<double> start_R0;
};

// Throws glaze::Error when the views leave the problem unconstrained (too few samples,
// point samples, fewer than half of the reflected directions seen from two or more
// views).
JointFit fit_joint(const LightingData& data, const SampleSet& samples, const LightingFitOptions& options,
                   const JointFitOptions& joint, const FitObserver& observer = {});

// The passes for full-band captures (above), on `data` gathered from `samples`;
// `data` receives the last pass's observations. diffuse_lmax <= data.lmax, or
// band-limited captures: fit_joint alone.
JointFit fit_joint_full_band(LightingData& data, const SampleSet& samples, int diffuse_lmax,
                             const LightingFitOptions& options, JointFitOptions joint,
                             const FitObserver& observer = {});

}  // namespace glaze
