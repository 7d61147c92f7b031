// shoot.cpp: shoot.json, and the photos of a shoot's folders.
#include "inverse/photos/shoot.h"

#include "inverse/photos/bracket.h"
#include "renderer/error.h"
#include "renderer/json_input.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <set>

namespace glaze {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* const kBoardHelp = "{\"inner_corners\": [cols, rows], \"square\": metres}";

[[noreturn]] void fail(const std::string& file, const std::string& key, const std::string& message) {
  throw Error(file + ": \"" + key + "\" " + message);
}

// Refuses keys of `object` outside `known` (a misspelt key would otherwise be ignored).
void check_keys(const json& object, const std::set<std::string>& known, const std::string& file,
                const std::string& where, const std::string& help) {
  for (const auto& [key, value] : object.items())
    if (!known.count(key)) fail(file, where + "." + key, "is not a key of \"" + where + "\", which is " + help);
}

double positive_number(const json& object, const std::string& key, const std::string& file, const std::string& where) {
  const json& value = object.at(key);
  if (!value.is_number() || !std::isfinite(value.get<double>()) || !(value.get<double>() > 0.0))
    fail(file, where + "." + key, "must be a positive number, not " + json_excerpt(value));
  return value.get<double>();
}

BoardSpec read_board(const json& root, const std::string& file) {
  if (!root.contains("board"))
    throw Error(file + ": \"board\" is missing: the chessboard that registers the camera, " + kBoardHelp);
  const json& board = root.at("board");
  if (!board.is_object()) fail(file, "board", std::string("must be an object ") + kBoardHelp);
  check_keys(board, {"inner_corners", "square"}, file, "board", kBoardHelp);
  for (const char* key : {"inner_corners", "square"})
    if (!board.contains(key)) fail(file, std::string("board.") + key, std::string("is missing: ") + kBoardHelp);
  const json& corners = board.at("inner_corners");
  const auto count = [](const json& value) {
    return value.is_number_integer() && value.get<long long>() >= 2 && value.get<long long>() <= 1000;
  };
  if (!corners.is_array() || corners.size() != 2 || !count(corners[0]) || !count(corners[1]))
    fail(file, "board.inner_corners",
         "must be [cols, rows], the inner corners (where four squares meet) along a row and along a column, "
         "each an integer in [2, 1000], not " +
             json_excerpt(corners));
  BoardSpec spec{corners[0].get<int>(), corners[1].get<int>(), positive_number(board, "square", file, "board")};
  if ((spec.cols + spec.rows) % 2 == 0)
    fail(file, "board.inner_corners",
         "is " + json_excerpt(corners) +
             ": such a board looks the same turned by 180 degrees, so views from opposite sides would disagree on "
             "the world frame; use a board with one count even and the other odd (9 x 6 inner corners, say)");
  return spec;
}

CameraIntrinsics read_camera(const json& camera, const std::string& file) {
  const char* const help =
      "known intrinsics {\"fl_x\", \"fl_y\", \"cx\", \"cy\", \"w\", \"h\", \"k1\", \"k2\", "
      "\"p1\", \"p2\", \"k3\", \"camera_model\"} as in transforms.json";
  if (!camera.is_object()) fail(file, "camera", std::string("must be an object of ") + help);
  check_keys(camera, {"fl_x", "fl_y", "cx", "cy", "w", "h", "k1", "k2", "p1", "p2", "k3", "camera_model"}, file,
             "camera", help);
  for (const char* key : {"fl_x", "cx", "cy"})
    if (!camera.contains(key)) fail(file, std::string("camera.") + key, std::string("is missing: ") + help);
  CameraIntrinsics intrinsics;
  intrinsics.fl_x = positive_number(camera, "fl_x", file, "camera");
  intrinsics.fl_y = camera.contains("fl_y") ? positive_number(camera, "fl_y", file, "camera") : intrinsics.fl_x;
  for (const auto& [key, target] :
       {std::pair{"cx", &intrinsics.cx}, std::pair{"cy", &intrinsics.cy}, std::pair{"k1", &intrinsics.k1},
        std::pair{"k2", &intrinsics.k2}, std::pair{"p1", &intrinsics.p1}, std::pair{"p2", &intrinsics.p2},
        std::pair{"k3", &intrinsics.k3}}) {
    if (!camera.contains(key)) continue;
    const json& value = camera.at(key);
    if (!value.is_number() || !std::isfinite(value.get<double>()))
      fail(file, std::string("camera.") + key, "must be a finite number, not " + json_excerpt(value));
    *target = value.get<double>();
  }
  for (const auto& [key, target] : {std::pair{"w", &intrinsics.width}, std::pair{"h", &intrinsics.height}}) {
    if (!camera.contains(key)) continue;
    const json& value = camera.at(key);
    if (!value.is_number_integer() || value.get<long long>() < 1 || value.get<long long>() > 65536)
      fail(file, std::string("camera.") + key, "must be the photos' size in pixels, not " + json_excerpt(value));
    *target = value.get<int>();
  }
  if (camera.contains("camera_model")) {
    const json& model = camera.at("camera_model");
    const std::string name = model.is_string() ? model.get<std::string>() : "";
    const bool distorted =
        intrinsics.k1 != 0 || intrinsics.k2 != 0 || intrinsics.p1 != 0 || intrinsics.p2 != 0 || intrinsics.k3 != 0;
    if (name != "OPENCV" && name != "PINHOLE" && name != "SIMPLE_PINHOLE")
      fail(file, "camera.camera_model",
           "must be \"OPENCV\", \"PINHOLE\" or \"SIMPLE_PINHOLE\" (the models registration supports), not " +
               json_excerpt(model));
    if (name != "OPENCV" && distorted)
      fail(file, "camera.camera_model",
           "is " + name +
               ", which has no lens distortion, but k1..k3, p1, p2 are given: "
               "use \"OPENCV\"");
  }
  return intrinsics;
}

const char* const kObjectHelp =
    "{\"type\": \"sphere\"} (locate it), {\"type\": \"sphere\", \"center\": [x, y, z], \"radius\": r} "
    "(board coordinates, metres) or {\"gltf\": FILE} (already in board coordinates)";

std::array<double, 3> read_point(const json& object, const std::string& key, const std::string& file,
                                 const std::string& where) {
  const json& c = object.at(key);
  if (!c.is_array() || c.size() != 3 ||
      !std::all_of(c.begin(), c.end(), [](const json& v) { return v.is_number() && std::isfinite(v.get<double>()); }))
    fail(file, where + "." + key, "must be [x, y, z] in metres (board coordinates), not " + json_excerpt(c));
  return {c[0].get<double>(), c[1].get<double>(), c[2].get<double>()};
}

ShootObject read_object(const json& object, const fs::path& folder, const std::string& file) {
  if (!object.is_object()) fail(file, "object", std::string("must be an object: ") + kObjectHelp);
  ShootObject result;
  if (object.contains("gltf")) {
    check_keys(object, {"gltf"}, file, "object", kObjectHelp);
    const json& gltf = object.at("gltf");
    if (!gltf.is_string() || gltf.get<std::string>().empty())
      fail(file, "object.gltf", "must be a file name, not " + json_excerpt(gltf));
    result.kind = ShootObject::Kind::gltf;
    result.gltf = folder / gltf.get<std::string>();
    return result;
  }
  check_keys(object, {"type", "center", "radius"}, file, "object", kObjectHelp);
  if (!object.contains("type") || object.at("type") != "sphere")
    fail(file, "object.type", std::string("must be \"sphere\" (or give \"gltf\"): ") + kObjectHelp);
  const bool center = object.contains("center"), radius = object.contains("radius");
  if (center != radius)
    fail(file, center ? "object.radius" : "object.center",
         "is missing: give both the centre and the radius, or neither to locate the sphere from its outline");
  if (!center) return result;
  result.kind = ShootObject::Kind::sphere;
  result.center = read_point(object, "center", file, "object");
  result.radius = positive_number(object, "radius", file, "object");
  return result;
}

ShootProbe read_probe(const json& probe, const std::string& file) {
  const std::string help =
      "{\"center\": [x, y, z], \"radius\": metres, \"reflectance\": x or [r, g, b]}, each optional (a centre only "
      "with the radius)";
  if (!probe.is_object()) fail(file, "probe", "must be an object " + help);
  check_keys(probe, {"center", "radius", "reflectance"}, file, "probe", help);
  ShootProbe result;
  if (probe.contains("radius")) result.radius = positive_number(probe, "radius", file, "probe");
  if (probe.contains("center")) {
    if (!result.radius) fail(file, "probe.radius", "is missing: a ball's centre is given with its radius");
    result.center = read_point(probe, "center", file, "probe");
  }
  if (probe.contains("reflectance")) {
    const json& value = probe.at("reflectance");
    const auto fraction = [](const json& v) {
      return v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() > 0.0 && v.get<double>() <= 1.0;
    };
    if (fraction(value)) {
      result.reflectance = {value.get<double>(), value.get<double>(), value.get<double>()};
    } else if (value.is_array() && value.size() == 3 && std::all_of(value.begin(), value.end(), fraction)) {
      result.reflectance = {value[0].get<double>(), value[1].get<double>(), value[2].get<double>()};
    } else {
      fail(file, "probe.reflectance",
           "must be the ball's reflectance in (0, 1], one number or [r, g, b], not " + json_excerpt(value) +
               "; leave it out to estimate it");
    }
  }
  return result;
}

// The image files directly in `folder` whose name passes `keep`, sorted by name.
template <typename Keep>
std::vector<fs::path> images_in(const fs::path& folder, Keep keep) {
  std::vector<fs::path> images;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder))
    if (entry.is_regular_file() && is_image_file(entry.path()) && keep(entry.path())) images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  return images;
}

