#include "app/fit_preview.h"

#include "app/invert_fit.h"
#include "renderer/error.h"
#include "renderer/sh_integrator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <optional>

namespace glaze {
namespace {

constexpr int kGutter = 4;  // grey pixels between panels
constexpr int kMaxCanvasWidth = 1800, kMaxCanvasHeight = 1000;

// The mean of each shrink x shrink block (radiance, before the display transform).
Image shrink_image(const Image& image, int shrink) {
  if (shrink == 1) return image;
  Image out(image.width / shrink, image.height / shrink);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x) {
      RGB sum = RGB::Zero();
      for (int j = 0; j < shrink; ++j)
        for (int i = 0; i < shrink; ++i) sum += image.at(x * shrink + i, y * shrink + j);
      out.set(x, y, sum / float(shrink * shrink));
    }
  return out;
}

}  // namespace

FitPreview::FitPreview(const DisplaySettings& display) : display_(display) {
  renderer_ = std::thread([this] { render_loop(); });
}

void FitPreview::begin(std::vector<View> views, const RayTracer& tracer, int lmax, int footprint) {
  if (views.empty()) throw Error("preview: no views to show");
  int width = 0, height = 0;
  for (const View& v : views) width = std::max(width, v.camera.width), height += v.camera.height;
  int shrink = 1;
  while (3 * width / shrink > kMaxCanvasWidth || height / shrink > kMaxCanvasHeight) ++shrink;
  {
    std::lock_guard lock(mutex_);
    views_ = std::move(views);
    tracer_ = &tracer;
    lmax_ = lmax, footprint_ = footprint, shrink_ = shrink;
    for (const View& v : views_) predicted_.emplace_back(v.camera.width, v.camera.height);
    begun_ = true;
  }
  changed_.notify_all();
}

void FitPreview::finish() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return (!has_pending_ && rendered_ == submitted_) || stop_; });
}

FitPreview::~FitPreview() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  renderer_.join();
}

void FitPreview::show(FitPreviewState state) {
  {
    std::lock_guard lock(mutex_);
    if (render_failure_) return;
    pending_ = std::move(state);
    has_pending_ = true;
    ++submitted_;
  }
  changed_.notify_all();
}

void FitPreview::render_loop() {
  for (;;) {
    FitPreviewState state;
    uint64_t serial;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return has_pending_ || stop_; });
      if (stop_) return;
      state = std::move(pending_);
      has_pending_ = false;
      serial = submitted_;
    }
    std::vector<Image> predicted;
    ShIntegratorOptions options;
    options.lmax = lmax_;
    options.supersampling = footprint_;
    options.black_background = true;
    options.approximation_advice = invert_fit::kFitModelAdvice;
    // A failure here (out of memory, a lighting solve that throws) stops the preview,
    // never the fit: it is reported and the window shows no more states.
    try {
      const std::shared_ptr<const Environment> environment = state.environment();
      for (const View& v : views_)
        predicted.push_back(render_sh(*state.scene, *tracer_, *environment, v.camera, options));
    } catch (const std::exception& error) {
      std::fprintf(stderr, "glaze: warning: the preview stops: %s\n", error.what());
      std::lock_guard lock(mutex_);
      render_failure_ = true;
      rendered_ = submitted_ = serial;
      has_pending_ = false;
      changed_.notify_all();
      return;
    }
    {
      std::lock_guard lock(mutex_);
      predicted_ = std::move(predicted);
      shown_label_ = state.label;
      rendered_ = serial;
    }
    changed_.notify_all();
  }
}

