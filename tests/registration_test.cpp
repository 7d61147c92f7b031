// registration_test.cpp: a photo shoot's camera registered on its chessboard
// (inverse/photos): board photos rendered by glaze's own path tracer through a known
// camera, registered, and compared with that camera.
#include "gltf_builder.h"
#include "inverse/photos/chessboard.h"
#include "inverse/photos/registration.h"
#include "inverse/photos/shoot.h"
#include "inverse/photos/shoot_simulator.h"
#include "renderer/display.h"
#include "renderer/environment.h"
#include "renderer/procedural_environment.h"
#include "renderer/ray_tracer.h"
#include "renderer/render.h"

#include <Eigen/Geometry>

#include <memory>

namespace glaze::testing {
namespace {

// 9 x 6 inner corners, 25 mm squares: the board seen from 0.3 to 0.5 m fills a third to
// two thirds of a 640 x 480 photo.
const BoardSpec kBoard{9, 6, 0.025};
constexpr int kWidth = 640, kHeight = 480;

// The camera of the test: fl 600 px, principal point off centre, a barrel lens.
PinholeCamera true_camera(const Eigen::Affine3f& pose) {
  PinholeCamera camera;
  camera.name = "board";
  camera.camera_to_world = pose;
  camera.width = kWidth;
  camera.height = kHeight;
  camera.fl_x = 600.0f;
  camera.fl_y = 600.0f;
  camera.cx = 323.5f;
  camera.cy = 236.0f;
  camera.distortion = {LensDistortion::Model::opencv, -0.1, 0.02, 0.0, 0.0, 0.0, 0.0};
  return camera;
}

// Where the board points (x, y) (in squares) fall in `camera`'s film.
std::vector<Eigen::Vector2d> film_points(const PinholeCamera& camera, const std::vector<Eigen::Vector2d>& points) {
  std::vector<Eigen::Vector2d> film;
  const Eigen::Affine3f world_to_camera = camera.camera_to_world.inverse();
  for (const Eigen::Vector2d& p : points) {
    const Vec3 world(float(p.x() * kBoard.square), float(p.y() * kBoard.square), 0.0f);
    film.push_back(camera.project(world_to_camera * world)->cast<double>());
  }
  return film;
}

// Where the board's corners fall, in chessboard.h's order.
std::vector<Eigen::Vector2d> true_corners(const PinholeCamera& camera) {
  std::vector<Eigen::Vector2d> corners;
  for (int j = 0; j < kBoard.rows; ++j)
    for (int i = 0; i < kBoard.cols; ++i) corners.emplace_back(i, j);
  return film_points(camera, corners);
}

// Whether the whole board, its margin included, is in `camera`'s picture.
bool board_in_picture(const PinholeCamera& camera) {
  const double x0 = -2, y0 = -2, x1 = kBoard.cols + 1, y1 = kBoard.rows + 1;
  for (const Eigen::Vector2d& p : film_points(camera, {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}))
    if (!(p.x() > 0 && p.x() < kWidth && p.y() > 0 && p.y() < kHeight)) return false;
  return true;
}

// The photo shoot rendered once for the suite: calibration photos (8-bit PNG) and three
// views around the board (EXR), each view's board seen from another side.
class BoardRegistration : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TemporaryDirectory();
    Scene scene;
    add_board(scene, kBoard);
    const RayTracer tracer(scene);
    const Environment environment(make_procedural_environment("constant", 16, 8), {});
    // Under uniform light, sampling the material alone has the least noise: the board's
    // edges then need only 8 samples a pixel to place its corners within 0.1 px.
    PathTracerOptions tracer_options;
    tracer_options.estimator = DirectLightEstimator::bsdf;
    const PathTracer path_tracer(scene, tracer, environment, tracer_options);
    RenderOptions options;
    options.spp = 8;
    const Vec3 centre(float(kBoard.square * (kBoard.cols - 1) / 2), float(kBoard.square * (kBoard.rows - 1) / 2), 0);
    const auto photograph = [&](const Eigen::Affine3f& pose, const std::string& name, uint64_t index) {
      const PinholeCamera camera = true_camera(pose);
      if (!board_in_picture(camera)) throw std::logic_error(name + ": the test's camera does not see all the board");
      const Image image = render(path_tracer, camera, options, index).image;
      std::filesystem::create_directories(dir_->path() / std::filesystem::path(name).parent_path());
      if (name.ends_with(".png")) {
        const std::vector<uint8_t> srgb = display_image(image, {0.0f, ToneMapping::clamp});
        write_picture(dir_->file(name), image.width, image.height, srgb);
      } else {
        write_image(dir_->file(name), image);
      }
      return camera;
    };
    // Calibration: tilted 20 to 45 degrees, turned about the board's normal, off centre.
    const struct {
      float azimuth, elevation, distance, roll, dx, dy;
    } calibration[] = {{0, 50, 0.40f, 0, 0, 0},         {90, 45, 0.39f, 10, 0.01f, 0}, {200, 42, 0.415f, -15, 0, 0.01f},
                       {300, 48, 0.43f, 25, -0.01f, 0}, {45, 40, 0.415f, -30, 0, 0},   {150, 52, 0.515f, 40, 0, -0.01f},
                       {250, 40, 0.49f, -45, 0, 0},     {330, 75, 0.515f, 60, 0, 0}};
    int index = 0;
    for (const auto& c : calibration) {
      const float a = c.azimuth * kPi / 180, e = c.elevation * kPi / 180, roll = c.roll * kPi / 180;
      const Vec3 eye = centre + c.distance * Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      const Vec3 up = Eigen::AngleAxisf(roll, Vec3::UnitZ()) * Vec3::UnitY();
      calibration_.push_back(photograph(look_at(eye, centre + Vec3(c.dx, c.dy, 0), up),
                                        "calibration/board_" + std::to_string(index) + ".png", index));
      ++index;
    }
    for (int view = 0; view < 3; ++view) {
      const float a = (30.0f + 120.0f * view) * kPi / 180, e = 50.0f * kPi / 180, distance = 0.5f;
      const Vec3 eye = centre + distance * Vec3(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
      views_.push_back(
          photograph(look_at(eye, centre, Vec3::UnitZ()), "view_00" + std::to_string(view) + "/board.exr", index++));
    }
    write_text(*dir_, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025}})");
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  static TemporaryDirectory* dir_;
  static std::vector<PinholeCamera> views_;
  static std::vector<PinholeCamera> calibration_;
};

