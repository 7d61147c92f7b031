#include "inverse/photos/shoot_simulator.h"

#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/memory_budget.h"
#include "renderer/mirror_ball.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/rng.h"
#include "renderer/sh.h"
#include "renderer/sh_integrator.h"
#include "renderer/text_file.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace glaze {

namespace {

using nlohmann::json;

// The board's texels: linear reflectances of a printed board's white paper and black ink.
constexpr float kWhite = 0.79f, kBlack = 0.007f;

// The luminance below which `fraction` of the image's pixels lie.
double luminance_quantile(const Image& image, double fraction) {
  std::vector<float> values(size_t(image.width) * image.height);
  for (size_t p = 0; p < values.size(); ++p)
    values[p] = luminance(RGB(image.pixels[3 * p], image.pixels[3 * p + 1], image.pixels[3 * p + 2]));
  const auto at = values.begin() + std::min(values.size() - 1, size_t(fraction * values.size()));
  std::nth_element(values.begin(), at, values.end());
  return std::max(*at, 1e-20f);
}

// The environment's mean radiance over the sphere of directions (its lat-long texels
// weighted by their solid angle), for the occluders' dark grey.
RGB mean_radiance(const Environment& environment) {
  const Image& map = environment.map();
  RGB sum = RGB::Zero();
  double weight = 0.0;
  for (int y = 0; y < map.height; ++y) {
    const double w = std::sin(kPi * (y + 0.5) / map.height);
    for (int x = 0; x < map.width; ++x) {
      const float* p = &map.pixels[3 * (size_t(y) * map.width + x)];
      sum += float(w) * RGB(p[0], p[1], p[2]);
    }
    weight += w * map.width;
  }
  return environment.scale() * sum / float(weight);
}

// Distance along origin + t direction to the vertical cylinder of `radius` about the axis
// through `base` (z from base.z to top), or infinity.
double cylinder_hit(const Vec3d& origin, const Vec3d& direction, const Vec3d& base, double top, double radius) {
  const double ox = origin.x() - base.x(), oy = origin.y() - base.y();
  const double a = direction.x() * direction.x() + direction.y() * direction.y();
  if (a <= 0.0) return INFINITY;
  const double half_b = ox * direction.x() + oy * direction.y(), c = ox * ox + oy * oy - radius * radius;
  const double discriminant = half_b * half_b - a * c;
  if (discriminant < 0.0) return INFINITY;
  for (const double t : {(-half_b - std::sqrt(discriminant)) / a, (-half_b + std::sqrt(discriminant)) / a}) {
    const double z = origin.z() + t * direction.z();
    if (t > 0.0 && z >= base.z() && z <= top) return t;
  }
  return INFINITY;
}

std::vector<std::vector<double>> rows_of(const Eigen::Matrix4d& m) {
  std::vector<std::vector<double>> rows(4);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) rows[r].push_back(m(r, c));
  return rows;
}

json camera_json(const SimulatedView& view) {
  json entry = intrinsics_json(view.camera);
  entry["name"] = view.name;
  entry["transform_matrix"] = rows_of(view.camera.camera_to_world.matrix().cast<double>());
  return entry;
}

// Whether the board, its margin included, is inside `camera`'s picture.
bool board_in_picture(const PinholeCamera& camera, const BoardSpec& board) {
  const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
  const float s = float(board.square);
  for (const Vec2& corner :
       {Vec2(-2, -2), Vec2(board.cols + 1, -2), Vec2(board.cols + 1, board.rows + 1), Vec2(-2, board.rows + 1)}) {
    const std::optional<Vec2> p = camera.project(world_to_camera * Vec3(s * corner.x(), s * corner.y(), 0));
    if (!p || !(p->x() > 0 && p->x() < camera.width && p->y() > 0 && p->y() < camera.height)) return false;
  }
  return true;
}