std::vector<uint8_t> FitPreview::compose(int& width, int& height) {
  std::vector<Image> predicted;
  {
    std::lock_guard lock(mutex_);
    predicted = predicted_;
  }
  int panel_width = 0;
  std::vector<int> row_top;
  height = 0;
  for (const View& v : views_) {
    panel_width = std::max(panel_width, v.camera.width / shrink_);
    row_top.push_back(height);
    height += v.camera.height / shrink_ + kGutter;
  }
  height -= kGutter;
  width = 3 * panel_width + 2 * kGutter;
  std::vector<uint8_t> canvas(size_t(width) * height * 3, 48);
  DisplaySettings residual_display = display_;
  residual_display.exposure_ev += 3.0f;
  for (size_t v = 0; v < views_.size(); ++v) {
    const Image observed = shrink_image(views_[v].observed, shrink_);
    const Image model = shrink_image(predicted[v], shrink_);
    Image residual(observed.width, observed.height);
    for (size_t k = 0; k < residual.pixels.size(); ++k)
      residual.pixels[k] = std::abs(observed.pixels[k] - model.pixels[k]);
    const std::vector<uint8_t> panels[3] = {display_image(observed, display_), display_image(model, display_),
                                            display_image(residual, residual_display)};
    for (int p = 0; p < 3; ++p)
      for (int y = 0; y < observed.height; ++y)
        std::copy_n(&panels[p][size_t(y) * observed.width * 3], size_t(observed.width) * 3,
                    &canvas[(size_t(row_top[v] + y) * width + p * (panel_width + kGutter)) * 3]);
  }
  return canvas;
}

void FitPreview::run(const std::function<void()>& fit, int frames, const std::string& screenshot) {
  std::exception_ptr failure;
  std::thread solver([&] {
    std::exception_ptr caught;
    try {
      fit();
    } catch (...) {
      caught = std::current_exception();
    }
    {
      std::lock_guard lock(mutex_);
      fit_done_ = true;
      fit_failed_ = bool(caught);
      failure = caught;
    }
    changed_.notify_all();
  });
  // Whatever happens here, the solver thread is joined before leaving (a joinable
  // std::thread destroyed by an exception would end the process). The window opens, at
  // the canvas's size, once the fit has told its views (the caller has checked that a
  // display can be opened, so that it did not wait for this to fail).
  std::optional<PreviewWindow> window;
  std::exception_ptr window_failure;
  try {
    bool begun;
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [&] { return begun_ || fit_done_; });
      begun = begun_;
    }
    if (begun) {
      int width, height;
      compose(width, height);
      window.emplace("glaze invert-fit: observed | predicted | residual x8", width, height);
      show_until_closed(*window, frames, screenshot);
    }
  } catch (...) {
    window_failure = std::current_exception();
  }
  bool done;
  {
    std::lock_guard lock(mutex_);
    done = fit_done_;
  }
  const bool closed_early = window && !done;
  window.reset();  // closed now, not frozen on the screen while the fit finishes
  if (closed_early) std::fprintf(stderr, "glaze: the preview window is closed; the fit goes on to its end\n");
  solver.join();
  if (failure) std::rethrow_exception(failure);
  if (window_failure) std::rethrow_exception(window_failure);
}

void FitPreview::show_until_closed(PreviewWindow& window, int frames, const std::string& screenshot) {
  uint64_t drawn = ~uint64_t(0);
  int shown = 0, width = 0, height = 0;
  std::vector<uint8_t> canvas;
  while (!window.should_close()) {
    std::string label;
    uint64_t rendered;
    bool done, begun;
    {
      std::unique_lock lock(mutex_);
      // Headless: nothing is shown until the fit's final state is rendered.
      if (frames > 0) changed_.wait(lock, [&] { return fit_done_ && !has_pending_ && rendered_ == submitted_; });
      if (fit_done_ && (!begun_ || fit_failed_ || render_failure_)) return;  // nothing (more) to show
      done = fit_done_;
      begun = begun_;
      rendered = rendered_;
      label = shown_label_;
    }
    if (begun && rendered != drawn) {
      canvas = compose(width, height);
      drawn = rendered;
      window.set_title("glaze invert-fit | " + (label.empty() ? std::string("starting") : label) +
                       (done ? " | done" : "") + " | observed | predicted | residual x8");
    }
    if (!canvas.empty()) window.draw(width, height, canvas);
    if (frames > 0 && ++shown >= frames) {
      if (!screenshot.empty()) {
        int w, h;
        const std::vector<uint8_t> shot = window.read_back(w, h);
        write_picture(screenshot, w, h, shot, {{"glaze:frames", std::to_string(frames)}});
        std::printf("wrote %s (%dx%d)\n", screenshot.c_str(), w, h);
      }
      window.present();
      return;
    }
    window.present();
    window.wait_events(1.0 / 30.0);
  }
}

}  // namespace glaze
