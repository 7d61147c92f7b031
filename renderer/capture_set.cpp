#include "renderer/capture_set.h"

#include "renderer/error.h"
#include "renderer/text_file.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>

namespace glaze {

nlohmann::json pose_to_json(const Eigen::Affine3f& camera_to_world) {
  nlohmann::json rows = nlohmann::json::array();
  const Eigen::Matrix4f m = camera_to_world.matrix();
  for (int r = 0; r < 4; ++r) rows.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
  return rows;
}

namespace {

nlohmann::json intrinsics(const PinholeCamera& c) {
  return {{"w", c.width}, {"h", c.height}, {"fl_x", c.fl_x}, {"fl_y", c.fl_y}, {"cx", c.cx}, {"cy", c.cy}};
}

}  // namespace

void write_transforms(const std::string& directory, const CaptureSet& captures) {
  if (captures.frames.empty()) throw Error(directory + ": a capture set needs at least one frame");
  nlohmann::json root = nlohmann::json::object();
  const nlohmann::json shared = intrinsics(captures.frames.front().camera);
  bool all_shared = true;
  for (const CaptureFrame& frame : captures.frames) all_shared = all_shared && intrinsics(frame.camera) == shared;
  if (all_shared) root.update(shared);
  if (captures.saturation) root["saturation"] = *captures.saturation;
  nlohmann::json frames = nlohmann::json::array();
  for (const CaptureFrame& frame : captures.frames) {
    nlohmann::json entry = {{"file_path", frame.file_path},
                            {"camera", frame.camera.name},
                            {"transform_matrix", pose_to_json(frame.camera.camera_to_world)}};
    if (!frame.mask_path.empty()) entry["mask_path"] = frame.mask_path;
    if (!all_shared) entry.update(intrinsics(frame.camera));
    frames.push_back(entry);
  }
  root["frames"] = frames;
  root["object"] = captures.object;
  if (!captures.environment.is_null()) root["environment"] = captures.environment;
  if (!captures.material.is_null()) root["material"] = captures.material;
  if (!captures.renderer.is_null()) root["renderer"] = captures.renderer;

  write_text_atomically((std::filesystem::path(directory) / "transforms.json").string(), root.dump(2) + "\n");
}

// ---------------------------------------------------------------------------------------
// Reading. Every message starts with where the problem is ("DIR/transforms.json: frame 2
// ("view_002.exr")"), then says what is wrong and what is expected instead.
// ---------------------------------------------------------------------------------------

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

[[noreturn]] void fail(const std::string& where, const std::string& problem) { throw Error(where + ": " + problem); }

std::string quoted(const std::string& key) { return "\"" + key + "\""; }

// What a number must be, and how messages say it. Values are stored as floats, so even
// "any finite number" excludes those a float cannot hold (1e300 parses as a double).
struct Range {
  double low, high;
  bool low_excluded;
  bool integer;
  const char* text;
};
constexpr double kFloatMax = std::numeric_limits<float>::max();
constexpr Range kFinite{-kFloatMax, kFloatMax, false, false, "a finite number"};
constexpr Range kPositive{0.0, kFloatMax, true, false, "a finite number > 0"};
constexpr Range kNonNegative{0.0, kFloatMax, false, false, "a finite number >= 0"};
constexpr Range kUnit{0.0, 1.0, false, false, "a number in [0, 1]"};
constexpr Range kPixels{1.0, 65536.0, false, true, "a whole number of pixels from 1 to 65536"};

// Every number in the file is read through here: a JSON number within `range`.
float number(const json& value, const std::string& where, const std::string& key, const Range& range) {
  const double x = value.is_number() ? value.get<double>() : std::nan("");
  const bool ok = x >= range.low && x <= range.high && !(range.low_excluded && x == range.low) &&
                  !(range.integer && x != std::floor(x));
  if (!ok) fail(where, quoted(key) + " must be " + range.text + ", not " + value.dump());
  return float(x);
}

// An array of `count` numbers, each in `range`.
std::vector<float> numbers(const json& value, size_t count, const std::string& where, const std::string& key,
                           const Range& range) {
  if (!value.is_array() || value.size() != count)
    fail(where, quoted(key) + " must be an array of " + std::to_string(count) + " numbers, not " + value.dump());
  std::vector<float> result;
  for (size_t i = 0; i < count; ++i) result.push_back(number(value[i], where, key + "[" + std::to_string(i) + "]", range));
  return result;
}

// object[key], which must be there; `expected` says what it should be.
const json& member(const json& object, const std::string& key, const std::string& where, const std::string& expected) {
  if (!object.contains(key)) fail(where, "no " + quoted(key) + " (" + expected + ")");
  return object.at(key);
}

// The transforms.json that `path` names: the file itself, or the one in a directory.
fs::path transforms_file(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec))
    throw Error(path + ": no such file or directory; give a capture directory or its transforms.json");
  const fs::path file = fs::is_directory(path, ec) ? fs::path(path) / "transforms.json" : fs::path(path);
  if (!fs::is_regular_file(file, ec))
    throw Error(file.string() + ": not found or not a file; a capture directory holds a transforms.json "
                                "(glaze render --captures writes one)");
  return file;
}