TemporaryDirectory* BoardRegistration::dir_ = nullptr;
std::vector<PinholeCamera> BoardRegistration::views_;
std::vector<PinholeCamera> BoardRegistration::calibration_;

// The pixel where OpenCV's lens model (k1 k2 p1 p2 k3) images the pinhole point at pixel
// (x, y) of `camera`, written out here as OpenCV documents it.
Eigen::Vector2d distorted_pixel(const CameraIntrinsics& camera, double x, double y) {
  const double u = (x - camera.cx) / camera.fl_x, v = (y - camera.cy) / camera.fl_y, r2 = u * u + v * v;
  const double radial = 1 + camera.k1 * r2 + camera.k2 * r2 * r2 + camera.k3 * r2 * r2 * r2;
  const double du = u * radial + 2 * camera.p1 * u * v + camera.p2 * (r2 + 2 * u * u);
  const double dv = v * radial + camera.p1 * (r2 + 2 * v * v) + 2 * camera.p2 * u * v;
  return {camera.cx + camera.fl_x * du, camera.cy + camera.fl_y * dv};
}

CameraIntrinsics intrinsics_of(const PinholeCamera& camera) {
  CameraIntrinsics intrinsics;
  intrinsics.width = camera.width;
  intrinsics.height = camera.height;
  intrinsics.fl_x = camera.fl_x;
  intrinsics.fl_y = camera.fl_y;
  intrinsics.cx = camera.cx;
  intrinsics.cy = camera.cy;
  intrinsics.k1 = camera.distortion.k1;
  intrinsics.k2 = camera.distortion.k2;
  intrinsics.p1 = camera.distortion.p1;
  intrinsics.p2 = camera.distortion.p2;
  intrinsics.k3 = camera.distortion.k3;
  return intrinsics;
}

