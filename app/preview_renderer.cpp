#include "app/preview_renderer.h"

#include "app/timing.h"
#include "renderer/error.h"
#include "renderer/integrator_registry.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <limits>

namespace glaze {
namespace {

// Path passes rendered before the sh image in path mode.
constexpr int kPathFirstSpp = 8;

std::vector<float> n_dot_v_image(const RayTracer& tracer, const PinholeCamera& camera) {
  std::vector<float> values(size_t(camera.width) * camera.height, std::numeric_limits<float>::quiet_NaN());
  tbb::parallel_for(0, camera.height, [&](int y) {
    for (int x = 0; x < camera.width; ++x) {
      const Ray ray = camera.generate_ray(x + 0.5f, y + 0.5f);
      if (const auto hit = tracer.intersect(ray, std::numeric_limits<float>::infinity(), false))
        values[size_t(y) * camera.width + x] = std::max(0.0f, hit->normal.dot(-ray.direction));
    }
  });
  return values;
}

}  // namespace

PreviewIntegrator preview_integrator(std::string_view name) {
  require_integrator(name);
  if (name == PathIntegrator::kName) return PreviewIntegrator::path;
  if (name == ShIntegrator::kName) return PreviewIntegrator::sh;
  throw Error("the preview shows the path and sh integrators, not '" + std::string(name) + "'");
}

PreviewRenderer::PreviewRenderer(const Scene& scene, const RayTracer& tracer, const Environment& environment,
                                 const PathTracer& path, const PreviewRendererOptions& options,
                                 const PinholeCamera& camera, PreviewIntegrator integrator)
    : scene_(scene),
      tracer_(tracer),
      environment_(environment),
      path_(path),
      options_(options),
      sh_(scene, tracer, environment, options.sh),
      camera_(camera),
      integrator_(integrator),
      worker_([this] { run(); }) {}

PreviewRenderer::~PreviewRenderer() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    cancel_ = true;
  }
  changed_.notify_all();
  worker_.join();
}

void PreviewRenderer::set_camera(const PinholeCamera& camera) {
  {
    std::lock_guard lock(mutex_);
    camera_ = camera;
    ++camera_serial_;
    idle_ = false;
    cancel_ = true;
  }
  changed_.notify_all();
}

void PreviewRenderer::set_integrator(PreviewIntegrator integrator) {
  {
    std::lock_guard lock(mutex_);
    integrator_ = integrator;
    idle_ = false;
  }
  changed_.notify_all();
}

std::shared_ptr<const PreviewFrame> PreviewRenderer::latest() const {
  std::lock_guard lock(mutex_);
  if (failure_) std::rethrow_exception(failure_);
  return latest_;
}

std::shared_ptr<const PreviewFrame> PreviewRenderer::wait_newer(uint64_t version) const {
  std::unique_lock lock(mutex_);
  // Only frames of the current camera: one still on its way from the previous camera is
  // of no interest to a caller that waits (a test, or --frames with --spin).
  changed_.wait(lock, [&] {
    return (latest_ && latest_->version > version && latest_->camera_serial == camera_serial_) || idle_ || stop_;
  });
  if (failure_) std::rethrow_exception(failure_);
  if (latest_) consumed_ = std::max(consumed_, latest_->version);
  changed_.notify_all();
  return latest_;
}

void PreviewRenderer::publish(std::shared_ptr<PreviewFrame> frame) {
  std::unique_lock lock(mutex_);
  frame->version = (latest_ ? latest_->version : 0) + 1;
  const uint64_t version = frame->version, serial = frame->camera_serial;
  latest_ = std::move(frame);
  changed_.notify_all();
  if (options_.lockstep) changed_.wait(lock, [&] { return consumed_ >= version || stop_ || camera_serial_ != serial; });
}

void PreviewRenderer::run() {
  // What the worker throws (out of memory at a large --res, say) ends the rendering and
  // is rethrown to the window's thread by latest() and wait_newer().
  try {
    render_steps();
  } catch (...) {
    std::lock_guard lock(mutex_);
    failure_ = std::current_exception();
    idle_ = true;
    changed_.notify_all();
  }
}

void PreviewRenderer::render_steps() {
  uint64_t serial = 0;
  std::unique_ptr<ProgressiveRender> passes;
  PreviewFrame state;
  bool published_for_camera = false;
  // The sh image is still to render: when sh is shown, or in the background for a
  // scene where it is exact (a single convex object; elsewhere it only warns).
  auto wants_sh = [&](PreviewIntegrator integrator) {
    return state.sh_ss == 0 && (integrator == PreviewIntegrator::sh || scene_.is_single_convex_object());
  };
  RenderOptions path_options = options_.path;
  path_options.spp = 1;
  for (;;) {
    PinholeCamera camera;
    PreviewIntegrator integrator;
    bool restart = false;
    {
      std::unique_lock lock(mutex_);
      for (;;) {
        if (stop_) return;
        if (camera_serial_ != serial || wants_sh(integrator_) || passes->spp() < options_.max_spp) break;
        idle_ = true;
        changed_.notify_all();
        changed_.wait(lock);
      }
      idle_ = false;
      if (camera_serial_ != serial) {
        serial = camera_serial_;
        camera = camera_;
        cancel_ = false;
        restart = true;
      }
      integrator = integrator_;
    }
    if (restart) {
      passes = std::make_unique<ProgressiveRender>(path_, camera, path_options);
      state = PreviewFrame{};
      state.camera_serial = serial;
      state.camera = camera;
      state.path = Image(camera.width, camera.height);
      state.path_relative_error.assign(size_t(camera.width) * camera.height, std::numeric_limits<float>::quiet_NaN());
      state.n_dot_v = n_dot_v_image(tracer_, camera);
      published_for_camera = false;
    }
    const auto start = std::chrono::steady_clock::now();
    const bool sh_next = wants_sh(integrator) && (integrator == PreviewIntegrator::sh ||
                                                  passes->spp() >= kPathFirstSpp || passes->spp() >= options_.max_spp);
    // A camera's first step is never abandoned, even when the camera has moved on by
    // the time it is done: while the mouse drags, every step would otherwise be cut
    // short and the window would show nothing new until the drag stops. It is published
    // (tagged with its own camera) and the next step starts from the newest camera.
    if (sh_next) {
      IntegratorResult sh = sh_.render(state.camera);
      state.sh = std::move(sh.image);
      state.sh_ss = options_.sh.supersampling;
      state.sh_seconds = sh.seconds;
      if (cancel_ && published_for_camera) continue;  // stale, and something is shown already
    } else {
      if (!passes->add_pass(published_for_camera ? &cancel_ : nullptr)) continue;
      state.path_seconds += seconds_since(start);
      state.path = passes->mean();
      state.path_spp = passes->spp();
      state.path_relative_error = passes->relative_standard_error();
    }
    publish(std::make_shared<PreviewFrame>(state));
    published_for_camera = true;
  }
}

}  // namespace glaze
