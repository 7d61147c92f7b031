// registration.cpp: calibrateCamera and PnP on the board photos of a shoot.
#include "inverse/photos/registration.h"

#include "inverse/photos/chessboard.h"
#include "renderer/capture_set.h"
#include "renderer/error.h"
#include "renderer/image.h"

#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace glaze {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Fewer photos than this give intrinsics that are poorly determined: a warning says so.
constexpr size_t kFewCalibrationPhotos = 6;
// A view registered worse than this (pixels RMS) is warned about.
constexpr double kLargeViewError = 1.0;

// A board photo's corners in OpenCV's pixel convention (pixel centres at integers).
struct BoardCorners {
  fs::path photo;
  std::vector<cv::Point2f> corners;
};

// Reads `photo` and finds the board in it; every photo must have the size of the first
// (`width` and `height` 0 until then).
BoardCorners board_corners(const fs::path& photo, const BoardSpec& board, int& width, int& height) {
  const Image image = read_image(photo.string());
  if (width == 0) width = image.width, height = image.height;
  if (image.width != width || image.height != height)
    throw Error(photo.string() + ": the photo is " + std::to_string(image.width) + " x " +
                std::to_string(image.height) + " pixels, the others " + std::to_string(width) + " x " +
                std::to_string(height) + "; every photo of a shoot must come from the same camera at the same size");
  BoardCorners found{photo, {}};
  for (const Eigen::Vector2d& p : find_board_corners(image, board, photo.string()))
    found.corners.emplace_back(float(p.x() - 0.5), float(p.y() - 0.5));
  return found;
}

// The board's corners in the world frame (registration.h), in chessboard.h's order.
std::vector<cv::Point3f> board_points(const BoardSpec& board) {
  std::vector<cv::Point3f> points;
  for (int j = 0; j < board.rows; ++j)
    for (int i = 0; i < board.cols; ++i) points.emplace_back(float(i * board.square), float(j * board.square), 0.0f);
  return points;
}

cv::Matx33d camera_matrix(const CameraIntrinsics& camera) {
  return {camera.fl_x, 0.0, camera.cx - 0.5, 0.0, camera.fl_y, camera.cy - 0.5, 0.0, 0.0, 1.0};
}

std::vector<double> distortion_vector(const CameraIntrinsics& camera) {
  return {camera.k1, camera.k2, camera.p1, camera.p2, camera.k3};
}

// A camera of these intrinsics (no pose), to check its lens.
PinholeCamera intrinsics_camera(const CameraIntrinsics& c) {
  PinholeCamera camera;
  camera.width = c.width, camera.height = c.height;
  camera.fl_x = float(c.fl_x), camera.fl_y = float(c.fl_y), camera.cx = float(c.cx), camera.cy = float(c.cy);
  camera.distortion = {LensDistortion::Model::opencv, c.k1, c.k2, c.k3, 0.0, c.p1, c.p2};
  return camera;
}

// Intrinsics and distortion from all the board photos; returns calibrateCamera's RMS error.
// The higher radial terms are only known as far out as the board was seen: photos that
// leave the film's corners out (a long lens, a small board) can leave k2 and k3 free to
// grow until the model folds back before the corners, where pixels would then have no
// ray. Such a fit is redone with k3 fixed at 0, then k2 too (OpenCV's advice for all but
// wide lenses), with a warning.
double calibrate(const std::vector<BoardCorners>& photos, const BoardSpec& board, CameraIntrinsics& camera) {
  const std::vector<std::vector<cv::Point3f>> objects(photos.size(), board_points(board));
  std::vector<std::vector<cv::Point2f>> images;
  for (const BoardCorners& photo : photos) images.push_back(photo.corners);
  const int fixed_terms[] = {0, cv::CALIB_FIX_K3, cv::CALIB_FIX_K3 | cv::CALIB_FIX_K2};
  for (size_t attempt = 0;; ++attempt) {
    cv::Mat matrix, distortion;
    std::vector<cv::Mat> rotations, translations;
    const double rms = cv::calibrateCamera(
        objects, images, cv::Size(camera.width, camera.height), matrix, distortion, rotations, translations,
        fixed_terms[attempt], cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 200, 1e-12));
    CameraIntrinsics fitted = camera;
    fitted.fl_x = matrix.at<double>(0, 0);
    fitted.fl_y = matrix.at<double>(1, 1);
    fitted.cx = matrix.at<double>(0, 2) + 0.5;
    fitted.cy = matrix.at<double>(1, 2) + 0.5;
    fitted.k1 = distortion.at<double>(0);
    fitted.k2 = distortion.at<double>(1);
    fitted.p1 = distortion.at<double>(2);
    fitted.p2 = distortion.at<double>(3);
    fitted.k3 = distortion.at<double>(4);
    try {
      intrinsics_camera(fitted).check_lens("the calibrated camera");
    } catch (const Error& e) {
      if (attempt + 1 < std::size(fixed_terms)) continue;
      throw Error(std::string(e.what()) +
                  "; the calibration photos do not show the board near the film's corners: add photos with the "
                  "board in every part of the frame");
    }
    if (attempt > 0)
      warn(
          "the calibration photos leave the film's corners out, where the full lens model folded back; calibrated "
          "with " +
          std::string(attempt == 1 ? "k3 = 0" : "k2 = k3 = 0") +
          " instead. Photos with the board in the corners of the frame calibrate the lens there");
    camera = fitted;
    return rms;
  }
}