json parse(const fs::path& file) {
  std::ifstream stream(file);
  if (!stream) throw Error(file.string() + ": cannot be read; check its permissions");
  try {
    return json::parse(stream);
  } catch (const json::exception& e) {
    throw Error(file.string() + ": not valid JSON (" + e.what() + "); fix the file or write it again");
  }
}

// Lens distortion coefficients as nerfstudio and OpenCV name them.
constexpr std::array<const char*, 6> kDistortion = {"k1", "k2", "k3", "k4", "p1", "p2"};

// Reads one parsed transforms.json.
class TransformsReader {
 public:
  TransformsReader(const fs::path& file, const json& root)
      : file_(file.string()), directory_(file.has_parent_path() ? file.parent_path() : fs::path(".")), root_(root) {}

  CaptureSet read() const {
    if (!root_.is_object()) fail(file_, "the top level must be an object {\"frames\": [...], \"object\": {...}, ...}, not " +
                      std::string(root_.type_name()));
    const json& frames = member(root_, "frames", file_, "the views: [{\"file_path\": ..., \"transform_matrix\": ...}, ...]");
    if (!frames.is_array() || frames.empty())
      fail(file_, "\"frames\" must be a non-empty array of views {\"file_path\": ..., \"transform_matrix\": ...}, not " +
                      frames.dump());
    CaptureSet set;
    set.directory = directory_.string();
    for (size_t i = 0; i < frames.size(); ++i) set.frames.push_back(frame(frames[i], i));
    set.object = object();
    set.environment = environment();
    set.material = material();
    if (root_.contains("saturation")) set.saturation = number(root_.at("saturation"), file_, "saturation", kPositive);
    if (root_.contains("renderer") && root_.at("renderer").is_object()) set.renderer = root_.at("renderer");
    return set;
  }

 private:
  // A path named in the file: resolved against its directory (operator/ keeps absolute
  // paths as they are); it must name an existing file.
  std::string existing_file(const json& value, const std::string& where, const std::string& key) const {
    if (!value.is_string() || value.get<std::string>().empty())
      fail(where, quoted(key) + " must be a file name (a non-empty string), not " + value.dump());
    const fs::path resolved = directory_ / value.get<std::string>();
    std::error_code ec;
    if (!fs::is_regular_file(resolved, ec))
      fail(where, quoted(key) + " names " + resolved.string() +
                      ", which does not exist or is not a file; relative paths are relative to " + directory_.string());
    return resolved.string();
  }

