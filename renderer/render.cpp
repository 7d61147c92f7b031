#include "renderer/render.h"

#include "renderer/checked_math.h"
#include "renderer/error.h"
#include "renderer/low_discrepancy.h"
#include "renderer/memory_budget.h"
#include "renderer/progress_bar.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <mutex>
#include <string>
#include <utility>

namespace glaze {
namespace {

constexpr int kTile = 16;

// A pixel's stream index is camera << kCameraShift plus its index in the image: images up
// to 2^40 pixels, and 2^22 cameras, keep the PCG sequences (2 index, 2 index + 1) distinct
// within their 63 bits.
constexpr int kCameraShift = 40;
constexpr uint64_t kCameraCount = uint64_t(1) << 22;

// Peak bytes per pixel of a path-traced render: the running sums (24), the pass (24),
// the luminance moments (16), the mean image (12) and the image as it is written.
// Measured with /usr/bin/time -v (maximum resident size) for `glaze render` of
// red_sphere_office at 2048x2048 against 256x256, 1 spp: 73 bytes.
constexpr uint64_t kFilmBytesPerPixel = 80;

}  // namespace

ProgressiveRender::ProgressiveRender(const PathTracer& tracer, const PinholeCamera& camera,
                                     const RenderOptions& options, uint64_t camera_index)
    : tracer_(tracer),
      camera_(camera),
      options_(options),
      camera_index_(camera_index),
      arena_(options.threads > 0 ? options.threads : tbb::task_arena::automatic) {
  if (options.spp < 1) throw Error("samples per pixel must be at least 1");
  if (camera_index >= kCameraCount) throw Error("camera index " + std::to_string(camera_index) + " is too large");
  if (options.spp > kMaxSamplesPerPixel)
    throw Error(std::to_string(options.spp) + " samples per pixel in one pass is more than the " +
                std::to_string(kMaxSamplesPerPixel) + " a render takes");
  const size_t pixels = size_t(camera.width) * camera.height;
  if (pixels >= (uint64_t(1) << kCameraShift)) throw Error("the image has too many pixels to render");
  require_memory(saturating_mul(pixels, kFilmBytesPerPixel), "the film of camera '" + camera.name + "' (" +
                                                                 std::to_string(camera.width) + "x" +
                                                                 std::to_string(camera.height) + ")");
  sum_.assign(pixels * 3, 0.0);
  pass_.assign(pixels * 3, 0.0);
  luminance_sum_.assign(pixels, 0.0);
  luminance_sq_sum_.assign(pixels, 0.0);
}

int ProgressiveRender::tile_count() const {
  return ((camera_.width + kTile - 1) / kTile) * ((camera_.height + kTile - 1) / kTile);
}

bool ProgressiveRender::add_pass(const std::atomic<bool>* cancel, const std::function<void()>& tile_done) {
  if (full())
    throw Error("the render has " + std::to_string(spp()) + " samples per pixel; another pass would take it past " +
                std::to_string(kMaxSamplesPerPixel));
  const int width = camera_.width, height = camera_.height, spp = options_.spp, pass = passes_;
  const int tiles_x = (width + kTile - 1) / kTile;
  std::atomic<bool> cancelled{false};
  arena_.execute([&] {
    tbb::parallel_for(0, tile_count(), [&](int tile) {
      if (cancel && cancel->load(std::memory_order_relaxed)) {
        cancelled = true;
        return;
      }
      const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
      std::vector<Ray> rays(spp);
      std::vector<RGB> radiance(spp);
      for (int y = y0; y < std::min(y0 + kTile, height); ++y) {
        for (int x = x0; x < std::min(x0 + kTile, width); ++x) {
          const uint64_t pixel = uint64_t(y) * width + x;
          // Two streams per pixel (PCG sequences 2i and 2i + 1, i its index among all
          // cameras' pixels): the scramble, one for all passes so that passes continue one
          // sequence, and the path samples.
          const uint64_t stream = (camera_index_ << kCameraShift) + pixel;
          Pcg32 scramble(options_.seed, 2 * stream);
          const uint32_t scramble_x = scramble.next_uint(), scramble_y = scramble.next_uint();
          Pcg32 rng(options_.seed * 0x9E3779B97F4A7C15ULL + uint64_t(pass), 2 * stream + 1);
          for (int s = 0; s < spp; ++s) {
            const Vec2 offset = options_.pixel_centres
                                    ? Vec2(0.5f, 0.5f)
                                    : scrambled_sobol_2d(uint32_t(pass * spp + s), scramble_x, scramble_y);
            rays[s] = camera_.generate_ray(x + offset.x(), y + offset.y());
          }
          tracer_.radiance(rays.data(), spp, rng, radiance.data());
          RGBd pixel_sum = RGBd::Zero();
          for (int s = 0; s < spp; ++s) pixel_sum += radiance[s].cast<double>();
          for (int c = 0; c < 3; ++c) pass_[pixel * 3 + c] = pixel_sum[c];
        }
      }
      if (tile_done) tile_done();
    });
  });
  if (cancelled) return false;
  for (size_t pixel = 0; pixel < luminance_sum_.size(); ++pixel) {
    const double* p = &pass_[pixel * 3];
    for (int c = 0; c < 3; ++c) sum_[pixel * 3 + c] += p[c];
    const double y = luminance(RGB(float(p[0] / spp), float(p[1] / spp), float(p[2] / spp)));
    luminance_sum_[pixel] += y;
    luminance_sq_sum_[pixel] += y * y;
  }
  ++passes_;
  return true;
}

Image ProgressiveRender::mean(size_t* non_finite) const {
  Image image(camera_.width, camera_.height);
  size_t bad = 0;
  if (passes_ > 0) {
    for (size_t k = 0; k < sum_.size(); ++k) {
      double value = sum_[k] / spp();
      if (!std::isfinite(value)) {
        value = 0.0;
        ++bad;
      }
      image.pixels[k] = static_cast<float>(value);
    }
  }
  if (non_finite) *non_finite = bad;
  return image;
}

std::vector<float> ProgressiveRender::relative_standard_error() const {
  std::vector<float> error(luminance_sum_.size(), std::numeric_limits<float>::quiet_NaN());
  if (passes_ < 2) return error;
  const double n = passes_;
  for (size_t pixel = 0; pixel < error.size(); ++pixel) {
    const double mean = luminance_sum_[pixel] / n;
    if (!(mean > 0.0)) continue;
    // Unbiased variance of one pass, then of the mean of n passes.
    const double variance = std::max(0.0, (luminance_sq_sum_[pixel] - n * mean * mean) / (n - 1.0));
    error[pixel] = static_cast<float>(std::sqrt(variance / n) / mean);
  }
  return error;
}

RenderResult render(const PathTracer& tracer, const PinholeCamera& camera, const RenderOptions& options,
                    uint64_t camera_index) {
  ProgressiveRender passes(tracer, camera, options, camera_index);
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  do {
    ProgressBar progress(options.progress && options.time_budget <= 0.0, passes.tile_count());
    passes.add_pass(nullptr, [&] { progress.advance(); });
  } while (options.time_budget > 0.0 && elapsed() < options.time_budget && !passes.full());
  if (options.time_budget > 0.0 && passes.full() && elapsed() < options.time_budget)
    warn("the render stopped at " + std::to_string(passes.spp()) + " samples per pixel, the most it takes (" +
         std::to_string(kMaxSamplesPerPixel) + "), before its time budget was spent");

  RenderResult result;
  result.spp = passes.spp();
  result.seconds = elapsed();
  size_t non_finite = 0;
  result.image = passes.mean(&non_finite);
  if (non_finite > 0) warn(std::to_string(non_finite) + " pixel values were not finite and were set to 0");
  return result;
}

IntegratorResult PathIntegrator::render_camera(const PinholeCamera& camera, uint64_t camera_index) const {
  RenderResult rendered = glaze::render(tracer_, camera, options_, camera_index);
  IntegratorResult result;
  result.image = std::move(rendered.image);
  result.seconds = rendered.seconds;
  result.metadata = {{"glaze:integrator", std::string(kName)},
                     {"glaze:spp", std::to_string(rendered.spp)},
                     {"glaze:seed", std::to_string(options_.seed)},
                     {"glaze:max_depth", std::to_string(tracer_.max_depth())}};
  result.summary = std::to_string(rendered.spp) + " spp";
  return result;
}

}  // namespace glaze
