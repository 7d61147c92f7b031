// shoot_simulator.h: a photo shoot simulated from a scene (docs/design.md §7), so that
// the photographs front end can be tried and tested without a camera.
//
// The scene's one analytic sphere is scaled to `radius` metres and set on a table: the
// plane z = 0 of a chessboard's frame (registration.h), the sphere above the board's
// middle. Each view is a tripod position on a circle around the sphere, looking at it:
//
//   calibration/board_K.png the board alone in varied poses, as registration calibrates from
//   view_NNN/board.png      the board (a matte textured quad on a dark table) without the
//                           sphere, under a uniform light of the environment's mean (the
//                           sh integrator, exact there), photographed at one exposure (the
//                           paper below clipping)
//   view_NNN/bracket_K.png  the sphere without the board, rendered once in HDR by the sh
//                           integrator (exact for a lone sphere), then photographed at
//                           each exposure; exposures.json gives the times
//   probe_NNN/              the same with a mirror ball in the sphere's place, rendered
//                           analytically (each ray reflected exactly off the ball); the
//                           camera and its tripod are dark occluders the ball reflects
//   shoot.json              the board, the object, the probe (design §7)
//   simulation.json         the truth (below)
//
// The camera (CameraModel): signal = radiance x time in units of the full well, shot
// noise (Poisson, as a Gaussian), read noise, clipping at the full well, a film-like
// tone curve that is not a power law, 8-bit codes (or 16-bit linear codes). Every
// pixel's noise comes from its own random stream, keyed by the seed, the photo and the
// row, so the photos do not depend on the thread count.
//
// simulation.json holds what the pipeline should recover, all in the board's frame
// (metres, cameras OpenGL camera-to-world): "object" {"center", "radius", "R0", "Rd"},
// "probe" {"center", "radius", "reflectance"}, "views" and "probes" (per folder: "name",
// "transform_matrix" and the intrinsics as transforms.json holds them: w h fl_x fl_y cx cy,
// "camera_model" and its coefficients), "board_to_scene" (4x4: board metres to the glTF's own units and axes),
// "environment" (a capture set's entry: the lighting in the board's frame),
// "exposures" (seconds) and "hdr_unit" [u_r, u_g, u_b]: a bracket merged by `glaze
// hdr-merge` (its recovered response fixed at code 128 = 1) is u x the true radiance.
#pragma once

#include "inverse/photos/shoot.h"
#include "renderer/image.h"
#include "renderer/lens_distortion.h"
#include "renderer/scene.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace glaze {

// The camera's sensor and tone curve, from radiance to codes.
struct CameraModel {
  double full_well = 30000.0;  // electrons at the top of the range (signal 1)
  double read_noise = 4.0;     // electrons, RMS
  bool noise = true;
};

// The film-like tone curve, code / 255 for a signal s (1 = the full well): 1.06 (1 -
// exp(-3 s^0.7)), clipped at 1. A toe like s^0.7 and a shoulder; not a power law, so that
// a recovered response is tested, not assumed.
double film_curve(double signal);
// Its inverse for code / 255 = v < 1.
double film_curve_inverse(double v);

// `radiance` (linear, any size) photographed for `seconds`: signal = radiance x seconds,
// with `camera`'s noise from streams keyed by (seed, photo), codes per channel: 8-bit
// through the tone curve, or 16-bit linear (`bits`).
PhotoCodes photograph(const Image& radiance, double seconds, const CameraModel& camera, int bits, uint64_t seed,
                      uint64_t photo);

// A chessboard as a matte, textured quad in the z = 0 plane of its own frame, facing +z:
// inner corner (i, j) at (i, j, 0) squares, a white margin one square wide around the
// squares, square (0, 0) (outside corner (0, 0)) black, so that chessboard.h reads the
// frame back. The texture has one texel per square, sampled nearest, so that its edges
// are exact. Appended to `scene` (a mesh, a material with R0 = 0, a texture), moved by
// `board_to_world`.
void add_board(Scene& scene, const BoardSpec& board,
               const Eigen::Affine3f& board_to_world = Eigen::Affine3f::Identity());

