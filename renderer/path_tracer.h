// path_tracer.h: the Monte-Carlo path tracer for polished materials under distant
// environment light.
//
// At each surface: next-event estimation by importance sampling the environment, and
// a BSDF sample (mirror or diffuse lobe) that continues the path; the two estimates of
// the diffuse lobe's direct light are combined by multiple importance sampling with the
// power heuristic (Veach 1997). The mirror is a delta, so its light is only ever found
// by the BSDF sample. Russian roulette from the third bounce on.
//
// A single convex object (Scene::is_single_convex_object) needs one bounce and nothing
// can occlude the environment, so no shadow rays or further intersections are traced.
// There the mirror term F(n.v) L(r) is evaluated exactly instead of being chosen at
// random against the diffuse lobe (splitting: its noise vanishes), and the diffuse lobe
// is always sampled. That estimator (convex_direct_light.cpp) runs 16 camera rays at a
// time, stage by stage, in SIMD lanes.
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
  int max_depth = 8;               // surface interactions along a path; 1 = direct light only
  int russian_roulette_depth = 3;  // first bounce at which paths may be terminated
  DirectLightEstimator estimator = DirectLightEstimator::mis;
  bool black_background = false;  // camera rays that miss return 0 (capture sets)
  bool convex_shortcut = true;    // use the single-convex-object estimator where it applies
};

class PathTracer {
 public:
  PathTracer(const Scene& scene, const RayTracer& tracer, const Environment& environment,
             const PathTracerOptions& options);

  // Radiance arriving at the camera along `ray`.
  RGB radiance(const Ray& ray, Pcg32& rng) const;
  // The same for `count` rays (the samples of one pixel), into out[0..count).
  void radiance(const Ray* rays, int count, Pcg32& rng, RGB* out) const;

  // The depth actually used: 1 for a single convex object, else options.max_depth.
  int max_depth() const { return max_depth_; }

 private:
  // The paths of rays[0..count), count <= kLanes, advanced together bounce by bounce:
  // the environment's memory reads of all of them (sampling table, texels) are
  // requested before any is used, so that their latencies overlap.
  void trace_paths(const Ray* rays, int count, Pcg32& rng, RGB* out) const;
  void convex_direct_light(const Ray* rays, int count, Pcg32& rng, RGB* out) const;
  // MIS weights of the two strategies for the diffuse lobe's direct light.
  float light_sample_weight(float light_pdf, float bsdf_pdf) const {
    return options_.estimator == DirectLightEstimator::mis ? power_heuristic(light_pdf, bsdf_pdf) : 1.0f;
  }
  float escape_weight(bool after_delta, float bsdf_pdf, float light_pdf) const {
    if (after_delta || options_.estimator == DirectLightEstimator::bsdf) return 1.0f;
    if (options_.estimator == DirectLightEstimator::environment) return 0.0f;
    return power_heuristic(bsdf_pdf, light_pdf);
  }

  const Scene& scene_;
  const RayTracer& tracer_;
  const Environment& environment_;
  PathTracerOptions options_;
  bool convex_;
  int max_depth_;
};

}  // namespace glaze
