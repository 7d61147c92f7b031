// fit_preview.h: `glaze invert-fit --preview`: a window with one row per view, the
// observation beside the fit's prediction and the residual |observed - predicted|
// (eight times brighter: +3 EV), updated as the solver iterates.
//
// The fit (on its own thread) hands over states: a scene carrying the current material
// and the current lighting. A render thread re-renders every view with the fit's own
// pixel model (the sh integrator at the fit's lmax and footprint, as the final
// render_view_NNN.exr) for the newest state only, so the solver never waits for the
// window. Views are shrunk by a whole factor to keep the window on the screen.
// Headless (--frames N): the window waits for the fit to end and its final state to be
// drawn, shows N frames of it and writes --screenshot.
#pragma once

#include "app/preview_window.h"
#include "renderer/camera.h"
#include "renderer/display.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"
#include "renderer/scene.h"

#include <condition_variable>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace glaze {

struct FitPreviewState {
  std::shared_ptr<const Scene> scene;  // the object with the current material
  // The current lighting; called on the render thread, for the newest state only (the
  // joint fit's lighting at an iterate is a solve that the solver should not wait for).
  std::function<std::shared_ptr<const Environment>()> environment;
  std::string label;  // for the title: what the solver is at
};

class FitPreview {
 public:
  struct View {
    PinholeCamera camera;
    Image observed;
  };
  explicit FitPreview(const DisplaySettings& display);
  ~FitPreview();

  // From the fit's thread, in this order: begin() once the views and the fit's pixel
  // model are known (`tracer`, the object's geometry, and whatever the states' lighting
  // functions use must stay alive until finish() returns); show() for every state,
  // returning at once; finish() waits until the last state is rendered.
  void begin(std::vector<View> views, const RayTracer& tracer, int lmax, int footprint);
  void show(FitPreviewState state);
  void finish();

  // Runs the window on this (the main) thread while `fit` runs on another; returns when
  // the window is closed (or, with `frames` > 0, after that many frames of the final
  // state). Rethrows what `fit` threw.
  void run(const std::function<void()>& fit, int frames, const std::string& screenshot);

 private:
  void render_loop();
  std::vector<uint8_t> compose(int& width, int& height);
  void show_until_closed(PreviewWindow& window, int frames, const std::string& screenshot);

  DisplaySettings display_;
  std::vector<View> views_;  // set by begin(), then read-only
  const RayTracer* tracer_ = nullptr;
  int lmax_ = 0, footprint_ = 1, shrink_ = 1;

  std::mutex mutex_;
  std::condition_variable changed_;
  FitPreviewState pending_;  // guarded: newest state not yet rendered
  bool begun_ = false, has_pending_ = false, stop_ = false, fit_done_ = false, fit_failed_ = false,
       render_failure_ = false;
  std::vector<Image> predicted_;           // guarded: the newest rendered state's views
  std::string shown_label_;                // guarded
  uint64_t rendered_ = 0, submitted_ = 0;  // guarded: states rendered / handed over
  std::thread renderer_;
};

}  // namespace glaze