// The pose of the camera that took `photo`, and its RMS reprojection error.
ViewRegistration locate(const std::string& name, const BoardCorners& photo, const BoardSpec& board,
                        const CameraIntrinsics& camera) {
  const std::vector<cv::Point3f> points = board_points(board);
  const cv::Matx33d matrix = camera_matrix(camera);
  const std::vector<double> distortion = distortion_vector(camera);
  cv::Vec3d rotation, translation;
  if (!cv::solvePnP(points, photo.corners, matrix, distortion, rotation, translation, false, cv::SOLVEPNP_IPPE))
    throw Error(photo.photo.string() + ": no camera pose places the board's corners where they were found");
  cv::solvePnPRefineLM(points, photo.corners, matrix, distortion, rotation, translation,
                       cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  std::vector<cv::Point2f> projected;
  cv::projectPoints(points, rotation, translation, matrix, distortion, projected);
  double squares = 0.0;
  for (size_t k = 0; k < points.size(); ++k) {
    const cv::Point2f d = projected[k] - photo.corners[k];
    squares += double(d.x) * d.x + double(d.y) * d.y;
  }
  // OpenCV's camera maps world points x to R x + t with axes x right, y down, z forward;
  // glaze's camera axes are (x, -y, -z) of those.
  cv::Matx33d r;
  cv::Rodrigues(rotation, r);
  Eigen::Matrix3d world_to_camera;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) world_to_camera(i, j) = r(i, j);
  const Eigen::Vector3d t(translation[0], translation[1], translation[2]);
  Eigen::Matrix4d pose = Eigen::Matrix4d::Identity();
  pose.topLeftCorner<3, 3>() = world_to_camera.transpose() * Eigen::Vector3d(1, -1, -1).asDiagonal();
  pose.topRightCorner<3, 1>() = -world_to_camera.transpose() * t;
  return {name, photo.photo, pose, std::sqrt(squares / double(points.size()))};
}

std::string shoot_relative(const fs::path& path, const fs::path& folder) {
  return path.lexically_relative(folder).generic_string();
}

}  // namespace

Registration register_shoot(const Shoot& shoot) {
  Registration registration;
  registration.board = shoot.board;
  const std::vector<ShootView> views = shoot_views(shoot);
  int width = 0, height = 0;
  std::vector<BoardCorners> view_corners;
  for (const ShootView& view : views)
    view_corners.push_back(board_corners(view.board_photo, shoot.board, width, height));
  if (shoot.camera) {
    registration.camera = *shoot.camera;
    if ((shoot.camera->width && shoot.camera->width != width) ||
        (shoot.camera->height && shoot.camera->height != height))
      throw Error(shoot.file + ": \"camera\" is for " + std::to_string(shoot.camera->width) + " x " +
                  std::to_string(shoot.camera->height) + " pixels, but the board photos are " + std::to_string(width) +
                  " x " + std::to_string(height) + " (" + views.front().board_photo.string() + ")");
  } else {
    std::vector<BoardCorners> photos;
    for (const fs::path& photo : calibration_photos(shoot))
      photos.push_back(board_corners(photo, shoot.board, width, height));
    photos.insert(photos.end(), view_corners.begin(), view_corners.end());
    if (photos.size() < 3)
      throw Error(shoot.folder.string() + ": " + std::to_string(photos.size()) +
                  " board photos are too few to calibrate the camera from; add photos of the board in varied poses "
                  "(tilted 20 to 45 degrees, turned, filling the frame) to " +
                  (shoot.folder / "calibration").string() + ", or give known intrinsics as \"camera\" in " +
                  shoot.file);
    if (photos.size() < kFewCalibrationPhotos)
      warn(shoot.folder.string() + ": the camera is calibrated from only " + std::to_string(photos.size()) +
           " board photos; its intrinsics and distortion are uncertain (10 to 20 photos in varied poses in "
           "calibration/ make them reliable)");
    registration.camera.width = width;
    registration.camera.height = height;
    registration.calibration_error_px = calibrate(photos, shoot.board, registration.camera);
    registration.calibrated = true;
    for (const BoardCorners& photo : photos) registration.calibration_photos.push_back(photo.photo);
  }
  registration.camera.width = width;
  registration.camera.height = height;
  for (size_t k = 0; k < views.size(); ++k) {
    registration.views.push_back(locate(views[k].name, view_corners[k], shoot.board, registration.camera));
    const double error = registration.views.back().reprojection_error_px;
    if (error > kLargeViewError)
      warn(views[k].board_photo.string() + ": the registered camera misses the board's corners by " +
           std::to_string(error) + " pixels RMS; check that the board is flat and sharp in this photo" +
           (registration.calibrated ? std::string() : ", and the intrinsics given in " + shoot.file));
  }
  return registration;
}

