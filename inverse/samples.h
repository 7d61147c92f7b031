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
  // Its weight in the material fits (1: full): below 1 where 8-bit quantisation is a
  // sizeable part of the value (near-black codes; see quantisation_weight).
  float weight = 1.0f;
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
  std::vector<int> source_bits;     // per frame: its image's Image::source_bits (8: an 8-bit file)
  std::vector<bool> source_lossy;   // per frame: its image's Image::source_lossy (a JPEG)
  DropCounts total_dropped() const;
};

// 8-bit images (PNG, JPEG): a code at the top of the range is the sensor's or the
// encoder's clipping, not the light, and such a pixel counts as saturated whatever the
// set's "saturation"; in a JPEG, whose blocks spread clipping over their neighbours, so
// does every pixel within kJpegClipReach of a code at or above kJpegClipCode.
inline constexpr int kJpegClipCode = 250;
inline constexpr int kJpegClipReach = 8;

// The weight of an observation `value` (linear RGB) of an 8-bit image: per channel
// 1 / (1 + (q / 0.02)^2), with q the relative standard deviation of the code's rounding
// (its step in linear units / sqrt(12) / value), averaged over the channels. Near-black
// codes, whose rounding is a large part of the value, count little (code 0: nothing);
// from code ~30 up a weight is within 20% of 1. 1 for other images.
float quantisation_weight(const Image& image, const RGB& value);

// A pixel is masked where its mask's value, or its image's alpha, is below 0.5.
// Throws glaze::Error naming the file for an image whose size differs from its camera,
// a mask of the wrong size, or a set in which no view sees the object.
SampleSet collect_samples(const CaptureSet& captures, const RayTracer& object, const Scene& object_scene,
                          const SampleOptions& options);

}  // namespace glaze
