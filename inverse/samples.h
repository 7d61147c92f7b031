// samples.h: the observations a fit uses (docs/design.md §5), taken from a capture set through
// the renderer's own ray tracer.
//
// Pixel samples: every pixel whose footprint lies on the object (the rays through its
// centre and four corners all hit, see interior_mask) gives one sample at its centre
// ray. Point samples (`points` > 0): points spread uniformly over the object (a
// Fibonacci lattice on a sphere, area-weighted random points on a mesh) are projected
// into every image and read bilinearly where they are visible. Either way a sample is
// dropped, and counted by reason, when the view is grazing (n.v < min_cos), the pixel
// straddles the silhouette, the value is not finite, any channel reaches the set's
// saturation level, or the mask excludes it.
#pragma once

#include "renderer/capture_set.h"
#include "renderer/image.h"
#include "renderer/ray_tracer.h"

#include <cstdint>
#include <vector>

namespace glaze {

struct Sample {
  Vec3 position;
  Vec3 normal;  // unit, shading normal
  Vec3 view;    // unit, from the surface towards the camera
  float mu;     // n.v
  RGB observed;
  Vec2 uv;    // texture coordinate (lat-long of the normal for a sphere)
  int frame;  // index into the capture set's frames
  Vec2 film;  // where it was seen: the pixel centre (pixel samples) or the projected point
};

struct DropCounts {
  size_t grazing = 0, silhouette = 0, non_finite = 0, saturated = 0, masked = 0, hidden = 0;
  size_t total() const { return grazing + silhouette + non_finite + saturated + masked + hidden; }
  DropCounts& operator+=(const DropCounts& other);
};

struct SampleOptions {
  // Default 0.2: below it a pixel spans a wide range of normals and the coat's Fresnel
  // term changes fast, so a centre-ray model of the pixel is least accurate there.
  float min_cos = 0.2f;
  int points = 0;     // 0: pixel samples; else this many points on the object
  uint64_t seed = 0;  // of the points on a mesh
};

struct SampleSet {
  bool pixels = true;               // pixel samples (else points)
  std::vector<Sample> samples;      // frame by frame, in a fixed order
  std::vector<size_t> per_frame;    // samples kept per frame
  std::vector<DropCounts> dropped;  // per frame
  DropCounts total_dropped() const;
};

// Throws glaze::Error naming the file for an image whose size differs from its camera,
// a mask of the wrong size, or a set in which no view sees the object.
SampleSet collect_samples(const CaptureSet& captures, const RayTracer& object, const Scene& object_scene,
                          const SampleOptions& options);

}  // namespace glaze
