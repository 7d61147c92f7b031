// simulate_shoot_command.cpp: `glaze simulate-shoot SCENE --out SHOOT`, a photo shoot
// simulated from a scene of one sphere (inverse/photos/shoot_simulator.h): board photos,
// exposure brackets and mirror-ball photos as a camera would record them, in the layout
// `glaze hdr-merge` and `glaze register` read, with the truth in SHOOT/simulation.json.
#include "app/commands.h"
#include "app/shared_options.h"
#include "inverse/photos/shoot_simulator.h"
#include "renderer/error.h"

#include <cstdio>
#include <memory>
#include <optional>

namespace glaze {

namespace {

struct SimulateShootArgs {
  ShootSimulation simulation;
  EnvironmentOverride environment;
  Resolution resolution{640, 480};
  std::string board = "9x6";
  std::string lens;
  std::optional<float> fov;
  bool no_noise = false, no_probe = false, no_reflectance = false;
};

int simulate(SimulateShootArgs& args) {
  ShootSimulation& simulation = args.simulation;
  simulation.width = args.resolution.width;
  simulation.height = args.resolution.height;
  if (std::sscanf(args.board.c_str(), "%dx%d", &simulation.board.cols, &simulation.board.rows) != 2)
    throw Error("--board takes COLSxROWS inner corners, e.g. 9x6, not \"" + args.board + "\"");
  simulation.fov_degrees = args.fov.value_or(0.0f);
  if (!args.lens.empty()) simulation.lens = parse_lens(args.lens);
  if (args.environment.source || args.environment.scale || args.environment.rotation_degrees)
    simulation.environment = environment_spec(load_scene(simulation.scene), args.environment);
  simulation.camera.noise = !args.no_noise;
  simulation.probe = !args.no_probe;
  simulation.write_reflectance = !args.no_reflectance;
  simulation.progress = true;
  const SimulatedShoot shoot = simulate_shoot(simulation);
  std::printf("wrote %s: %zu views%s, %zu exposures %.3g to %.3g s, board %dx%d of %.1f mm squares, in %.1f s\n",
              shoot.folder.string().c_str(), shoot.views.size(), shoot.probes.empty() ? "" : " and their probes",
              shoot.exposures.size(), shoot.exposures.front(), shoot.exposures.back(), shoot.board.cols,
              shoot.board.rows, 1000 * shoot.board.square, shoot.seconds);
  std::printf("the truth: %s\n", (shoot.folder / "simulation.json").string().c_str());
  return 0;
}

}  // namespace

CommandRun declare_simulate_shoot(CLI::App& app) {
  auto args = std::make_shared<SimulateShootArgs>();
  ShootSimulation& s = args->simulation;
  app.description(
      "simulate a photo shoot of a scene's sphere: board photos, exposure brackets and mirror-ball photos through "
      "a camera with noise, a tone curve and a lens, and the truth (simulation.json)");
  add_scene(app, s.scene);
  add_text(app, "--out SHOOT", s.out, "the shoot folder to write (must not hold a shoot yet)")->required();
  add_environment_override(app, args->environment);
  add_real(app, "--radius M", s.radius, "the sphere's radius in metres: the scene is scaled to it", 1e-4f, 100.0f);
  add_integer(app, "--views N", s.views, 1, 64, "tripod positions on a circle around the sphere");
  add_real(app, "--elevation DEG", s.elevation_degrees, "the cameras' height above the table, in degrees", 1.0f, 89.0f);
  add_real(app, "--distance M", s.distance, "camera to sphere centre in metres (0: 10 radii)", 0.0f, 1e4f);
  add_real(app, "--azimuth DEG", s.azimuth_degrees, "the first view's azimuth about the board's normal");
  add_resolution(app, "--res WxH", args->resolution, "the photos' size");
  add_real(app, "--fov DEG", args->fov, "vertical field of view (default: the board fills 85% of the picture)", 0.0f,
           180.0f);
  add_text(app, "--lens MODEL:NAME=VALUE,...", args->lens, "the lens, as render --lens, e.g. OPENCV:k1=-0.1,k2=0.02");
  add_text(app, "--board COLSxROWS", args->board, "the chessboard's inner corners, one count even, one odd");
  add_real(app, "--square M", s.board.square, "the board's square in metres (0: 3 sphere diameters a row)", 0.0f,
           100.0f);
  add_integer(app, "--board-ss K", s.board_supersampling, 1, 32,
              "the board photos' K x K samples a pixel (4K x 4K on the squares' edges, at most 32 x 32)");
  add_integer(app, "--calibration N", s.calibration_photos, 0, 1000,
              "board photos in varied poses (SHOOT/calibration) for the registration to calibrate from");
  add_integer(app, "--exposures N", s.exposures, 2, 64, "photos per bracket");
  add_real(app, "--ev-step EV", s.ev_step, "stops between exposures", 0.1f, 10.0f);
  add_choice(app, "--format NAME", s.format, {"png", "jpg", "png16"},
             "png, jpg (8-bit through the tone curve) or png16 (16-bit linear)");
  add_real(app, "--full-well E", s.camera.full_well, "electrons at saturation", 100.0f, 1e7f);
  add_real(app, "--read-noise E", s.camera.read_noise, "read noise, electrons RMS", 0.0f, 1e4f);
  app.add_flag("--no-noise", args->no_noise, "photos without shot and read noise");
  add_seed(app, s.seed, "random seed of the camera's noise");
  app.add_flag("--no-probe", args->no_probe, "no mirror-ball photos (probe_NNN)");
  add_real(app, "--ball-radius M", s.ball_radius, "the mirror ball's radius (0: the sphere's)", 0.0f, 100.0f);
  add_real(app, "--reflectance R", s.reflectance, "the mirror ball's reflectance", 0.01f, 1.0f);
  app.add_flag("--no-reflectance", args->no_reflectance, "leave the ball's reflectance out of shoot.json");
  app.add_flag("--give-object", s.write_object, "give the sphere's true centre and radius in shoot.json");
  app.add_flag("--known-intrinsics", s.known_intrinsics, "give the true intrinsics in shoot.json (\"camera\")");
  add_threads(app, s.threads);
  return [args] { return simulate(*args); };
}

}  // namespace glaze