// Each view's pose within 0.1 degree and 1 mm of the camera that rendered it, and its
// board's corners reprojected within 0.3 px RMS.
void expect_views_registered(const glaze::Registration& registration, const std::vector<PinholeCamera>& truth) {
  ASSERT_EQ(registration.views.size(), truth.size());
  for (size_t v = 0; v < truth.size(); ++v) {
    const ViewRegistration& view = registration.views[v];
    const Eigen::Matrix4d expected = truth[v].camera_to_world.matrix().cast<double>();
    const double degrees = Eigen::AngleAxisd(Eigen::Matrix3d(view.camera_to_world.topLeftCorner<3, 3>().transpose() *
                                                             expected.topLeftCorner<3, 3>()))
                               .angle() *
                           180.0 / M_PI;
    const double millimetres = 1000.0 * (view.camera_to_world.col(3) - expected.col(3)).norm();
    std::printf("%s: %.4f px RMS, pose off by %.4f degrees and %.4f mm\n", view.name.c_str(),
                view.reprojection_error_px, degrees, millimetres);
    EXPECT_LT(view.reprojection_error_px, 0.3) << view.name;
    EXPECT_LT(degrees, 0.1) << view.name;
    EXPECT_LT(millimetres, 1.0) << view.name;
    // glaze's camera of the view images the board's corners where the true one does.
    const std::vector<Eigen::Vector2d> expected_corners = true_corners(truth[v]);
    const std::vector<Eigen::Vector2d> corners = true_corners(registered_camera(registration, v));
    for (size_t k = 0; k < corners.size(); ++k)
      EXPECT_LT((corners[k] - expected_corners[k]).norm(), 0.3) << view.name << " corner " << k;
  }
}

TEST_F(BoardRegistration, CornersFoundWhereTheCameraImagesThem) {
  for (size_t v = 0; v < views_.size(); ++v) {
    const std::string file = dir_->file("view_00" + std::to_string(v) + "/board.exr");
    const std::vector<Eigen::Vector2d> found = find_board_corners(read_image(file), kBoard, file);
    const std::vector<Eigen::Vector2d> truth = true_corners(views_[v]);
    ASSERT_EQ(found.size(), truth.size());
    double squares = 0, largest = 0;
    for (size_t k = 0; k < found.size(); ++k) {
      const double d = (found[k] - truth[k]).norm();
      squares += d * d;
      largest = std::max(largest, d);
    }
    const double rms = std::sqrt(squares / found.size());
    std::printf("view %zu: corners %.4f px RMS, %.4f px at most\n", v, rms, largest);
    EXPECT_LT(rms, 0.1) << file;
  }
}

TEST_F(BoardRegistration, CalibratesIntrinsicsDistortionAndPoses) {
  const glaze::Registration registration = register_shoot(read_shoot(dir_->path()));
  ASSERT_TRUE(registration.calibrated);
  EXPECT_EQ(registration.calibration_photos.size(), calibration_.size() + views_.size());
  const CameraIntrinsics& found = registration.camera;
  const CameraIntrinsics truth = intrinsics_of(views_.front());
  std::printf(
      "calibration %.4f px RMS; fl_x %.3f fl_y %.3f cx %.3f cy %.3f; k1 %.5f k2 %.5f p1 %.6f p2 %.6f "
      "k3 %.5f\n",
      registration.calibration_error_px, found.fl_x, found.fl_y, found.cx, found.cy, found.k1, found.k2, found.p1,
      found.p2, found.k3);
  EXPECT_EQ(found.width, kWidth);
  EXPECT_EQ(found.height, kHeight);
  EXPECT_LT(registration.calibration_error_px, 0.3);
  EXPECT_NEAR(found.fl_x, truth.fl_x, 0.005 * truth.fl_x);
  EXPECT_NEAR(found.fl_y, truth.fl_y, 0.005 * truth.fl_y);
  EXPECT_NEAR(found.cx, truth.cx, 2.0);
  EXPECT_NEAR(found.cy, truth.cy, 2.0);
  // The lens: the recovered model moves every corner the photos saw within 0.3 px of
  // where the true one does (the coefficients trade off against each other, and beyond
  // the corners seen they extrapolate; where the board was, the image does not).
  double largest = 0.0;
  for (const std::vector<PinholeCamera>* cameras : {&calibration_, &views_})
    for (const PinholeCamera& camera : *cameras)
      for (const Eigen::Vector2d& p : true_corners(camera))
        largest =
            std::max(largest, (distorted_pixel(found, p.x(), p.y()) - distorted_pixel(truth, p.x(), p.y())).norm());
  std::printf("distortion: the models differ by %.4f px at most where the photos saw corners\n", largest);
  EXPECT_LT(largest, 0.3);
  expect_views_registered(registration, views_);
}