// The vertical field of view (radians) in which the board, its margin included, fills
// 85% of the picture's tighter direction, seen from `pose`.
float fitting_fov(const Eigen::Affine3f& pose, const BoardSpec& board, int width, int height) {
  const Eigen::Affine3f world_to_camera = pose.inverse();
  const float s = float(board.square);
  float x = 0, y = 0;
  for (const Vec2& corner :
       {Vec2(-2, -2), Vec2(board.cols + 1, -2), Vec2(board.cols + 1, board.rows + 1), Vec2(-2, board.rows + 1)}) {
    const Vec3 local = world_to_camera * Vec3(s * corner.x(), s * corner.y(), 0);
    x = std::max(x, std::abs(local.x() / local.z()));
    y = std::max(y, std::abs(local.y() / local.z()));
  }
  const float focal = 0.85f * std::min(0.5f * width / x, 0.5f * height / y);
  return 2.0f * std::atan(0.5f * height / focal);
}

void check(bool ok, const std::string& message) {
  if (!ok) throw Error("simulate-shoot: " + message);
}

}  // namespace

double film_curve(double signal) {
  return std::min(1.0, 1.06 * (1.0 - std::exp(-3.0 * std::pow(std::max(signal, 0.0), 0.7))));
}

double film_curve_inverse(double v) { return std::pow(-std::log(1.0 - v / 1.06) / 3.0, 1.0 / 0.7); }

PhotoCodes photograph(const Image& radiance, double seconds, const CameraModel& camera, int bits, uint64_t seed,
                      uint64_t photo) {
  if (bits != 8 && bits != 16) throw Error("internal: photographs are 8- or 16-bit, not " + std::to_string(bits));
  PhotoCodes codes{radiance.width, radiance.height, bits, bits == 16, std::vector<uint16_t>(radiance.pixels.size())};
  const double top = bits == 16 ? 65535.0 : 255.0;
  tbb::parallel_for(0, radiance.height, [&](int y) {
    // One stream a row, keyed by the photo: the codes do not depend on the threads.
    Pcg32 rng(seed, (photo << 24) + uint64_t(y));
    const auto gaussian = [&rng] {  // Box-Muller
      const double u = std::max<double>(rng.next_float(), 1e-9), v = rng.next_float();
      return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * M_PI * v);
    };
    for (size_t i = size_t(y) * radiance.width * 3; i < size_t(y + 1) * radiance.width * 3; ++i) {
      double electrons = std::max(0.0, double(radiance.pixels[i]) * seconds) * camera.full_well;
      if (camera.noise) electrons += std::sqrt(electrons) * gaussian() + camera.read_noise * gaussian();
      const double signal = std::clamp(electrons / camera.full_well, 0.0, 1.0);
      codes.codes[i] = uint16_t(std::lround(top * (bits == 16 ? signal : film_curve(signal))));
    }
  });
  return codes;
}

void add_board(Scene& scene, const BoardSpec& board, const Eigen::Affine3f& board_to_world) {
  const int columns = board.cols + 3, rows = board.rows + 3;  // texels: the squares and the margin
  Texture texture;
  texture.source = "chessboard";
  texture.nearest = true;
  texture.wrap_u = texture.wrap_v = Wrap::clamp;
  texture.image = Image(columns, rows);
  for (int row = 0; row < rows; ++row)
    for (int column = 0; column < columns; ++column) {
      // Square (a, b) spans corners a - 1 .. a along x and b - 1 .. b along y; texel row 0
      // is the top (largest y). Square (0, 0), outside corner (0, 0), is black.
      const int a = column - 1, b = board.rows + 1 - row;
      const bool margin = a < 0 || a > board.cols || b < 0 || b > board.rows;
      const float value = margin || (a + b) % 2 ? kWhite : kBlack;
      for (int c = 0; c < 3; ++c) texture.image.pixels[3 * (size_t(row) * columns + column) + c] = value;
    }
  const float s = float(board.square), x0 = -2 * s, y0 = -2 * s, x1 = (board.cols + 1) * s, y1 = (board.rows + 1) * s;
  TriangleMesh mesh;
  mesh.name = "chessboard";
  for (const Vec3& p : {Vec3(x0, y0, 0), Vec3(x1, y0, 0), Vec3(x1, y1, 0), Vec3(x0, y1, 0)})
    mesh.positions.push_back(board_to_world * p);
  mesh.normals.assign(4, (board_to_world.linear() * Vec3::UnitZ()).normalized());
  mesh.uvs = {Vec2(0, 1), Vec2(1, 1), Vec2(1, 0), Vec2(0, 0)};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.material = int(scene.materials.size());
  SceneMaterial material;
  material.name = "chessboard";
  material.R0 = 0.0f;
  material.texture = int(scene.textures.size());
  scene.materials.push_back(material);
  scene.textures.push_back(std::move(texture));
  scene.meshes.push_back(std::move(mesh));
}

