// joint_fit.h: material and lighting together (DESIGN §5, paper section 7): an outer
// Ceres bounded nonlinear least squares over R0 and RGB Rd; inside, the lighting
// recovery of lighting_fit.h (the map-consistent solve); the residual is the
// least-squares misfit between that model and the observations.
//
// Why the scale is determined: the mirror term is F(n.v) L(r) with F = R0 + (1 - R0)
// (1 - n.v)^5 fixed in shape by R0 alone, and every direction of the coarse map is seen
// by several samples at different n.v (several views, a pixel's worth of normals). A
// lighting scaled by s would need F / s at every n.v at once, which no R0 gives; so the
// Fresnel-weighted coat pins the lighting's absolute scale, and with it Rd. (A
// Lambertian or microfacet fit has no such anchor: brighter light and darker paint
// look the same.) The map is solved at a resolution coarser than the samples for
// exactly this reason: one texel, many samples.
#pragma once

#include "inverse/fit_progress.h"
#include "inverse/lighting_fit.h"

#include <string>

namespace glaze {

struct JointFit {
  float R0 = 0.0f;
  RGB Rd = RGB::Zero();
  LightingFit lighting;  // at the recovered material
  int iterations = 0;
  bool converged = false;
  double rms = 0.0;  // of the map-consistent model over samples and channels
  std::string brief_report, full_report;
};

// Throws glaze::Error when the views leave the problem unconstrained (too few samples,
// or fewer than half of the reflected directions seen from two or more views).
JointFit fit_joint(const LightingData& data, const LightingFitOptions& options, int max_iterations,
                   const FitObserver& observer = {});

}  // namespace glaze
