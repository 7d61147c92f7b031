#include "renderer/render.h"

#include "renderer/error.h"
#include "renderer/low_discrepancy.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>

namespace glaze {
namespace {

constexpr int kTile = 16;

class ProgressBar {
 public:
  ProgressBar(bool enabled, int total) : enabled_(enabled), total_(total) {}
  void advance() {
    if (!enabled_) return;
    const int done = ++done_;
    const int percent = 100 * done / total_;
    std::lock_guard lock(mutex_);
    if (percent == shown_) return;
    shown_ = percent;
    const int bar = percent / 4;
    std::fprintf(stderr, "\r[%.*s%*s] %3d%%", bar, "=========================", 25 - bar, "", percent);
    if (done == total_) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  int total_;
  std::atomic<int> done_{0};
  std::mutex mutex_;
  int shown_ = -1;
};

}  // namespace

RenderResult render(const PathTracer& tracer, const PinholeCamera& camera, const RenderOptions& options) {
  if (options.spp < 1) throw Error("samples per pixel must be at least 1");
  const int width = camera.width, height = camera.height;
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  std::vector<double> sum(size_t(width) * height * 3, 0.0);
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  int passes = 0;
  do {
    const int pass = passes;
    ProgressBar progress(options.progress && options.time_budget <= 0.0, tiles_x * tiles_y);
    arena.execute([&] {
      tbb::parallel_for(0, tiles_x * tiles_y, [&](int tile) {
        const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
        std::vector<Ray> rays(options.spp);
        std::vector<RGB> radiance(options.spp);
        for (int y = y0; y < std::min(y0 + kTile, height); ++y) {
          for (int x = x0; x < std::min(x0 + kTile, width); ++x) {
            const uint64_t pixel = uint64_t(y) * width + x;
            // Two streams per pixel (PCG sequences 2p and 2p + 1): the scramble, one for
            // all passes so that passes continue one sequence, and the path samples.
            Pcg32 scramble(options.seed, 2 * pixel);
            const uint32_t scramble_x = scramble.next_uint(), scramble_y = scramble.next_uint();
            Pcg32 rng(options.seed * 0x9E3779B97F4A7C15ULL + uint64_t(pass), 2 * pixel + 1);
            for (int s = 0; s < options.spp; ++s) {
              const Vec2 offset = options.pixel_centres
                                      ? Vec2(0.5f, 0.5f)
                                      : scrambled_sobol_2d(uint32_t(pass * options.spp + s), scramble_x, scramble_y);
              rays[s] = camera.generate_ray(x + offset.x(), y + offset.y());
            }
            tracer.radiance(rays.data(), options.spp, rng, radiance.data());
            RGBd pixel_sum = RGBd::Zero();
            for (int s = 0; s < options.spp; ++s) pixel_sum += radiance[s].cast<double>();
            for (int c = 0; c < 3; ++c) sum[pixel * 3 + c] += pixel_sum[c];
          }
        }
        progress.advance();
      });
    });
    ++passes;
  } while (options.time_budget > 0.0 && elapsed() < options.time_budget);

  RenderResult result;
  result.spp = passes * options.spp;
  result.seconds = elapsed();
  result.image = Image(width, height);
  size_t non_finite = 0;
  for (size_t k = 0; k < sum.size(); ++k) {
    double value = sum[k] / result.spp;
    if (!std::isfinite(value)) {
      value = 0.0;
      ++non_finite;
    }
    result.image.pixels[k] = static_cast<float>(value);
  }
  if (non_finite > 0) warn(std::to_string(non_finite) + " pixel values were not finite and were set to 0");
  return result;
}

}  // namespace glaze