PinholeCamera registered_camera(const Registration& registration, size_t view) {
  PinholeCamera camera = intrinsics_camera(registration.camera);
  camera.name = registration.views.at(view).name;
  camera.camera_to_world = Eigen::Affine3f(registration.views[view].camera_to_world.cast<float>());
  return camera;
}

json registration_json(const Registration& registration, const fs::path& folder) {
  json root = intrinsics_json(intrinsics_camera(registration.camera));
  root["board"] = {{"inner_corners", {registration.board.cols, registration.board.rows}},
                   {"square", registration.board.square}};
  root["intrinsics"] = registration.calibrated ? "calibrated" : "given";
  if (registration.calibrated) {
    json photos = json::array();
    for (const fs::path& photo : registration.calibration_photos) photos.push_back(shoot_relative(photo, folder));
    root["calibration"] = {{"photos", photos}, {"reprojection_error_px", registration.calibration_error_px}};
  }
  json frames = json::array();
  for (const ViewRegistration& view : registration.views) {
    json rows = json::array();
    for (int i = 0; i < 4; ++i)
      rows.push_back({view.camera_to_world(i, 0), view.camera_to_world(i, 1), view.camera_to_world(i, 2),
                      view.camera_to_world(i, 3)});
    frames.push_back(json{{"view", view.name},
                          {"board_path", shoot_relative(view.board_photo, folder)},
                          {"transform_matrix", rows},
                          {"reprojection_error_px", view.reprojection_error_px}});
  }
  root["frames"] = frames;
  return root;
}

std::string registration_table(const Registration& registration, const fs::path& folder) {
  const CameraIntrinsics& c = registration.camera;
  std::ostringstream out;
  char line[256];
  if (registration.calibrated)
    std::snprintf(line, sizeof line, "intrinsics calibrated from %zu board photos, %.3f px RMS\n",
                  registration.calibration_photos.size(), registration.calibration_error_px);
  else
    std::snprintf(line, sizeof line, "intrinsics given in shoot.json\n");
  out << line;
  std::snprintf(line, sizeof line, "  %d x %d  fl_x %.2f  fl_y %.2f  cx %.2f  cy %.2f\n", c.width, c.height, c.fl_x,
                c.fl_y, c.cx, c.cy);
  out << line;
  std::snprintf(line, sizeof line, "  k1 %.5f  k2 %.5f  p1 %.5f  p2 %.5f  k3 %.5f\n", c.k1, c.k2, c.p1, c.p2, c.k3);
  out << line;
  std::snprintf(line, sizeof line, "%-12s %-28s %9s   %s\n", "view", "board photo", "RMS px", "camera at (m)");
  out << line;
  for (const ViewRegistration& view : registration.views) {
    const Eigen::Vector4d at = view.camera_to_world.col(3);
    std::snprintf(line, sizeof line, "%-12s %-28s %9.3f   (%.4f, %.4f, %.4f)\n", view.name.c_str(),
                  shoot_relative(view.board_photo, folder).c_str(), view.reprojection_error_px, at.x(), at.y(), at.z());
    out << line;
  }
  return out.str();
}

}  // namespace glaze
