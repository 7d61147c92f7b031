// footprint.h: which rays model an observation. A pixel records the mean radiance over
// its area, so a pixel sample is modelled by `footprint` x `footprint` rays through the
// sh integrator's sub-pixel points (pixel_grid.h, its --ss positions); a point sample,
// read bilinearly between four pixel centres, by the same bilinear blend of those pixels.
// The material fit and the lighting fit build their models from these rays, so that
// both see a pixel the same way.
#pragma once

#include "inverse/samples.h"
#include "renderer/pixel_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

namespace glaze {

struct FootprintRay {
  Vec3 normal;  // the shading normal where the ray hits, facing the camera
  Vec3 view;    // unit, towards the camera
};

// Calls pixel(centre_normal, rays, weight) for every pixel that models sample k:
// `centre_normal` the normal seen through the pixel centre (a pixel sample's own), `rays`
// the footprint rays that hit the object, `weight` the pixel's share of the sample (1 for
// a pixel sample, bilinear for a point). Each ray's own share is weight / rays.size().
// The footprint's rays are cast kLanes at a time (RayTracer's SIMD lanes). `rays` is
// per-thread storage, reused by the next pixel: `pixel` must not start parallel work,
// whose tasks this thread could run meanwhile.
template <typename PixelVisit>
void for_each_model_pixel(const SampleSet& samples, size_t k, const CaptureSet& captures, const RayTracer& tracer,
                          int footprint, PixelVisit&& pixel) {
  const Sample& s = samples.samples[k];
  const PinholeCamera& camera = captures.frames[s.frame].camera;
  // Per thread, their room reused (not allocated per sample).
  thread_local std::vector<FootprintRay> rays;
  thread_local std::vector<Ray> grid;
  // centre_normal: the normal through the pixel centre when the caller has it (a pixel sample).
  auto visit = [&](int px, int py, float weight, std::optional<Vec3> centre_normal) {
    if (weight == 0.0f) return;
    const Ray centre_ray = camera.generate_ray(px + 0.5f, py + 0.5f);
    if (!centre_normal) {
      const std::optional<SurfaceHit> centre =
          tracer.intersect(centre_ray, std::numeric_limits<float>::infinity(), false);
      if (!centre) return;  // interior pixels always hit; kept safe
      centre_normal = centre->normal;
    }
    rays.clear();
    if (footprint == 1) {  // the centre ray itself
      rays.push_back({*centre_normal, -centre_ray.direction});
    } else {
      grid.clear();
      for (int j = 0; j < footprint; ++j)
        for (int i = 0; i < footprint; ++i)
          grid.push_back(
              camera.generate_ray(pixel_grid_coordinate(px, i, footprint), pixel_grid_coordinate(py, j, footprint)));
      SurfaceHits hits;
      for (size_t first = 0; first < grid.size(); first += kLanes) {
        const int count = int(std::min(grid.size() - first, size_t(kLanes)));
        tracer.intersect(&grid[first], count, hits, false);
        for (int lane = 0; lane < count; ++lane)
          if (hits.hit[lane]) rays.push_back({hits.normal[lane], -grid[first + lane].direction});
      }
    }
    if (!rays.empty()) pixel(*centre_normal, rays, weight);
  };
  if (samples.pixels) {
    visit(int(std::floor(s.film.x())), int(std::floor(s.film.y())), 1.0f, s.normal);
    return;
  }
  const float x = s.film.x() - 0.5f, y = s.film.y() - 0.5f;
  const int x0 = int(std::floor(x)), y0 = int(std::floor(y));
  const float tx = x - x0, ty = y - y0;
  for (int dy = 0; dy <= 1; ++dy)
    for (int dx = 0; dx <= 1; ++dx)
      visit(x0 + dx, y0 + dy, (dx ? tx : 1.0f - tx) * (dy ? ty : 1.0f - ty), std::nullopt);
}

}  // namespace glaze