namespace {

// A dark grey table (Rd 0.15) under the board, 1 mm below it and 8 boards wide: the
// board's white margin then stands out from what is around it, as findChessboardCorners
// needs (against a background as bright as the paper it fails).
void add_table(Scene& scene, const BoardSpec& board) {
  const float size = 8.0f * float(board.square) * (board.cols + 3);
  const Vec3 centre(float(board.square) * (board.cols - 1) / 2, float(board.square) * (board.rows - 1) / 2, -0.001f);
  TriangleMesh mesh;
  mesh.name = "table";
  for (const Vec2& corner : {Vec2(-1, -1), Vec2(1, -1), Vec2(1, 1), Vec2(-1, 1)})
    mesh.positions.push_back(centre + 0.5f * size * Vec3(corner.x(), corner.y(), 0));
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.material = int(scene.materials.size());
  SceneMaterial material;
  material.name = "table";
  material.R0 = 0.0f;
  material.Rd = RGB::Constant(0.15f);
  scene.materials.push_back(material);
  scene.meshes.push_back(std::move(mesh));
}

}  // namespace

Eigen::Affine3f look_at(const Vec3& eye, const Vec3& target, const Vec3& up) {
  const Vec3 forward = (target - eye).normalized();
  const Vec3 right = forward.cross(up).normalized();
  Eigen::Affine3f pose = Eigen::Affine3f::Identity();
  pose.linear().col(0) = right;
  pose.linear().col(1) = right.cross(forward);
  pose.linear().col(2) = -forward;
  pose.translation() = eye;
  return pose;
}

Image render_probe(const Environment& environment, const PinholeCamera& camera, const Vec3d& ball_center,
                   double ball_radius, double reflectance, int supersampling, int threads) {
  const MirrorBall ball{ball_center, ball_radius};
  const RGB dark = float(kOccluderAlbedo) * mean_radiance(environment);
  const Vec3d eye = camera.position().cast<double>();
  const int k = supersampling;
  Image image(camera.width, camera.height);
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(0, camera.height, [&](int y) {
      for (int x = 0; x < camera.width; ++x) {
        RGB sum = RGB::Zero();
        for (int j = 0; j < k; ++j)
          for (int i = 0; i < k; ++i) {
            const Ray ray = camera.generate_ray(x + (i + 0.5f) / k, y + (j + 0.5f) / k);
            const std::optional<BallReflection> hit = reflect_off_ball(eye, ray.direction.cast<double>(), ball);
            if (!hit) {
              sum += environment.eval(ray.direction);
              continue;
            }
            // The camera's body and its tripod, down to the table, in the reflected ray's way.
            const Vec3d oc = hit->point - eye;
            const bool body =
                !std::isnan(sphere_hit_distance(oc.x(), oc.y(), oc.z(), hit->direction.x(), hit->direction.y(),
                                                hit->direction.z(), kCameraBodyRadius, 0.0, INFINITY));
            const bool tripod = std::isfinite(
                cylinder_hit(hit->point, hit->direction, Vec3d(eye.x(), eye.y(), 0.0), eye.z(), kTripodRadius));
            sum += body || tripod ? dark : float(reflectance) * environment.eval(hit->direction.cast<float>());
          }
        const RGB mean = sum / float(k * k);
        for (int c = 0; c < 3; ++c) image.pixels[3 * (size_t(y) * camera.width + x) + c] = mean[c];
      }
    });
  });
  return image;
}