// Intrinsics given in shoot.json: no calibration, each view located by PnP alone, as
// accurately; `glaze register` writes the same poses as JSON.
TEST_F(BoardRegistration, GivenIntrinsicsLocateTheViewsAlone) {
  const std::filesystem::path shoot = dir_->path() / "given";
  for (size_t v = 0; v < views_.size(); ++v) {
    const std::string view = "view_00" + std::to_string(v);
    std::filesystem::create_directories(shoot / view);
    std::filesystem::copy_file(dir_->path() / view / "board.exr", shoot / view / "board.exr");
  }
  const PinholeCamera& camera = views_.front();
  json description = {{"board", {{"inner_corners", {kBoard.cols, kBoard.rows}}, {"square", kBoard.square}}},
                      {"camera",
                       {{"fl_x", camera.fl_x},
                        {"fl_y", camera.fl_y},
                        {"cx", camera.cx},
                        {"cy", camera.cy},
                        {"k1", camera.distortion.k1},
                        {"k2", camera.distortion.k2},
                        {"p1", camera.distortion.p1},
                        {"p2", camera.distortion.p2}}}};
  write_text(*dir_, "given/shoot.json", description.dump());
  const glaze::Registration registration = register_shoot(read_shoot(shoot));
  EXPECT_FALSE(registration.calibrated);
  EXPECT_TRUE(registration.calibration_photos.empty());
  EXPECT_EQ(registration.camera.fl_x, camera.fl_x);
  expect_views_registered(registration, views_);
}

// A board that is not in the photo: the error names the photo and says what to check.
TEST(ShootRegistration, BoardNotFoundNamesThePhoto) {
  TemporaryDirectory dir;
  write_text(dir, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025}})");
  std::filesystem::create_directories(dir.path() / "view_000");
  Image grey(64, 48);
  for (size_t k = 0; k < grey.pixels.size(); ++k) grey.pixels[k] = 0.2f + 0.1f * float(k % 7);
  write_image(dir.file("view_000/board.exr"), grey);
  try {
    register_shoot(read_shoot(dir.path()));
    ADD_FAILURE() << "registered without a board";
  } catch (const Error& e) {
    const std::string message = without_directory(e.what(), dir);
    for (const char* word : {"DIR/view_000/board.exr", "not found", "inner_corners", "whole board", "focus"})
      EXPECT_NE(message.find(word), std::string::npos) << "'" << word << "' not in: " << message;
  }
}

