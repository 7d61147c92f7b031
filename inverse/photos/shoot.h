// shoot.h: a photo shoot as a folder (docs/design.md §7): shoot.json, and the photos of
// its folders.
//
//   SHOOT/shoot.json    {"board": {"inner_corners": [cols, rows], "square": metres},
//                        "object": {"type": "sphere"} (locate it from its outline)
//                                | {"type": "sphere", "center": [x, y, z], "radius": r} | {"gltf": FILE},
//                        "probe": {"center": [x, y, z], "radius": r, "reflectance": x or [r, g, b]}
//                                 (each optional),
//                        "camera": {"fl_x": .., "fl_y": .., "cx": .., "cy": .., "k1": .., ...}}
//   SHOOT/calibration/  optional: photos of the board in many poses
//   SHOOT/view_NNN/     one tripod position each, with the board photo board.* ...
//   SHOOT/probe_NNN/    ... and the same with the mirror ball
//
// "camera" (optional) gives known intrinsics in transforms.json's vocabulary and
// convention (pixel centres at i + 0.5). "object" and "probe" are in board coordinates
// (registration.h), metres; a glTF object's FILE is relative to the shoot's folder.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace glaze {

// The chessboard: `cols` x `rows` inner corners (where four squares meet), `square`
// metres apart. One count even and the other odd, so that the board does not look the
// same turned by 180 degrees (chessboard.h fixes its frame by that).
struct BoardSpec {
  int cols = 0, rows = 0;
  double square = 0.0;
};

// Pinhole intrinsics in pixels and OpenCV's lens model (lens_distortion.h), as a
// transforms.json holds them.
struct CameraIntrinsics {
  int width = 0, height = 0;
  double fl_x = 0, fl_y = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
};

// What was photographed ("object").
struct ShootObject {
  enum class Kind { locate_sphere, sphere, gltf };
  Kind kind = Kind::locate_sphere;
  std::array<double, 3> center{};  // sphere: given centre
  double radius = 0.0;             // sphere: given radius
  std::filesystem::path gltf;      // gltf: resolved against the shoot's folder
};

// The mirror ball of the probe_NNN folders ("probe"); unset values are estimated.
struct ShootProbe {
  std::optional<std::array<double, 3>> center;  // given only with the radius
  std::optional<double> radius;
  std::optional<std::array<double, 3>> reflectance;  // per channel, in (0, 1]
};

struct Shoot {
  std::filesystem::path folder;  // SHOOT
  std::string file;              // SHOOT/shoot.json, for messages
  BoardSpec board;
  // Known intrinsics ("camera"); width and height are 0 where not given (the photos have them).
  std::optional<CameraIntrinsics> camera;
  std::optional<ShootObject> object;  // none: shoot.json has no "object"
  ShootProbe probe;
};

// One place the camera stood: view_NNN or probe_NNN, and its board photo.
struct ShootView {
  std::string name;  // "view_000"
  std::filesystem::path board_photo;
};

// Reads SHOOT/shoot.json (`path` is the folder or the file). Throws glaze::Error naming
// the file and the key at fault.
Shoot read_shoot(const std::filesystem::path& path);

// The image files in SHOOT/calibration/, sorted by name (none when there is no such folder).
std::vector<std::filesystem::path> calibration_photos(const Shoot& shoot);

// The view_NNN folders, then the probe_NNN folders, each sorted by name, with their board
// photos. Throws glaze::Error for a folder without exactly one board.* image, and when
// there is no view at all.
std::vector<ShootView> shoot_views(const Shoot& shoot);

// Whether `path` names an image glaze reads, by its extension (any case): PNG, JPEG,
// TIFF, EXR, HDR and the camera raw formats that OpenImageIO reads through LibRaw.
bool is_image_file(const std::filesystem::path& path);

}  // namespace glaze