// A camera at `eye` looking at `target`, its picture's up towards `up`.
Eigen::Affine3f look_at(const Vec3& eye, const Vec3& target, const Vec3& up);

struct ShootSimulation {
  std::string scene;  // glTF with one analytic sphere (node extras.glaze.sphere)
  // The lighting instead of the scene's (glaze render's --env, --env-scale, --env-rotation
  // make one); unset: the scene's.
  std::optional<EnvironmentSpec> environment;
  std::filesystem::path out;  // the shoot folder (created; must not hold a shoot.json)

  double radius = 0.05;  // the sphere's radius, metres: the scene is scaled to it
  int views = 3;
  double elevation_degrees = 30.0;
  double distance = 0.0;          // camera to sphere centre, metres; 0: 10 radii
  double azimuth_degrees = 20.0;  // of the first view; the others evenly around
  int width = 640, height = 480;
  double fov_degrees = 0.0;  // vertical; 0: the board (with its margin) fills about 85% of the smaller field
  LensDistortion lens;       // opencv model expected, as registration recovers it

  BoardSpec board{9, 6, 0.0};  // square 0: the squares span 3 sphere diameters along a row
  // The board photos' K x K samples a pixel, 4K x 4K (at most 32 x 32) where an edge
  // crosses the pixel: a camera integrates each pixel's area, and the corners' positions
  // follow from the edge pixels' coverage.
  int board_supersampling = 4;
  int calibration_photos = 8;  // calibration/board_K: the board alone in varied poses

  int exposures = 7;
  double ev_step = 2.0;
  std::string format = "png";  // png, jpg (8-bit through the curve) or png16 (16-bit linear)
  CameraModel camera;          // the codes' bits are the format's
  uint64_t seed = 0;
  int threads = 0;  // 0: all cores

  bool probe = true;
  double ball_radius = 0.0;  // 0: the sphere's radius
  double reflectance = 0.6;
  int probe_supersampling = 4;    // K x K rays a pixel
  bool write_reflectance = true;  // shoot.json's "probe.reflectance"
  bool write_object = false;      // shoot.json's "object.center" and "radius" (the truth)
  bool known_intrinsics = false;  // shoot.json's "camera"
  bool progress = false;
  bool keep_radiance = false;  // keep each bracket's true radiance in SimulatedShoot (tests)
};

struct SimulatedView {
  std::string name;  // "view_000", "probe_000"
  PinholeCamera camera;
};

struct SimulatedShoot {
  std::filesystem::path folder;
  BoardSpec board;
  Vec3d sphere_center;  // board frame, metres
  double sphere_radius = 0.0;
  PolishedMaterial material{0.0f, RGB::Ones()};  // the sphere's (its texture, if any, at uv (0.5, 0.5))
  Vec3d ball_center;
  double ball_radius = 0.0, reflectance = 0.0;
  std::vector<SimulatedView> views, probes;
  std::vector<Image> radiance;    // each bracket's true radiance (views, then probes), when keep_radiance
  std::vector<double> exposures;  // seconds, shortest first
  RGB hdr_unit = RGB::Ones();     // merged HDR = hdr_unit x radiance (simulation.json)
  Eigen::Matrix4d board_to_scene;
  EnvironmentSpec environment;  // the lighting in the board's frame (make_environment)
  double seconds = 0.0;
};

// Simulates the shoot and writes options.out. Throws glaze::Error naming the scene when it
// is not one analytic sphere, and for options out of range.
SimulatedShoot simulate_shoot(const ShootSimulation& options);

// The radiance of the probe's photo seen by `camera` (K x K rays a pixel): the ball's
// reflection (x reflectance) where a ray meets it, the camera and tripod as dark
// occluders of the reflected rays, the environment elsewhere.
Image render_probe(const Environment& environment, const PinholeCamera& camera, const Vec3d& ball_center,
                   double ball_radius, double reflectance, int supersampling, int threads = 0);

// The dark camera and tripod the probe reflects: a sphere of this radius at the camera's
// centre and a vertical cylinder down to the table, and their radiance relative to the
// environment's mean.
inline constexpr double kCameraBodyRadius = 0.04, kTripodRadius = 0.012, kOccluderAlbedo = 0.03;

}  // namespace glaze