// Whether `name` is PREFIX followed by one or more digits.
bool numbered(const std::string& name, const std::string& prefix) {
  return name.size() > prefix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
         std::all_of(name.begin() + prefix.size(), name.end(), [](unsigned char c) { return std::isdigit(c); });
}

}  // namespace

bool is_image_file(const fs::path& path) {
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr",
                                                    ".hdr", ".dng", ".cr2",  ".cr3", ".nef",  ".arw",
                                                    ".raf", ".orf", ".rw2",  ".pef", ".srw"};
  const std::string name = path.filename().string();
  return !name.empty() && name[0] != '.' && kExtensions.count(lowercase(path.extension().string()));
}

Shoot read_shoot(const fs::path& path) {
  std::error_code ec;
  const bool folder = fs::is_directory(path, ec);
  Shoot shoot;
  shoot.folder = folder ? path : (path.has_parent_path() ? path.parent_path() : fs::path("."));
  shoot.file = (folder ? path / "shoot.json" : path).string();
  if (!fs::exists(shoot.file, ec))
    throw Error(shoot.file + ": not found; a photo shoot is a folder with a shoot.json (docs: guide, photo shoots)");
  const json root = read_json_file(shoot.file, "photo shoot description");
  if (!root.is_object())
    throw Error(shoot.file + ": the top level must be an object {\"board\": ..., ...}, not " +
                std::string(root.type_name()));
  shoot.board = read_board(root, shoot.file);
  if (root.contains("camera")) shoot.camera = read_camera(root.at("camera"), shoot.file);
  if (root.contains("object")) shoot.object = read_object(root.at("object"), shoot.folder, shoot.file);
  if (root.contains("probe")) shoot.probe = read_probe(root.at("probe"), shoot.file);
  return shoot;
}

