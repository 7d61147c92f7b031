// sh_integrator.h: the analytic integrator of docs/design.md §2, the paper's dual
// angular/frequency-space shading model:
//
//   Lo(n, v) = F(n.v) L(r)  +  21/(20 pi) Rd (1 - R0) g(n.v) sum_l Lambda_l h_l L_lm Y_lm(n)
//
// per sub-pixel sample: one ray cast through the scene's Embree geometry, one
// environment lookup along the mirror direction, and the SH diffuse sum. No Monte-Carlo
// noise: K x K sub-pixel samples (centres of a K x K grid, box filter: pixel_grid.h) only against
// aliasing at silhouettes and in sharp reflections, optionally M x M where those K x K
// disagree (the few pixels with an edge in them get the samples). It is exact for a single convex
// object under distant light up to the SH truncation of the diffuse term; elsewhere it
// ignores occlusion and interreflection (glaze warns). Where the truncated diffuse sum
// rings below zero (far from a point-like light) it is clamped at zero.
#pragma once

#include "renderer/camera.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/integrator.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"

namespace glaze {

struct ShIntegratorOptions {
  int lmax = 4;                   // SH band limit of the lighting
  int supersampling = 2;          // K: K x K samples per pixel
  bool black_background = false;  // camera rays that miss return 0
  int threads = 0;                // 0: the caller's arena (all cores by default)
  bool clamp_diffuse = true;      // clamp a negative (ringing) diffuse sum at zero
  // M > K: a pixel where the K x K samples' luminance bends by more than refine_contrast
  // of the pixel's (a second difference on the lattice of samples: a silhouette, the edge
  // of a reflected light; not a smooth gradient, which K x K averages exactly) is
  // rendered again with M x M samples, which replace its K x K ones. 0: off.
  int refined_supersampling = 0;
  float refine_contrast = 0.05f;
  // What the warning for a scene it is not exact for (not one convex object) advises: the
  // calling command's alternative.
  std::string approximation_advice = "use --integrator path";
  // False for a scene that the caller knows to be exact although it is not one convex
  // object: nothing occludes the light of any visible point (a flat board on a flat table).
  bool warn_when_inexact = true;
};

Image render_sh(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                const PinholeCamera& camera, const ShIntegratorOptions& options);

// render_sh as an Integrator (integrator.h): its image, timed, with its parameters.
class ShIntegrator final : public Integrator {
 public:
  static constexpr std::string_view kName = "sh";

  ShIntegrator(const Scene& scene, const RayTracer& tracer, const Environment& environment,
               const ShIntegratorOptions& options)
      : scene_(scene), tracer_(tracer), environment_(environment), options_(options) {}

  std::string_view name() const override { return kName; }

 private:
  IntegratorResult render_camera(const PinholeCamera& camera, uint64_t camera_index) const override;

  const Scene& scene_;
  const RayTracer& tracer_;
  const Environment& environment_;
  ShIntegratorOptions options_;
};

}  // namespace glaze
