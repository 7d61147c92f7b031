// sphere_outline.h: a sphere's centre and radius from its outline in calibrated views
// (docs/design.md §7), as the paper finds them: "by intersecting the cones defined by the
// camera positions and the conic section that the sphere maps to in each of the images".
//
// Every ray through a point of a view's outline grazes the sphere, so the outline spans a
// cone from the camera's position that is tangent to it. The sphere is found in three
// steps: circle candidates in each view (a Hough transform of its log luminance), the
// sphere of the two views' cones that the other views' images support best, then a few
// rounds of detect-and-fit: the outline edge looked for along the normals of the sphere's
// projected outline at sub-pixel precision, and centre and radius by least squares over
// the cones of all views (Ceres, a robust loss). The log makes an edge's strength its
// contrast, whatever the exposure; the edge looked for is the strongest one near the
// predicted outline in any colour channel, and the robust loss and the edges' rejection
// leave out the few that are a reflection on the sphere or the background's. Where the
// lighting is known, what the coat mirrors just inside the outline (the lighting over
// tens of degrees beyond it, compressed into a pixel or two) is predicted and taken off
// the edges' profiles, so that a detailed background does not move them.
#pragma once

#include "renderer/camera.h"
#include "renderer/environment.h"
#include "renderer/image.h"
#include "renderer/math.h"

#include <string>
#include <vector>

namespace glaze {

// One calibrated view of the sphere.
struct SphereView {
  std::string name;  // the view's folder ("view_000"), for messages
  Image image;       // linear HDR, relative units
  // Optional, one value a pixel (row-major): 0 where the merge saw only saturated codes.
  std::vector<float> alpha;
  // Optional, one value a pixel: 1 on the sphere, 0 off it. Given, its boundary is the
  // outline and the image's content is not looked at.
  std::vector<float> mask;
  PinholeCamera camera;  // registered_camera(): pose in the board's frame, intrinsics, lens
};

struct SphereOutlineOptions {
  int outline_samples = 256;   // edges looked for around each view's outline
  int refinements = 4;         // detect-and-fit rounds
  double blur_pixels = 0.5;    // Gaussian sigma on the image, against noise
  double min_contrast = 0.05;  // weakest edge (log step over a pixel, in one channel) that counts
  double min_found = 0.3;      // fraction of a view's outline that must show an edge
  double disagreement = 4.0;   // a view whose RMS exceeds this times the others' (and 1 px) disagrees
};

// One view's share in the fit.
struct SphereViewFit {
  std::string name;
  int points = 0;               // outline edges used (after the robust rejection)
  int samples = 0;              // places along the outline where an edge was looked for
  double rms_px = 0.0;          // RMS residual of those edges, pixels
  double mean_signed_px = 0.0;  // mean residual, pixels: > 0 where the edges lie outside the fitted outline
  // The rim's mirror was modelled (a lighting was given and the view's background agrees
  // with it), the view's radiance being lighting_scale times the lighting's.
  bool rim_mirror = false;
  RGBd lighting_scale = RGBd::Zero();
  std::vector<Vec2d> edges;    // the edges used, film coordinates (pixels)
  std::vector<Vec2d> outline;  // the fitted sphere's outline, projected through the view's lens
};

struct SphereFit {
  Vec3d center = Vec3d::Zero();  // board frame, metres
  double radius = 0.0;
  double rms_px = 0.0;  // over all views' edges
  double rms_mm = 0.0;  // the same at the sphere: the rays' distance from the tangent cones
  std::vector<SphereViewFit> views;
  std::string solver_summary;  // Ceres's one-line report of the last fit
};

// Locates the sphere that `views` show. Throws glaze::Error, naming the view's folder and
// what to do, when there are fewer than two views, when the sphere is not found in a
// view, and when a view disagrees with the others about where it is.
//
// `lighting`, where known (the light probe, board frame), models what the sphere's coat
// mirrors just inside its outline, which under a detailed background moves the edges
// (sphere_outline.cpp, RimMirror). It is used in each view whose background (the
// lighting seen past the sphere) it matches up to a scale.
SphereFit locate_sphere(const std::vector<SphereView>& views, const SphereOutlineOptions& options = {},
                        const Environment* lighting = nullptr);

// The outline of the sphere (centre, radius) in `camera`'s film: `points` film points
// around it, through the lens; empty when the camera is inside the sphere or any part of
// the outline is behind it.
std::vector<Vec2d> sphere_outline(const PinholeCamera& camera, const Vec3d& center, double radius, int points = 180);

}  // namespace glaze
