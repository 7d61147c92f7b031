// mirror_ball_probe.h: the light probe, a lat-long environment map in board coordinates
// from HDR photographs of a mirror ball taken from several registered camera positions
// (docs/design.md §7, the paper's section 4).
//
// The map is built by inverse sampling: for each texel direction d (board frame) and each
// view, the point on the ball that reflects the ray from the camera's centre o out along d
// is solved for exactly (the cameras stand a few ball diameters away: no orthographic
// approximation), projected through the camera's lens and read bilinearly from the HDR.
// Inverse sampling leaves no holes where the ball's image is compressed (the rim) or
// stretched, which splatting pixels forward would. Each view's sample is weighted by the
// cosine of incidence at the ball (how foreshortened the reflection is there), nothing
// within a few pixels of the ball's outline (blurred with the background), nothing where
// the reflected ray passes near the camera or its tripod (their own reflection, which
// another view sees past) and nothing where a pixel read is saturated (alpha 0). The
// views' samples are merged by their weighted mean and divided by the ball's reflectance.
//
// The map's frame has +Y along the board's +Z (the sky at the top of the image): `to_world`
// (probe_to_board()) is the EnvironmentOptions::to_world that reads it in board coordinates.
#pragma once

#include "renderer/camera.h"
#include "renderer/image.h"
#include "renderer/math.h"
#include "renderer/mirror_ball.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace glaze {

class OutputFolder;

// One photograph of the ball: the merged HDR (linear), its alpha (0: saturated, a lower
// bound left out; empty: every pixel measured) and the registered camera (board frame).
struct ProbeView {
  std::string name;  // "probe_000", for messages and the report
  Image radiance;
  std::vector<float> alpha;
  PinholeCamera camera;
};

struct MirrorBallProbeOptions {
  int width = 256, height = 128;  // of the lat-long map
  // Directions per texel side, averaged: 0 picks enough that the samples are no farther
  // apart than a 256x128 map's texels, so a coarse map is its texels' mean, not a point.
  int samples_per_side = 0;
  RGB reflectance = RGB::Constant(1.0f);  // the ball's, per channel (grey: all three equal)
  // Nothing is read this close (pixels) to the ball's outline, which the lens and the
  // pixels blur with the background.
  double rim_margin_px = 2.0;
  // The camera and its tripod: a capsule of this radius (metres) around the camera's
  // centre and the vertical line below it (the board's -z: the board lies flat), down to
  // `tripod_depth_m` under the ball's centre. A reflected ray that passes through it sees them, and is left out.
  double camera_radius_m = 0.1;
  double tripod_depth_m = 2.0;
};

// One view's part in the map.
struct ProbeViewContribution {
  std::string name;
  double weight_share = 0.0;      // of the map's total weight (solid-angle weighted)
  double covered_fraction = 0.0;  // of the sphere's solid angle it sees with weight > 0
};

struct MirrorBallProbe {
  Image map;                         // lat-long, radiance over the reflectance, map frame
  Mat3 to_world = Mat3::Identity();  // map frame -> board frame (probe_to_board())
  // Per texel (row-major): 1 if a view saw it, 0 where filled in (no view saw it, or every
  // view that did saw it saturated in some direction of the texel: a lower bound).
  std::vector<float> covered;
  double covered_fraction = 0.0;  // of the sphere's solid angle
  std::vector<ProbeViewContribution> views;
};

// The rotation that takes the map's +Y to the board's +Z (and its -Z to the board's +Y,
// +X to +X): a lat-long map in board coordinates with the sky at the top.
Mat3 probe_to_board();

// Where the reflection off `ball` of a ray from `origin` leaves along unit `direction`:
// the reflection whose normal bisects `direction` and the way back to `origin`, or nothing
// when the ball hides that direction from `origin` (behind it) or `origin` is inside it.
// The point lies in the plane of the ball's centre, `origin` and `direction`; Newton's
// method on the normal's angle there (monotone: it converges from any start).
std::optional<BallReflection> ball_point_reflecting(const Vec3d& origin, const Vec3d& direction,
                                                    const MirrorBall& ball);

// The probe from `views` of `ball` (board frame). Directions no view sees (weight 0) are
// filled from their covered neighbours, ring by ring inwards (each texel the mean of its
// filled neighbours), and marked 0 in `covered`. Throws glaze::Error when a view's image
// and camera differ in size or its alpha has the wrong size, when the ball is invalid, or
// when no view sees any direction (naming the views and what to check).
MirrorBallProbe build_mirror_ball_probe(const std::vector<ProbeView>& views, const MirrorBall& ball,
                                        const MirrorBallProbeOptions& options = {});

// Writes the map (EXR, its to_world in the metadata "glaze:to_world", row-major) and the
// coverage mask (PNG, white = seen) into `out`. Returns their paths.
struct ProbeFiles {
  std::string map, mask;
};
ProbeFiles write_mirror_ball_probe(OutputFolder& out, const MirrorBallProbe& probe,
                                   const std::string& map_name = "env.exr", const std::string& mask_name = "mask.png");

// A lat-long `map` whose frame `to_world` takes to the board's (a capture set's world frame:
// Mat3::Identity()), with its coverage (1 = known; empty: all), resampled onto the texels
// of a width x height map in the probe's frame: each texel the mean of the bilinear
// lookups at n x n directions in it (n enough to reach every texel of a finer source),
// known where all of them fall in known texels.
struct LatlongResample {
  Image map;
  std::vector<float> covered;
};
LatlongResample resample_into_probe_frame(const Image& map, const std::vector<float>& covered, const Mat3& to_world,
                                          int width, int height);

// The ball's reflectance from the probe made with reflectance 1 (radiance times the
// reflectance) and an estimate of the lighting at absolute scale on the same texels (same
// size and frame, e.g. a joint fit's map resampled into the probe's frame), each with its
// coverage (1 = known; empty: all). Per channel, the least-squares factor over the texels
// both cover, weighted by solid angle, made robust by Huber weights on the residuals
// (iteratively reweighted, scale from their median absolute deviation): a texel that
// disagrees beyond the noise (a wrong fit there, a reflection) counts less.
struct ReflectanceRatio {
  RGBd reflectance = RGBd::Zero();
  size_t texels = 0;                 // covered by both
  RGBd relative_rms = RGBd::Zero();  // of the residuals probe - reflectance x estimate, over the probe's RMS
};
ReflectanceRatio reflectance_ratio(const Image& probe, const std::vector<float>& probe_covered, const Image& absolute,
                                   const std::vector<float>& absolute_covered);

}  // namespace glaze
