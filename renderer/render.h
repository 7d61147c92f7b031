// render.h: renders a camera's image with the path tracer, in parallel over tiles.
//
// Pixel filter: box. Each pixel is the mean of its samples, placed in the pixel's area
// by a scrambled (0, 2)-sequence (low_discrepancy.h): for 2^m samples every elementary
// interval of the pixel holds one, and passes of a time budget continue the sequence.
// Every pixel draws from its own random streams, seeded by (seed, pass, pixel index),
// so the image depends only on the seed and the number of passes, never on the thread
// count or the scheduling.
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"
#include "renderer/path_tracer.h"

#include <cstdint>
#include <functional>

namespace glaze {

struct RenderOptions {
  int spp = 64;                 // samples per pixel (per pass when time_budget > 0)
  double time_budget = 0.0;     // seconds; > 0: render passes of `spp` until it is spent
  uint64_t seed = 0;
  int threads = 0;              // 0: all cores
  bool progress = false;        // a progress bar on stderr
  // Every sample through the pixel centre: no anti-aliasing, a point-sampled image (what
  // the sh integrator renders at ss 1), to compare shading models without pixel filtering.
  bool pixel_centres = false;
};

struct RenderResult {
  Image image;
  int spp = 0;          // samples per pixel actually taken
  double seconds = 0.0;
};

RenderResult render(const PathTracer& tracer, const PinholeCamera& camera, const RenderOptions& options);

}  // namespace glaze
