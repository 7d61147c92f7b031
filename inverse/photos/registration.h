// registration.h: a photo shoot's camera, registered on its chessboard (docs/design.md §7):
// intrinsics and lens distortion, and where the camera stood for each view.
//
// Intrinsics and OpenCV's distortion (k1 k2 p1 p2 k3) come from calibrateCamera over
// every board photo (calibration/ and each view's board.*), unless shoot.json gives
// them; each view's pose then comes from PnP on its board photo (IPPE, refined by
// Levenberg-Marquardt). The reprojection error, the RMS distance in pixels between the
// corners found and the corners the registered camera projects, is reported per view
// and over the calibration.
//
// The world frame is the board's (chessboard.h fixes its corner order): the origin at
// inner corner (0, 0), x along its row, y along its column, z the board's normal towards
// the cameras (up from the table), in metres. The poses are camera-to-world with glaze's
// camera axes (OpenGL: +X right, +Y up, looking along -Z), as transforms.json holds them.
#pragma once

#include "inverse/photos/shoot.h"
#include "renderer/camera.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace glaze {

struct ViewRegistration {
  std::string name;                    // "view_000"
  std::filesystem::path board_photo;   // the photo it was registered on
  Eigen::Matrix4d camera_to_world;     // board frame, OpenGL camera axes
  double reprojection_error_px = 0.0;  // RMS over the board's corners
};

struct Registration {
  BoardSpec board;
  CameraIntrinsics camera;
  bool calibrated = false;  // false: the intrinsics were given in shoot.json
  // When calibrated: the photos the intrinsics come from, and calibrateCamera's RMS
  // reprojection error over all their corners.
  std::vector<std::filesystem::path> calibration_photos;
  double calibration_error_px = 0.0;
  std::vector<ViewRegistration> views;
};

// glaze's camera of view `view`: its pose, the intrinsics and the lens (opencv model).
PinholeCamera registered_camera(const Registration& registration, size_t view);

// Registers the views of `shoot` (shoot.h), reading its board photos. Throws glaze::Error
// naming the photo where a board is not found or the photos differ in size, and when
// there are too few photos to calibrate from; warns when a view's error is large.
Registration register_shoot(const Shoot& shoot);

// `registration` as JSON in transforms.json's vocabulary (capture_set.h's
// intrinsics_json: w, h, fl_x, fl_y, cx, cy, camera_model "OPENCV", k1, k2, p1, p2, and k3
// when not 0), and "frames" with each view's "transform_matrix" and
// "reprojection_error_px". Photo paths relative to `folder`.
nlohmann::json registration_json(const Registration& registration, const std::filesystem::path& folder);

// A table for people: the intrinsics, then one line per view.
std::string registration_table(const Registration& registration, const std::filesystem::path& folder);

}  // namespace glaze