  // A frame's own value for `key`, else the top-level one shared by all frames (null if
  // neither), with where it came from.
  std::pair<const json*, std::string> setting(const json& frame, const std::string& frame_where,
                                              const std::string& key) const {
    if (frame.contains(key)) return {&frame.at(key), frame_where};
    if (root_.contains(key)) return {&root_.at(key), file_};
    return {nullptr, frame_where};
  }

  CaptureFrame frame(const json& entry, size_t index) const {
    std::string where = file_ + ": frame " + std::to_string(index);
    if (!entry.is_object()) fail(where, "must be an object {\"file_path\": ..., \"transform_matrix\": ...}, not " + entry.dump());
    const json& file_path = member(entry, "file_path", where, "the image's file name");
    where += " (" + file_path.dump() + ")";
    CaptureFrame frame;
    frame.file_path = existing_file(file_path, where, "file_path");
    if (entry.contains("mask_path")) frame.mask_path = existing_file(entry.at("mask_path"), where, "mask_path");
    frame.camera = camera(entry, index, where);
    return frame;
  }

  PinholeCamera camera(const json& frame, size_t index, const std::string& where) const {
    check_lens(frame, where);
    PinholeCamera camera;
    if (frame.contains("camera")) {
      if (!frame.at("camera").is_string()) fail(where, "\"camera\" must be the camera's name (a string), not " + frame.at("camera").dump());
      camera.name = frame.at("camera").get<std::string>();
    } else {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%03zu", index);
      camera.name = name;
    }
    const auto intrinsic = [&](const std::string& key, const Range& range) {
      const auto [value, value_where] = setting(frame, where, key);
      if (!value)
        fail(where, "no " + quoted(key) + "; give the intrinsics w, h, fl_x, fl_y, cx, cy (in pixels) at the top level, "
                                          "shared by all frames, or in each frame");
      return number(*value, value_where, key, range);
    };
    camera.width = int(intrinsic("w", kPixels));
    camera.height = int(intrinsic("h", kPixels));
    camera.fl_x = intrinsic("fl_x", kPositive);
    camera.fl_y = intrinsic("fl_y", kPositive);
    camera.cx = intrinsic("cx", kFinite);
    camera.cy = intrinsic("cy", kFinite);
    camera.camera_to_world = pose(frame, where);
    return camera;
  }

  // glaze renders through an ideal pinhole, so distorted images cannot be compared with
  // its renders; undistorting them is the photographer's job (e.g. COLMAP's undistorter).
  void check_lens(const json& frame, const std::string& where) const {
    const std::string remedy = "; undistort the images first (e.g. with COLMAP's image_undistorter) and describe "
                               "them as \"camera_model\": \"PINHOLE\" without distortion coefficients";
    if (const auto [model, model_where] = setting(frame, where, "camera_model");
        model && *model != "PINHOLE" && *model != "OPENCV")
      fail(model_where, "\"camera_model\" " + model->dump() + " is not supported: glaze's camera is a pinhole" + remedy);
    for (const char* key : kDistortion) {
      const auto [value, value_where] = setting(frame, where, key);
      if (value && number(*value, value_where, key, kFinite) != 0.0f)
        fail(value_where, "lens distortion " + quoted(key) + " = " + value->dump() +
                              " is not supported: glaze's camera is a pinhole" + remedy);
    }
  }

