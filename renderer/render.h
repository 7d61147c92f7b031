// render.h: renders a camera's image with the path tracer, in parallel over tiles, and
// that as an Integrator (integrator.h), PathIntegrator.
//
// Pixel filter: box. Each pixel is the mean of its samples, placed in the pixel's area
// by a scrambled (0, 2)-sequence (low_discrepancy.h): for 2^m samples every elementary
// interval of the pixel holds one, and passes of a time budget continue the sequence.
// Every pixel draws from its own random streams, seeded by (seed, pass, camera index,
// pixel index), so the image depends only on the seed, the camera and the number of
// passes, never on the thread count or the scheduling. The camera enters so that the views of
// one capture set carry independent noise, as photographs do: with streams keyed by the
// pixel alone, the same pixel of two views would draw the same numbers, and their noise
// would be correlated, which the joint fit, comparing views, does not model
// (docs/notes/noise-model.md, "Views with independent noise").
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"
#include "renderer/integrator.h"
#include "renderer/path_tracer.h"

#include <tbb/task_arena.h>

#include <atomic>
#include <cstdint>
#include <functional>
#include <vector>

namespace glaze {

// The most samples per pixel one render takes, over all its passes: a time budget stops
// here (with a warning) rather than let the sample count overflow.
inline constexpr int kMaxSamplesPerPixel = 1 << 30;

struct RenderOptions {
  int spp = 64;              // samples per pixel (per pass when time_budget > 0)
  double time_budget = 0.0;  // seconds; > 0: render passes of `spp` until it is spent
  uint64_t seed = 0;
  int threads = 0;        // 0: all cores
  bool progress = false;  // a progress bar on stderr
  // Every sample through the pixel centre: no anti-aliasing, a point-sampled image (what
  // the sh integrator renders at ss 1), to compare shading models without pixel filtering.
  bool pixel_centres = false;
};

struct RenderResult {
  Image image;
  int spp = 0;  // samples per pixel actually taken
  double seconds = 0.0;
};

// `camera_index`: the camera's index in its scene (see above).
RenderResult render(const PathTracer& tracer, const PinholeCamera& camera, const RenderOptions& options,
                    uint64_t camera_index = 0);

// The passes behind render(), one at a time, for callers that show the image as it
// refines (the preview window): pass k of `options.spp` samples per pixel is the same
// whether it is rendered here or by render(). Besides the running sum it keeps, per
// pixel, the sum of squares of each pass's mean luminance, from which the Monte-Carlo
// standard error of the running mean follows (passes are independent estimates).
class ProgressiveRender {
 public:
  ProgressiveRender(const PathTracer& tracer, const PinholeCamera& camera, const RenderOptions& options,
                    uint64_t camera_index = 0);

  // Renders the next pass and adds it. Returns false, adding nothing, when `cancel`
  // becomes true before the pass is complete (it is checked between tiles).
  // `tile_done` (optional) is called after each of the pass's tiles, from any thread.
  bool add_pass(const std::atomic<bool>* cancel = nullptr, const std::function<void()>& tile_done = {});

  int passes() const { return passes_; }
  int spp() const { return passes_ * options_.spp; }
  // True when another pass would take the samples per pixel past kMaxSamplesPerPixel
  // (the pass index times spp numbers the samples in 32 bits); add_pass then throws.
  bool full() const { return int64_t(passes_ + 1) * options_.spp > kMaxSamplesPerPixel; }
  int tile_count() const;
  // The mean of the passes so far (zero before the first); values that are not finite
  // become 0, and their number is returned in `non_finite` if given.
  Image mean(size_t* non_finite = nullptr) const;
  // Per pixel (row-major): the standard error of the running mean's luminance relative
  // to that mean, from the spread of the passes; NaN before two passes or where the mean
  // is not positive. Exact in expectation for independent passes (pixel_centres); over
  // the pixel area the passes continue one stratified sequence and the mean converges
  // faster than that, so there it is an upper bound (its square about 1.3x too large in tests).
  std::vector<float> relative_standard_error() const;

 private:
  const PathTracer& tracer_;
  PinholeCamera camera_;
  RenderOptions options_;
  uint64_t camera_index_;
  tbb::task_arena arena_;
  int passes_ = 0;
  std::vector<double> sum_;               // width * height * 3
  std::vector<double> luminance_sum_;     // per pixel: sum over passes of the pass mean's luminance
  std::vector<double> luminance_sq_sum_;  // ... and of its square
  std::vector<double> pass_;              // the pass being rendered: its per-pixel sums
};

// render() as an Integrator: the path tracer of `scene` under `environment` with
// `tracer_options`, rendering with `options`; its image, with the samples taken.
class PathIntegrator final : public Integrator {
 public:
  static constexpr std::string_view kName = "path";

  PathIntegrator(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                 const PathTracerOptions& tracer_options, const RenderOptions& options)
      : tracer_(scene, tracer, environment, tracer_options), options_(options) {}

  std::string_view name() const override { return kName; }

 private:
  IntegratorResult render_camera(const PinholeCamera& camera, uint64_t camera_index) const override;

  PathTracer tracer_;
  RenderOptions options_;
};

}  // namespace glaze