// shoot.json's mistakes: each error names the file and the key.
TEST(ShootRegistration, MalformedShootJsonNamesTheKey) {
  TemporaryDirectory dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"({"camera": {"fl_x": 500, "cx": 1, "cy": 1}})", "\"board\" is missing"},
      {R"({"board": {"inner_corners": [9], "square": 0.02}})", "\"board.inner_corners\""},
      {R"({"board": {"inner_corners": [9, 6.5], "square": 0.02}})", "\"board.inner_corners\""},
      {R"({"board": {"inner_corners": [8, 6], "square": 0.02}})", "one count even and the other odd"},
      {R"({"board": {"inner_corners": [9, 6], "square": -1}})", "\"board.square\" must be a positive number"},
      {R"({"board": {"inner_corners": [9, 6]}})", "\"board.square\" is missing"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02, "size": 3}})", "\"board.size\" is not a key"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "camera": {"cx": 1, "cy": 1}})",
       "\"camera.fl_x\" is missing"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "camera": {"fl_x": 5, "cx": 1, "cy": 1, "k4": 0}})",
       "\"camera.k4\" is not a key"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "camera": {"fl_x": 5, "cx": "a", "cy": 1}})",
       "\"camera.cx\" must be a finite number"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02},
           "camera": {"fl_x": 5, "cx": 1, "cy": 1, "k1": 0.1, "camera_model": "PINHOLE"}})",
       "\"camera.camera_model\""},
      {R"([1, 2])", "the top level must be an object"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "object": {"type": "cube"}})",
       "\"object.type\" must be \"sphere\""},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "object": {"type": "sphere", "center": [0, 0, 1]}})",
       "\"object.radius\" is missing"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02},
           "object": {"type": "sphere", "center": [0, 0], "radius": 0.05}})",
       "\"object.center\" must be [x, y, z]"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "object": {"gltf": 3}})", "\"object.gltf\""},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "probe": {"reflectance": 1.5}})",
       "\"probe.reflectance\" must be the ball's reflectance in (0, 1]"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "probe": {"reflectance": [0.5, 0.5]}})",
       "\"probe.reflectance\""},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "probe": {"radius": 0}})",
       "\"probe.radius\" must be a positive number"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "probe": {"diameter": 0.1}})",
       "\"probe.diameter\" is not a key"},
      {R"({"board": {"inner_corners": [9, 6], "square": 0.02}, "probe": {"center": [0, 0, 0.05]}})",
       "\"probe.radius\" is missing"}};
  for (const auto& [text, expected] : cases) {
    const std::string file = write_text(dir, "shoot.json", text);
    try {
      read_shoot(dir.path());
      ADD_FAILURE() << "accepted " << text;
    } catch (const Error& e) {
      const std::string message = without_directory(e.what(), dir);
      EXPECT_NE(message.find("DIR/shoot.json: "), std::string::npos) << message;
      EXPECT_NE(message.find(expected), std::string::npos) << "'" << expected << "' not in: " << message;
    }
  }
}

// A view folder without its board photo, or with two, is refused, naming the folder.
// The object and the probe as shoot.json gives them, in board coordinates.
TEST(ShootRegistration, ObjectAndProbeAreRead) {
  TemporaryDirectory dir;
  write_text(dir, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025}})");
  Shoot shoot = read_shoot(dir.path());
  EXPECT_FALSE(shoot.object);
  EXPECT_FALSE(shoot.probe.radius);
  EXPECT_FALSE(shoot.probe.reflectance);
  write_text(dir, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025}, "object": {"type": "sphere"},
                                    "probe": {"reflectance": 0.6}})");
  shoot = read_shoot(dir.path());
  ASSERT_TRUE(shoot.object);
  EXPECT_EQ(shoot.object->kind, ShootObject::Kind::locate_sphere);
  ASSERT_TRUE(shoot.probe.reflectance);
  EXPECT_EQ(*shoot.probe.reflectance, (std::array<double, 3>{0.6, 0.6, 0.6}));
  write_text(dir, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025},
                                    "object": {"type": "sphere", "center": [0.1, 0.075, 0.05], "radius": 0.05},
                                    "probe": {"center": [0.1, 0.075, 0.0375], "radius": 0.0375,
                                              "reflectance": [0.55, 0.6, 0.65]}})");
  shoot = read_shoot(dir.path());
  EXPECT_EQ(shoot.object->kind, ShootObject::Kind::sphere);
  EXPECT_EQ(shoot.object->center, (std::array<double, 3>{0.1, 0.075, 0.05}));
  EXPECT_EQ(shoot.object->radius, 0.05);
  EXPECT_EQ(shoot.probe.radius, 0.0375);
  EXPECT_EQ(shoot.probe.center, (std::array<double, 3>{0.1, 0.075, 0.0375}));
  EXPECT_EQ(*shoot.probe.reflectance, (std::array<double, 3>{0.55, 0.6, 0.65}));
  write_text(dir, "shoot.json",
             R"({"board": {"inner_corners": [9, 6], "square": 0.025}, "object": {"gltf": "a.glb"}})");
  shoot = read_shoot(dir.path());
  EXPECT_EQ(shoot.object->kind, ShootObject::Kind::gltf);
  EXPECT_EQ(shoot.object->gltf, dir.path() / "a.glb");
}