SimulatedShoot simulate_shoot(const ShootSimulation& options) {
  const auto start = std::chrono::steady_clock::now();
  check(options.radius > 0 && std::isfinite(options.radius), "--radius must be a positive number of metres");
  check(options.views >= 1, "--views must be at least 1");
  check(options.exposures >= 2, "--exposures must be at least 2 (a bracket)");
  check(options.ev_step > 0, "--ev-step must be positive");
  check(options.width >= 16 && options.height >= 16, "--res must be at least 16x16");
  check(options.board.cols >= 2 && options.board.rows >= 2 && (options.board.cols + options.board.rows) % 2 == 1,
        "--board COLSxROWS needs at least 2 x 2 inner corners, one count even and the other odd");
  check(options.format == "png" || options.format == "jpg" || options.format == "png16",
        "--format must be png, jpg or png16");
  check(options.reflectance > 0 && options.reflectance <= 1, "--reflectance must be in (0, 1]");
  check(options.elevation_degrees > 0 && options.elevation_degrees < 90, "--elevation must be in (0, 90) degrees");

  Scene scene = load_scene(options.scene);
  if (scene.spheres.size() != 1 || !scene.meshes.empty())
    throw Error(options.scene +
                ": the shoot simulator photographs one analytic sphere (node extras.glaze.sphere) and nothing "
                "else; this scene has " +
                std::to_string(scene.spheres.size()) + " spheres and " + std::to_string(scene.meshes.size()) +
                " meshes");
  if (!options.environment && !scene.environment)
    throw Error(options.scene +
                ": the scene names no environment; give the lighting with --env FILE or --env "
                "procedural:office");
  EnvironmentSpec spec = options.environment ? *options.environment : *scene.environment;

  SimulatedShoot shoot;
  shoot.folder = options.out;
  shoot.board = options.board;
  const double r = options.radius;
  if (shoot.board.square <= 0) shoot.board.square = 3 * 2 * r / (shoot.board.cols + 1);
  const BoardSpec& board = shoot.board;

  // The board's frame in the scene's (scaled to metres): x along the scene's +X, z (up
  // from the table) along its +Y, y = z x x along its -Z. The sphere stands on the table
  // above the board's middle.
  Sphere& sphere = scene.spheres.front();
  const double scale = r / sphere.radius;
  Mat3 board_axes;
  board_axes.col(0) = Vec3::UnitX();
  board_axes.col(1) = -Vec3::UnitZ();
  board_axes.col(2) = Vec3::UnitY();
  shoot.sphere_center = Vec3d(board.square * (board.cols - 1) / 2, board.square * (board.rows - 1) / 2, r);
  shoot.sphere_radius = r;
  shoot.board_to_scene = Eigen::Matrix4d::Identity();
  shoot.board_to_scene.topLeftCorner<3, 3>() = board_axes.cast<double>() / scale;
  shoot.board_to_scene.topRightCorner<3, 1>() =
      sphere.center.cast<double>() - board_axes.cast<double>() * shoot.sphere_center / scale;
  shoot.material = scene.material_at(sphere.material, Vec2(0.5f, 0.5f));
  // The scene moved into the board's frame: the sphere, and the environment's rotation
  // folded into its to_world.
  sphere.center = shoot.sphere_center.cast<float>();
  sphere.radius = float(r);
  sphere.rotation = board_axes.transpose() * sphere.rotation;
  spec.options.to_world =
      board_axes.transpose() * rotation_about_y(spec.options.rotation_degrees) * spec.options.to_world;
  spec.options.rotation_degrees = 0.0f;
  shoot.environment = spec;
  const Environment environment = make_environment(spec.source, spec.options, spec.width, spec.height);

  shoot.ball_radius = options.ball_radius > 0 ? options.ball_radius : r;
  shoot.ball_center = Vec3d(shoot.sphere_center.x(), shoot.sphere_center.y(), shoot.ball_radius);
  shoot.reflectance = options.reflectance;

  // The views: a circle around the sphere, looking at its centre, the board's up up.
  const double distance = options.distance > 0 ? options.distance : 10 * r;
  const float elevation = float(options.elevation_degrees * kPi / 180);
  float fov = float(options.fov_degrees * kPi / 180);
  std::vector<Eigen::Affine3f> poses;
  for (int v = 0; v < options.views; ++v) {
    const float azimuth = float((options.azimuth_degrees + 360.0 * v / options.views) * kPi / 180);
    const Vec3 eye = shoot.sphere_center.cast<float>() + float(distance) * Vec3(std::cos(elevation) * std::cos(azimuth),
                                                                                std::cos(elevation) * std::sin(azimuth),
                                                                                std::sin(elevation));
    poses.push_back(look_at(eye, shoot.sphere_center.cast<float>(), Vec3::UnitZ()));
    if (options.fov_degrees <= 0) fov = std::max(fov, fitting_fov(poses.back(), board, options.width, options.height));
  }
  for (const bool probe : {false, true}) {
    if (probe && !options.probe) break;
    for (int v = 0; v < options.views; ++v) {
      char name[32];
      std::snprintf(name, sizeof name, "%s_%03d", probe ? "probe" : "view", v);
      PinholeCamera camera = PinholeCamera::from_vertical_fov(name, poses[v], fov, options.width, options.height);
      camera.distortion = options.lens;
      camera.check_lens(std::string("--lens on view ") + name);
      if (!board_in_picture(camera, board))
        throw Error(std::string("simulate-shoot: ") + name +
                    " does not see the whole board; widen --fov, step back (--distance) or shrink the board "
                    "(--square)");
      (probe ? shoot.probes : shoot.views).push_back({name, camera});
    }
  }

  // Calibration photos: the board tilted 40 to 75 degrees, turned and off centre (poses as
  // a photographer varies them), each as close as the whole board allows.
  const struct {
    float azimuth, elevation, distance, roll, dx, dy;
  } calibration_poses[] = {{0, 50, 0.40f, 0, 0, 0},          {90, 45, 0.39f, 10, 0.01f, 0},
                           {200, 42, 0.415f, -15, 0, 0.01f}, {300, 48, 0.43f, 25, -0.01f, 0},
                           {45, 40, 0.415f, -30, 0, 0},      {150, 52, 0.515f, 40, 0, -0.01f},
                           {250, 40, 0.49f, -45, 0, 0},      {330, 75, 0.515f, 60, 0, 0}};
  std::vector<PinholeCamera> calibration;
  const Vec3 board_centre(float(board.square * (board.cols - 1) / 2), float(board.square * (board.rows - 1) / 2), 0);
  for (int k = 0; k < options.calibration_photos; ++k) {
    const auto& c = calibration_poses[k % std::size(calibration_poses)];
    const float a = (c.azimuth + 17.0f * float(k / std::size(calibration_poses))) * kPi / 180,
                e = c.elevation * kPi / 180, roll = c.roll * kPi / 180;
    const float unit = float(board.square / 0.025);  // the poses are for 25 mm squares and a 600 px focal length
    const Vec3 up = Eigen::AngleAxisf(roll, Vec3::UnitZ()) * Vec3::UnitY();
    const Vec3 target = board_centre + unit * Vec3(c.dx, c.dy, 0);
    for (float distance = unit * c.distance * 0.4f / std::tan(0.5f * fov);; distance *= 1.1f) {
      const Vec3 eye =
          board_centre + distance * Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      PinholeCamera camera = PinholeCamera::from_vertical_fov(
          "calibration_" + std::to_string(k), look_at(eye, target, up), fov, options.width, options.height);
      camera.distortion = options.lens;
      if (board_in_picture(camera, board)) {
        calibration.push_back(camera);
        break;
      }
    }
  }

  // The renderers: the sphere alone (sh: exact for one convex object), the board alone
  // (path traced). A photograph's diffuse term has every band, and the fits of photo
  // captures (which carry no renderer's lmax) model and take off its bands up to
  // kFullBandDiffuseLmax: the simulated photos must have them too.
  const RayTracer sphere_tracer(scene);
  ShIntegratorOptions sh_options;
  sh_options.lmax = kFullBandDiffuseLmax;
  sh_options.threads = options.threads;
  sh_options.refined_supersampling = 4;
  const ShIntegrator sphere_renderer(scene, sphere_tracer, environment, sh_options);
  Scene board_scene = scene;
  board_scene.spheres.clear();
  add_board(board_scene, board);
  add_table(board_scene, board);
  const RayTracer board_tracer(board_scene);
  // glaze's coat reflects Schlick's grazing Fresnel even at R0 = 0, which would mirror the
  // environment's lamps in the board's black squares; a printed board is rough and blurs
  // them, so the board is lit by a uniform light of the environment's mean radiance. Under
  // it nothing shades a flat board on a flat table, and the sh integrator is exact there:
  // the photos carry the camera's noise alone, as a real board photo does, where a path
  // tracer's noise in the edge pixels would move the corners by a tenth of a pixel.
  const RGB mean = mean_radiance(environment);
  const Environment board_light(make_procedural_environment("constant", 8, 4), {luminance(mean)});
  ShIntegratorOptions board_options;
  board_options.lmax = 0;
  board_options.supersampling = options.board_supersampling;
  board_options.refined_supersampling = std::min(4 * options.board_supersampling, 32);
  board_options.threads = options.threads;
  board_options.warn_when_inexact = false;
  const ShIntegrator board_renderer(board_scene, board_tracer, board_light, board_options);

  require_memory(size_t(options.width) * options.height * 3 * (sizeof(float) + sizeof(uint16_t)) * 4,
                 "the simulated photos");
  create_output_folder(options.out, "the shoot folder");
  if (std::filesystem::exists(options.out / "shoot.json"))
    throw Error(options.out.string() + ": already holds a shoot (shoot.json); give a new folder to --out");
  const CameraModel& camera_model = options.camera;
  const int bits = options.format == "png16" ? 16 : 8;
  const std::string extension = options.format == "jpg" ? ".jpg" : ".png";
  // The middle exposure puts the first view's median radiance at the middle code.
  const double middle_signal = bits == 16 ? 0.5 : film_curve_inverse(128.0 / 255.0);
  shoot.hdr_unit = RGB::Constant(float(bits == 16 ? 1.0 : 1.0 / middle_signal));

  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  uint64_t photo = 0;
  // A board photo: one exposure, exposed as for a chart: its brightest 2% (the white
  // paper) at code 230, below clipping.
  const auto photograph_board = [&](const PinholeCamera& camera, uint64_t index, const std::filesystem::path& file) {
    arena.execute([&] {
      const Image hdr = board_renderer.render(camera, index).image;
      const double white = luminance_quantile(hdr, 0.98);
      const double seconds = (bits == 16 ? 0.9 : film_curve_inverse(230.0 / 255.0)) / white;
      write_photo_codes(file.string(), photograph(hdr, seconds, camera_model, bits, options.seed, photo++));
    });
  };
  if (!calibration.empty()) create_output_folder(options.out / "calibration", "the calibration photos");
  for (size_t k = 0; k < calibration.size(); ++k) {
    if (options.progress) std::cerr << "simulate-shoot: calibration photo " << k << '\n';
    photograph_board(calibration[k], 1000 + k,
                     options.out / "calibration" / ("board_" + std::to_string(k) + extension));
  }
  const size_t folders = shoot.views.size() + shoot.probes.size();
  for (size_t f = 0; f < folders; ++f) {
    const bool probe = f >= shoot.views.size();
    const SimulatedView& view = probe ? shoot.probes[f - shoot.views.size()] : shoot.views[f];
    if (options.progress) std::cerr << "simulate-shoot: " << view.name << '\n';
    const std::filesystem::path folder = options.out / view.name;
    create_output_folder(folder, "a view folder");
    photograph_board(view.camera, f, folder / ("board" + extension));
    Image hdr;
    arena.execute([&] {
      hdr = probe ? render_probe(environment, view.camera, shoot.ball_center, shoot.ball_radius, shoot.reflectance,
                                 options.probe_supersampling, options.threads)
                  : sphere_renderer.render(view.camera, f).image;
    });
    if (shoot.exposures.empty()) {
      const double middle = middle_signal / luminance_quantile(hdr, 0.5);
      for (int k = 0; k < options.exposures; ++k)
        shoot.exposures.push_back(middle * std::exp2(options.ev_step * (k - (options.exposures - 1) / 2.0)));
    }
    if (options.keep_radiance) shoot.radiance.push_back(hdr);
    json times = json::object();
    for (size_t k = 0; k < shoot.exposures.size(); ++k) {
      const std::string file = "bracket_" + std::to_string(k) + extension;
      arena.execute([&] {
        write_photo_codes((folder / file).string(),
                          photograph(hdr, shoot.exposures[k], camera_model, bits, options.seed, photo++));
      });
      times[file] = shoot.exposures[k];
    }
    write_text_atomically((folder / "exposures.json").string(), times.dump(2) + "\n");
  }

  json description = {{"board", {{"inner_corners", {board.cols, board.rows}}, {"square", board.square}}},
                      {"object", {{"type", "sphere"}}}};
  if (options.write_object) {
    description["object"]["center"] = {shoot.sphere_center.x(), shoot.sphere_center.y(), shoot.sphere_center.z()};
    description["object"]["radius"] = shoot.sphere_radius;
  }
  if (options.probe) {
    description["probe"] = {{"radius", shoot.ball_radius}};
    if (options.write_reflectance) description["probe"]["reflectance"] = shoot.reflectance;
  }
  if (options.known_intrinsics) {
    const PinholeCamera& c = shoot.views.front().camera;
    description["camera"] = {{"w", c.width},
                             {"h", c.height},
                             {"fl_x", c.fl_x},
                             {"fl_y", c.fl_y},
                             {"cx", c.cx},
                             {"cy", c.cy},
                             {"k1", c.distortion.k1},
                             {"k2", c.distortion.k2},
                             {"p1", c.distortion.p1},
                             {"p2", c.distortion.p2},
                             {"k3", c.distortion.k3}};
  }

  CaptureEnvironment environment_entry{{}, {}, spec.options};
  if (spec.source.starts_with("procedural:"))
    environment_entry.procedural = spec.source.substr(std::string("procedural:").size());
  else
    environment_entry.file = std::filesystem::absolute(spec.source).string();
  json truth = {{"scene", std::filesystem::absolute(options.scene).string()},
                {"object",
                 {{"center", {shoot.sphere_center.x(), shoot.sphere_center.y(), shoot.sphere_center.z()}},
                  {"radius", shoot.sphere_radius},
                  {"R0", shoot.material.R0()},
                  {"Rd", {shoot.material.Rd()[0], shoot.material.Rd()[1], shoot.material.Rd()[2]}}}},
                {"board_to_scene", rows_of(shoot.board_to_scene)},
                {"environment", environment_json(environment_entry)},
                {"exposures", shoot.exposures},
                {"hdr_unit", {shoot.hdr_unit[0], shoot.hdr_unit[1], shoot.hdr_unit[2]}},
                {"camera",
                 {{"full_well", camera_model.full_well},
                  {"read_noise", camera_model.read_noise},
                  {"noise", camera_model.noise},
                  {"bits", bits},
                  {"seed", options.seed}}},
                {"views", json::array()}};
  for (const SimulatedView& view : shoot.views) truth["views"].push_back(camera_json(view));
  if (options.probe) {
    truth["probe"] = {{"center", {shoot.ball_center.x(), shoot.ball_center.y(), shoot.ball_center.z()}},
                      {"radius", shoot.ball_radius},
                      {"reflectance", shoot.reflectance}};
    truth["probes"] = json::array();
    for (const SimulatedView& view : shoot.probes) truth["probes"].push_back(camera_json(view));
  }
  write_text_atomically((options.out / "simulation.json").string(), truth.dump(2) + "\n");
  // shoot.json last: a folder with one is a complete shoot.
  write_text_atomically((options.out / "shoot.json").string(), description.dump(2) + "\n");
  shoot.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return shoot;
}

}  // namespace glaze
