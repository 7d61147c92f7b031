// path_tracer.h: the Monte-Carlo path tracer for polished materials under distant
// environment light.
//
// At each surface: next-event estimation by importance sampling the environment, and
// a BSDF sample (mirror or diffuse lobe) that continues the path; the two estimates of
// the diffuse lobe's direct light are combined by multiple importance sampling with the
// power heuristic (Veach 1997). The mirror is a delta, so its light is only ever found
// by the BSDF sample. Russian roulette from the third bounce on. For a single convex
// object (Scene::is_single_convex_object) one bounce is exact and nothing can occlude
// the environment, so no further intersection or shadow rays are traced.
#pragma once

#include "renderer/environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/rng.h"
#include "renderer/scene.h"

#include <string>

namespace glaze {

// Which estimators of direct light are used (all three are unbiased; tests compare them).
enum class DirectLightEstimator { mis, bsdf, environment };
DirectLightEstimator parse_direct_light_estimator(const std::string& name);

struct PathTracerOptions {
  int max_depth = 8;                 // surface interactions along a path; 1 = direct light only
  int russian_roulette_depth = 3;    // first bounce at which paths may be terminated
  DirectLightEstimator estimator = DirectLightEstimator::mis;
  bool black_background = false;     // camera rays that miss return 0 (capture sets)
};

class PathTracer {
 public:
  PathTracer(const Scene& scene, const RayTracer& tracer, const Environment& environment,
             const PathTracerOptions& options);

  // Radiance arriving at the camera along `ray`.
  RGB radiance(const Ray& ray, Pcg32& rng) const;

  // The depth actually used: 1 for a single convex object, else options.max_depth.
  int max_depth() const { return max_depth_; }

 private:
  const Scene& scene_;
  const RayTracer& tracer_;
  const Environment& environment_;
  PathTracerOptions options_;
  bool convex_;
  int max_depth_;
};

}  // namespace glaze