TEST(ShootRegistration, EachViewNeedsOneBoardPhoto) {
  TemporaryDirectory dir;
  write_text(dir, "shoot.json", R"({"board": {"inner_corners": [9, 6], "square": 0.025}})");
  std::filesystem::create_directories(dir.path() / "view_000");
  write_text(dir, "view_000/bracket_1.png", "");
  const Shoot shoot = read_shoot(dir.path());
  EXPECT_THROW(
      {
        try {
          shoot_views(shoot);
        } catch (const Error& e) {
          EXPECT_NE(without_directory(e.what(), dir).find("DIR/view_000: has no board photo"), std::string::npos)
              << e.what();
          throw;
        }
      },
      Error);
  write_text(dir, "view_000/board.png", "");
  write_text(dir, "view_000/board.exr", "");
  EXPECT_THROW(shoot_views(shoot), Error);
}

// `glaze register` writes the registration as transforms.json's keys and prints a table;
// a shoot without a board photo fails as users should meet errors.
TEST_F(BoardRegistration, CommandWritesTransformsVocabulary) {
  const std::filesystem::path shoot = dir_->path() / "command";
  std::filesystem::create_directories(shoot / "view_000");
  std::filesystem::copy_file(dir_->path() / "view_000" / "board.exr", shoot / "view_000" / "board.exr");
  const PinholeCamera& camera = views_.front();
  const json description = {{"board", {{"inner_corners", {kBoard.cols, kBoard.rows}}, {"square", kBoard.square}}},
                            {"camera",
                             {{"fl_x", camera.fl_x},
                              {"cx", camera.cx},
                              {"cy", camera.cy},
                              {"w", kWidth},
                              {"h", kHeight},
                              {"k1", camera.distortion.k1},
                              {"k2", camera.distortion.k2},
                              {"p1", camera.distortion.p1},
                              {"p2", camera.distortion.p2}}}};
  write_text(*dir_, "command/shoot.json", description.dump());
  const std::string out = dir_->file("command/out/registration.json");
  std::filesystem::create_directories(dir_->path() / "command" / "out");
  const CommandResult run = run_glaze("register " + quoted(shoot.string()) + " --out " + quoted(out), *dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("view_000"), std::string::npos) << run.out;
  const json written = json::parse(std::ifstream(out));
  EXPECT_EQ(written.at("camera_model"), "OPENCV");
  EXPECT_EQ(written.at("w"), kWidth);
  EXPECT_EQ(written.at("intrinsics"), "given");
  for (const char* key : {"fl_x", "fl_y", "cx", "cy", "k1", "k2", "p1", "p2"}) EXPECT_TRUE(written.contains(key));
  EXPECT_FALSE(written.contains("k3"));  // given as 0, so left out as in transforms.json
  const json& frame = written.at("frames").at(0);
  EXPECT_EQ(frame.at("board_path"), "view_000/board.exr");
  EXPECT_LT(frame.at("reprojection_error_px").get<double>(), 0.3);
  const Eigen::Matrix4f expected = camera.camera_to_world.matrix();
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      EXPECT_NEAR(frame.at("transform_matrix")[i][j].get<double>(), expected(i, j), 1e-3) << i << ", " << j;

  std::filesystem::remove(shoot / "view_000" / "board.exr");
  const CommandResult failed = run_glaze("register " + quoted(shoot.string()), *dir_);
  EXPECT_EQ(failed.exit_code, 1);
  EXPECT_NE(failed.err.find("glaze: error: "), std::string::npos) << failed.err;
  EXPECT_NE(failed.err.find("has no board photo"), std::string::npos) << failed.err;
}

}  // namespace
}  // namespace glaze::testing