std::vector<fs::path> calibration_photos(const Shoot& shoot) {
  const fs::path folder = shoot.folder / "calibration";
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return {};
  return images_in(folder, [](const fs::path&) { return true; });
}

std::vector<ShootView> shoot_views(const Shoot& shoot) {
  std::vector<ShootView> views;
  for (const char* prefix : {"view_", "probe_"}) {
    std::vector<fs::path> folders;
    for (const fs::directory_entry& entry : fs::directory_iterator(shoot.folder))
      if (entry.is_directory() && numbered(entry.path().filename().string(), prefix)) folders.push_back(entry.path());
    std::sort(folders.begin(), folders.end());
    for (const fs::path& folder : folders) {
      const std::vector<fs::path> boards =
          images_in(folder, [](const fs::path& file) { return file.stem() == "board"; });
      if (boards.size() != 1)
        throw Error(folder.string() + ": " +
                    (boards.empty() ? std::string("has no board photo")
                                    : "has " + std::to_string(boards.size()) + " board photos") +
                    "; each view needs exactly one, board.* (board.jpg, board.exr, ...): the chessboard seen from "
                    "that tripod position, which registers the view");
      views.push_back({folder.filename().string(), boards.front()});
    }
  }
  if (views.empty())
    throw Error(shoot.folder.string() +
                ": no view_NNN folder; each tripod position is a folder view_000, view_001, ... with a board photo");
  return views;
}

}  // namespace glaze