  // "transform_matrix": 4x4 row-major camera-to-world, which must be rigid (the renderer
  // and the fit assume unit-length rays and an undistorted frame).
  Eigen::Affine3f pose(const json& frame, const std::string& where) const {
    const json& rows = member(frame, "transform_matrix", where, "the 4x4 row-major camera-to-world pose");
    if (!rows.is_array() || rows.size() != 4)
      fail(where, "\"transform_matrix\" must be 4 rows of 4 numbers (row-major camera-to-world), not " + rows.dump());
    Eigen::Matrix4f m;
    for (int r = 0; r < 4; ++r) {
      const std::vector<float> row = numbers(rows[r], 4, where, "transform_matrix[" + std::to_string(r) + "]", kFinite);
      for (int c = 0; c < 4; ++c) m(r, c) = row[c];
    }
    const std::string rigid = "; the pose must be a rigid camera-to-world transform (rotation and translation, "
                              "no scale, shear or mirroring)";
    if ((m.row(3) - Eigen::RowVector4f(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-4f)
      fail(where, "the last row of \"transform_matrix\" is " + rows[3].dump() + ", not [0, 0, 0, 1]" + rigid);
    const Mat3 rotation = m.topLeftCorner<3, 3>();
    const float deviation = (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
    if (deviation > 1e-3f || rotation.determinant() <= 0.0f)
      fail(where, "the upper-left 3x3 of \"transform_matrix\" is not a rotation (R^T R differs from I by up to " +
                      std::to_string(deviation) + ", det R = " + std::to_string(rotation.determinant()) + ")" + rigid);
    Eigen::Affine3f pose = Eigen::Affine3f::Identity();
    pose.linear() = rotation;
    pose.translation() = m.topRightCorner<3, 1>();
    return pose;
  }

  json object() const {
    const std::string shapes = "{\"type\": \"sphere\", \"center\": [x, y, z], \"radius\": r} or {\"gltf\": FILE}";
    json object = member(root_, "object", file_, "what was photographed: " + shapes);
    const std::string where = file_ + ": \"object\"";
    const bool gltf = object.is_object() && object.contains("gltf");
    const bool typed = object.is_object() && object.contains("type");
    if (gltf == typed || (typed && object["type"] != "sphere")) fail(where, "must be " + shapes + ", not " + object.dump());
    if (gltf) {
      object["gltf"] = existing_file(object["gltf"], where, "gltf");
    } else {
      numbers(member(object, "center", where, "the sphere's centre [x, y, z]"), 3, where, "center", kFinite);
      number(member(object, "radius", where, "the sphere's radius"), where, "radius", kPositive);
    }
    return object;
  }

  json environment() const {
    if (!root_.contains("environment")) return nullptr;
    json environment = root_.at("environment");
    const std::string where = file_ + ": \"environment\"";
    if (!environment.is_object() || !(environment.contains("file") || environment.contains("procedural")))
      fail(where, "must be {\"file\": FILE, ...} or {\"procedural\": NAME, ...}, not " + environment.dump());
    if (environment.contains("file")) environment["file"] = existing_file(environment["file"], where, "file");
    if (environment.contains("procedural") && !environment["procedural"].is_string())
      fail(where, "\"procedural\" must be the name of a procedural environment (a string), not " +
                      environment["procedural"].dump());
    if (environment.contains("scale")) number(environment["scale"], where, "scale", kNonNegative);
    if (environment.contains("rotation")) number(environment["rotation"], where, "rotation", kFinite);
    if (environment.contains("to_world")) {
      const json& rows = environment["to_world"];
      if (!rows.is_array() || rows.size() != 3)
        fail(where, "\"to_world\" must be 3 rows of 3 numbers (a rotation, row-major), not " + rows.dump());
      for (int r = 0; r < 3; ++r) numbers(rows[r], 3, where, "to_world[" + std::to_string(r) + "]", kFinite);
    }
    return environment;
  }

  json material() const {
    if (!root_.contains("material")) return nullptr;
    const json& material = root_.at("material");
    const std::string where = file_ + ": \"material\"";
    if (!material.is_object()) fail(where, "must be {\"R0\": x, \"Rd\": [r, g, b]}, not " + material.dump());
    number(member(material, "R0", where, "the specular reflectance at normal incidence"), where, "R0", kUnit);
    numbers(member(material, "Rd", where, "the diffuse albedo [r, g, b]"), 3, where, "Rd", kUnit);
    return material;
  }

  std::string file_;
  fs::path directory_;
  const json& root_;
};

}  // namespace

CaptureSet read_transforms(const std::string& path) {
  const fs::path file = transforms_file(path);
  const json root = parse(file);
  return TransformsReader(file, root).read();
}

}  // namespace glaze
