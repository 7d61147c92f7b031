// preview_renderer.h: the preview window's renderer: renders a camera progressively on
// worker threads and publishes each finished step, so that the window (or a test) can
// show the newest one at any moment without ever waiting for a pass.
//
// Per camera it keeps both integrators' images:
//  - sh: one image at the requested lmax and ss (ShIntegrator; tens of milliseconds at
//    512x512);
//  - path: passes of one sample per pixel (ProgressiveRender, so pass k is the pass k of
//    `glaze render`), accumulated up to max_spp, with the per-pixel Monte-Carlo error
//    (passes are the path tracer's own: integrator.h says why).
// The selected integrator is rendered first after every camera change: in sh mode the sh
// image, then path passes; in path mode the first 8 passes, then the sh image (only for
// a single convex object, where sh is exact), then the remaining passes. So switching is
// instant, and in sh mode the path passes give a converging reference that the relative
// error view compares against. A camera change cancels the running path pass between
// tiles; a running sh frame (tens of milliseconds) is finished. A camera's first step is
// always finished and published, so that a drag shows images all along.
// Also per camera: n.v at every pixel centre, for the n.v view.
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"
#include "renderer/path_tracer.h"
#include "renderer/render.h"
#include "renderer/sh_integrator.h"

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <string_view>
#include <thread>
#include <vector>

namespace glaze {

enum class PreviewIntegrator { path, sh };

// The integrator registered as `name` (integrator_registry.h); throws glaze::Error for an
// unknown name or one the preview does not show.
PreviewIntegrator preview_integrator(std::string_view name);

// One published state; immutable once published.
struct PreviewFrame {
  uint64_t version = 0;        // 1, 2, 3, ... in publishing order
  uint64_t camera_serial = 0;  // which set_camera() it belongs to
  PinholeCamera camera;
  Image path;  // mean of the path passes (black before the first)
  int path_spp = 0;
  double path_seconds = 0;                 // render time of those passes
  std::vector<float> path_relative_error;  // per pixel; NaN where unknown
  Image sh;                                // empty until the first sh step
  int sh_ss = 0;                           // its K (0: none yet)
  double sh_seconds = 0;                   // render time of that sh image
  std::vector<float> n_dot_v;              // per pixel centre; NaN where the ray misses
};

struct PreviewRendererOptions {
  ShIntegratorOptions sh;  // lmax, ss (the final K), threads
  RenderOptions path;      // seed, threads (spp is forced to 1 per pass)
  int max_spp = 4096;      // path passes stop here
  // Each published frame waits until wait_newer() has returned it: every step is seen,
  // in order, so that N frames always show the same image (--frames, tests).
  bool lockstep = false;
};

class PreviewRenderer {
 public:
  PreviewRenderer(const Scene& scene, const RayTracer& tracer, const Environment& environment, const PathTracer& path,
                  const PreviewRendererOptions& options, const PinholeCamera& camera, PreviewIntegrator integrator);
  ~PreviewRenderer();
  PreviewRenderer(const PreviewRenderer&) = delete;
  PreviewRenderer& operator=(const PreviewRenderer&) = delete;

  // Restarts from nothing with this camera (the running pass is abandoned).
  void set_camera(const PinholeCamera& camera);
  // Which integrator to render first; keeps what has been rendered.
  void set_integrator(PreviewIntegrator integrator);

  // The newest published frame (null before the first). Never waits for rendering.
  // Both rethrow what stopped the worker, if anything did.
  std::shared_ptr<const PreviewFrame> latest() const;
  // Waits until a frame newer than `version` is published and returns it; returns the
  // newest frame as it is when the renderer has nothing left to do (idle).
  std::shared_ptr<const PreviewFrame> wait_newer(uint64_t version) const;

 private:
  void run();
  void render_steps();
  void publish(std::shared_ptr<PreviewFrame> frame);

  const Scene& scene_;
  const RayTracer& tracer_;
  const Environment& environment_;
  const PathTracer& path_;
  const PreviewRendererOptions options_;
  const ShIntegrator sh_;

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;     // new request, or new frame, or idle
  PinholeCamera camera_;                        // guarded by mutex_
  uint64_t camera_serial_ = 1;                  // guarded by mutex_
  PreviewIntegrator integrator_;                // guarded by mutex_
  bool stop_ = false;                           // guarded by mutex_
  bool idle_ = false;                           // guarded by mutex_: nothing left to render
  std::shared_ptr<const PreviewFrame> latest_;  // guarded by mutex_
  mutable uint64_t consumed_ = 0;               // guarded by mutex_: newest version wait_newer() returned
  std::exception_ptr failure_;                  // guarded by mutex_: what stopped the worker
  std::atomic<bool> cancel_{false};             // set with a new camera: abandon the pass
  std::thread worker_;
};

}  // namespace glaze
